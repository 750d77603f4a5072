//! The assembled global tangent (solids + contact) against central finite differences of the
//! assembled residual, for the three methods, on two overlapping blocks shifted so that slave nodes
//! sit inside facets (away from edges, where `∇²P` jumps); and for the three methods with nodes in
//! a concave valley, on two flanks (with multipliers, two unknowns for such a node).
#![allow(clippy::needless_range_loop)]

mod common;

use tricontact_fem::assembly::{DofMap, ExtraTerms, NO_EQ, Pattern, assemble};
use tricontact_fem::contact::ContactTerms;
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::structured::box_mesh;

fn model(method: &str) -> String {
    format!(
        r#"
[[material]]
name = "m"
type = "neo_hooke"
E = 100.0
nu = 0.3
[[body]]
group = "lower_solid"
material = "m"
[[body]]
group = "upper_solid"
material = "m"
[[boundary]]
group = "lower_zmin"
fix = ["x", "y", "z"]
[[contact]]
slave = "upper_zmin"
master = "lower_zmax"
method = "{method}"
[[step]]
nlgeom = true
"#
    )
}

fn check(method: &str) -> f64 {
    let l = box_mesh([1.0, 1.0, 0.5], [2, 2, 1], ElementKind::Hex8);
    let u = box_mesh([0.6, 0.6, 0.5], [2, 2, 1], ElementKind::Hex8);
    let mesh = tricontact_fem::structured::stack(&l, &u, [0.13, 0.21, 0.5]);
    tangent_error(mesh, method, 0.75, false)
}

/// The largest difference between the assembled tangent and central differences of the
/// residual, relative to the tangent's largest entry, for `mesh` (two blocks, `lower_*` and
/// `upper_*`) with the upper block's nodes above `z_upper` pressed 0.01 down and its bottom
/// nodes (those of the lowest `z`) another 0.01; `two_flanks`: some node must be on two flanks.
fn tangent_error(
    mesh: tricontact_fem::mesh::Mesh,
    method: &str,
    z_upper: f64,
    two_flanks: bool,
) -> f64 {
    let lower_nodes = mesh.group("lower_solid").map_or(0, |g| {
        g.elements
            .iter()
            .flat_map(|&e| mesh.elements[e].nodes.iter().copied())
            .max()
            .map_or(0, |a| a + 1)
    });
    let bottom = mesh.nodes[lower_nodes..]
        .iter()
        .fold(f64::INFINITY, |m, p| m.min(p[2]));
    let an = common::analysis(mesh, &model(method));
    let mut terms = ContactTerms::new(&an);
    let n_extra = terms.num_extra();
    let (mask, _) = tricontact_fem::driver::step_constraints(&an, 0);
    let dm = DofMap::new(&an.active_nodes, &mask, n_extra);
    let pat = Pattern::new(&an, &dm);
    let n = an.num_nodal_dofs();
    let mut u = vec![0.0; n + n_extra];
    let mut s: u64 = 12345;
    let mut rnd = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    for d in 0..n {
        u[d] = 2e-3 * rnd();
        if d % 3 == 2 && an.mesh.nodes[d / 3][2] > z_upper {
            u[d] -= 0.01; // press the upper block in
        }
    }
    for d in n..n + n_extra {
        u[d] = -0.3 + 0.1 * rnd();
    }
    terms.begin_increment(&u).expect("begin");
    // Penetrating slave nodes: upper-block nodes at z = 0.5 moved down.
    for d in 0..n {
        if d % 3 == 2 && (an.mesh.nodes[d / 3][2] - bottom).abs() < 1e-12 && d / 3 >= lower_nodes {
            u[d] -= 0.01;
        }
    }
    let asm = assemble(&an, &dm, &pat, &u, true, true, None, &mut terms).expect("admissible");
    if method == "augmented" {
        // A non-zero multiplier estimate: one Uzawa update.
        let _ = terms.after_converged(&u).expect("update");
    }
    let asm = if method == "augmented" {
        assemble(&an, &dm, &pat, &u, true, true, None, &mut terms).expect("admissible")
    } else {
        asm
    };
    let closed = terms.iteration_note().unwrap_or_default();
    assert!(!closed.contains(" 0 closed"), "{closed}");
    assert_eq!(closed.contains("on two flanks"), two_flanks, "{closed}");
    let k = asm.matrix(&pat);
    let kmax = k.as_ref().val().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let h = 1e-7;
    let mut err = 0.0f64;
    for dof in 0..dm.eq.len() {
        let c = dm.eq[dof];
        if c == NO_EQ {
            continue;
        }
        let mut up = u.clone();
        let mut um = u.clone();
        up[dof] += h;
        um[dof] -= h;
        let rp = assemble(&an, &dm, &pat, &up, true, false, None, &mut terms)
            .expect("ok")
            .residual;
        let rm = assemble(&an, &dm, &pat, &um, true, false, None, &mut terms)
            .expect("ok")
            .residual;
        let mut col = vec![0.0; dm.n_eq];
        let (cp, ri, vals) = (k.as_ref().col_ptr(), k.as_ref().row_idx(), k.as_ref().val());
        for p in cp[c]..cp[c + 1] {
            col[ri[p]] += vals[p];
        }
        for (rdof, &re) in dm.eq.iter().enumerate() {
            if re == NO_EQ {
                continue;
            }
            let fd = (rp[rdof] - rm[rdof]) / (2.0 * h);
            err = err.max((fd - col[re]).abs());
        }
    }
    eprintln!(
        "{method}: {closed}; relative tangent error {:.3e}",
        err / kmax
    );
    err / kmax
}

#[test]
fn global_tangent_matches_finite_differences_penalty() {
    assert!(check("penalty") < 1e-6);
}

#[test]
fn global_tangent_matches_finite_differences_augmented() {
    assert!(check("augmented") < 1e-6);
}

#[test]
fn global_tangent_matches_finite_differences_multiplier() {
    assert!(check("multiplier") < 1e-6);
}

/// A block one brick wide across a V-groove (`common::v_groove`'s floor, the base one brick per
/// flank along `x`), its bottom 0.02 below the valley line, then pressed 0.02 more: its middle
/// row of bottom nodes, 0.03 past the valley line, is behind both flanks, its foot on the far
/// flank's plane within the reach of the second constraint; the tangent includes both
/// constraints' terms.
fn valley(method: &str) -> f64 {
    let mut lower = box_mesh([2.0, 1.0, 1.0], [4, 2, 1], ElementKind::Hex8);
    for p in &mut lower.nodes {
        p[2] *= common::groove_top(p[0]);
    }
    let upper = box_mesh([0.4, 0.6, 0.3], [2, 2, 1], ElementKind::Hex8);
    let mesh = tricontact_fem::structured::stack(&lower, &upper, [0.83, 0.13, 0.73]);
    tangent_error(mesh, method, 0.9, true)
}

#[test]
fn global_tangent_matches_finite_differences_on_two_flanks_penalty() {
    assert!(valley("penalty") < 1e-6);
}

#[test]
fn global_tangent_matches_finite_differences_on_two_flanks_augmented() {
    assert!(valley("augmented") < 1e-6);
}

#[test]
fn global_tangent_matches_finite_differences_on_two_flanks_multiplier() {
    assert!(valley("multiplier") < 1e-6);
}
