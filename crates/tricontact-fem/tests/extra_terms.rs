//! The `ExtraTerms` hook with an extra unknown: a Lagrange multiplier `λ`
//! enforcing `u_y(a) = ḡ` at one node (`r_u += λ e_ay`, `r_λ = u_y(a) − ḡ`,
//! a symmetric indefinite saddle-point system: factored by `LDLᵀ` when the
//! terms declare themselves symmetric, by LU when they do not). The result must
//! equal the same model with `u_y(a)` prescribed, and `λ` must equal the
//! reaction force there.
#![allow(clippy::needless_range_loop)]

mod common;

use tricontact_fem::analysis::Boundary;
use tricontact_fem::assembly::ExtraTerms;
use tricontact_fem::driver::run;
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::structured::box_mesh;

struct TipConstraint {
    dof: usize,
    lambda_dof: usize,
    value: f64,
    symmetric: bool,
    /// The node `λ` is declared to belong to (ordered after its block), or none (last).
    owner: Option<usize>,
}

impl ExtraTerms for TipConstraint {
    fn num_extra(&self) -> usize {
        1
    }
    fn symmetric(&self) -> bool {
        self.symmetric
    }
    fn extra_nodes(&self) -> Vec<Option<usize>> {
        vec![self.owner]
    }
    fn add_terms(
        &mut self,
        u: &[f64],
        residual: &mut [f64],
        triplets: &mut Vec<(usize, usize, f64)>,
    ) -> Result<(), String> {
        residual[self.dof] += u[self.lambda_dof];
        residual[self.lambda_dof] += u[self.dof] - self.value;
        triplets.push((self.dof, self.lambda_dof, 1.0));
        triplets.push((self.lambda_dof, self.dof, 1.0));
        Ok(())
    }
}

const MODEL: &str = r#"
[[material]]
name = "m"
type = "neo_hooke"
E = 1000.0
nu = 0.3
[[body]]
group = "solid"
material = "m"
[[boundary]]
group = "xmin"
fix = ["x", "y", "z"]
[[step]]
nlgeom = true
increments = 2
residual_tolerance = 1e-11
displacement_tolerance = 1e-11
"#;

#[test]
fn multiplier_constraint_matches_prescribed_displacement() {
    check(true, "ldlt", false);
    check(true, "ldlt", true);
    check(false, "lu", false);
}

/// `owned`: `λ` belongs to the constrained node, so it is ordered among the displacements.
fn check(symmetric: bool, method: &str, owned: bool) {
    // 369 nodes: several nested-dissection blocks, so an owned `λ` is not simply last (the
    // tip lies in the last leaf, before the separators).
    let mesh = box_mesh([5.0, 1.0, 1.0], [40, 2, 2], ElementKind::Hex8);
    let tip = mesh
        .nodes
        .iter()
        .position(|p| (p[0] - 5.0).abs() < 1e-12 && p[1] == 0.0 && p[2] == 0.0)
        .expect("tip node");
    let value = -0.5;
    let an = common::analysis(mesh.clone(), MODEL);
    let n = an.num_nodal_dofs();
    let mut extra = TipConstraint {
        dof: 3 * tip + 1,
        lambda_dof: n,
        value,
        symmetric,
        owner: owned.then_some(tip),
    };
    let mut u_mult = Vec::new();
    let mut methods = Vec::new();
    run(&an, &mut extra, &mut |info| {
        u_mult = info.u.to_vec();
        methods.push(info.method.to_string());
        Ok(())
    })
    .expect("converges");
    assert_eq!(u_mult.len(), n + 1);
    assert!(methods.iter().all(|m| m == method), "{methods:?}");
    assert!((u_mult[3 * tip + 1] - value).abs() < 1e-10);

    let mut an2 = common::analysis(mesh, MODEL);
    an2.boundaries.push(Boundary {
        name: "tip".into(),
        nodes: vec![tip],
        values: [None, Some(value), None],
        active: vec![true],
    });
    let (_, rec) = common::solve(&an2);
    let last = rec.last().expect("converged");
    let scale = last.u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for d in 0..n {
        assert!((u_mult[d] - last.u[d]).abs() <= 1e-8 * scale, "dof {d}");
    }
    // λ is the force the constraint applies: r = f_int + λ = 0 ⇒ λ = −f_int = −(reaction).
    let reaction = last.reactions[1][1];
    assert!(
        (u_mult[n] + reaction).abs() <= 1e-7 * reaction.abs(),
        "λ {} vs reaction {reaction}",
        u_mult[n]
    );
}
