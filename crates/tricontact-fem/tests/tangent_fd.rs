//! Consistent tangents against central finite differences of the internal
//! force, for every element kind × material × kinematics, on distorted
//! elements with a sizeable displacement field; and the assembled global
//! tangent (with prescribed DOFs eliminated) against differences of the
//! assembled residual.
#![allow(clippy::needless_range_loop)]

mod common;

use tricontact_fem::assembly::{DofMap, NoExtra, Pattern, assemble};
use tricontact_fem::element::internal_force;
use tricontact_fem::material::{Law, Material};
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::shape::{node_coords, rule};
use tricontact_fem::structured::{box_mesh, distort_interior};

fn pseudo_random(seed: u64, n: usize) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

fn check_element(kind: ElementKind, law: Law, nlgeom: bool) -> f64 {
    let mat = Material::from_e_nu(law, 200.0, 0.3);
    let q = rule(kind);
    let n = kind.num_nodes();
    let r = pseudo_random(7 + n as u64, 6 * n);
    // Distorted element: reference nodes scaled, sheared and jittered.
    let x0: Vec<[f64; 3]> = node_coords(kind)
        .iter()
        .enumerate()
        .map(|(a, p)| {
            [
                2.0 * p[0] + 0.3 * p[1] + 0.08 * r[3 * a],
                1.5 * p[1] + 0.2 * p[2] + 0.08 * r[3 * a + 1],
                1.2 * p[2] + 0.1 * p[0] + 0.08 * r[3 * a + 2],
            ]
        })
        .collect();
    let u: Vec<[f64; 3]> = (0..n)
        .map(|a| {
            [
                0.05 * r[3 * n + 3 * a],
                0.05 * r[3 * n + 3 * a + 1],
                0.05 * r[3 * n + 3 * a + 2],
            ]
        })
        .collect();
    let nd = 3 * n;
    let mut f = vec![0.0; nd];
    let mut k = vec![0.0; nd * nd];
    internal_force(&q, &x0, &u, &mat, nlgeom, &mut f, Some(&mut k)).expect("admissible");
    let h = 1e-6;
    let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut err = 0.0f64;
    for col in 0..nd {
        let mut up = u.clone();
        let mut um = u.clone();
        up[col / 3][col % 3] += h;
        um[col / 3][col % 3] -= h;
        let mut fp = vec![0.0; nd];
        let mut fm = vec![0.0; nd];
        internal_force(&q, &x0, &up, &mat, nlgeom, &mut fp, None).expect("admissible");
        internal_force(&q, &x0, &um, &mat, nlgeom, &mut fm, None).expect("admissible");
        for row in 0..nd {
            let fd = (fp[row] - fm[row]) / (2.0 * h);
            err = err.max((fd - k[row * nd + col]).abs());
        }
    }
    err / kmax
}

#[test]
fn element_tangents_match_central_differences() {
    for kind in [ElementKind::Tet4, ElementKind::Tet10, ElementKind::Hex8] {
        for law in [Law::LinearElastic, Law::NeoHooke] {
            for nlgeom in [false, true] {
                let rel = check_element(kind, law, nlgeom);
                assert!(
                    rel <= 1e-6,
                    "{kind:?} {law:?} nlgeom={nlgeom}: relative error {rel:e}"
                );
            }
        }
    }
}

#[test]
fn assembled_tangent_matches_central_differences() {
    let size = [2.0, 1.0, 1.0];
    let n = [2, 1, 1];
    let mut mesh = box_mesh(size, n, ElementKind::Tet10);
    distort_interior(&mut mesh, size, n, 0.15);
    let an = common::analysis(
        mesh,
        r#"
[[material]]
name = "m"
type = "neo_hooke"
E = 100.0
nu = 0.35
[[body]]
group = "solid"
material = "m"
[[boundary]]
group = "xmin"
fix = ["x", "y", "z"]
[[step]]
nlgeom = true
"#,
    );
    let (mask, _) = tricontact_fem::driver::step_constraints(&an, 0);
    let dm = DofMap::new(&an.active_nodes, &mask, 0);
    let pat = Pattern::new(&an, &dm);
    let r = pseudo_random(3, an.num_nodal_dofs());
    let u: Vec<f64> = r.iter().map(|v| 0.04 * v).collect();
    let asm = assemble(&an, &dm, &pat, &u, true, true, None, &mut NoExtra).expect("admissible");
    let k = asm.matrix(&pat);
    let kmax = asm.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let h = 1e-6;
    let mut err = 0.0f64;
    let cols = k.as_ref().col_ptr().len() - 1;
    assert_eq!(cols, dm.n_eq);
    for dof in 0..dm.eq.len() {
        let c = dm.eq[dof];
        if c == tricontact_fem::assembly::NO_EQ {
            continue;
        }
        let mut up = u.clone();
        let mut um = u.clone();
        up[dof] += h;
        um[dof] -= h;
        let rp = assemble(&an, &dm, &pat, &up, true, false, None, &mut NoExtra)
            .expect("ok")
            .residual;
        let rm = assemble(&an, &dm, &pat, &um, true, false, None, &mut NoExtra)
            .expect("ok")
            .residual;
        let mut dense_col = vec![0.0; dm.n_eq];
        let (cp, ri, vals) = (k.as_ref().col_ptr(), k.as_ref().row_idx(), k.as_ref().val());
        for p in cp[c]..cp[c + 1] {
            dense_col[ri[p]] = vals[p];
        }
        for (rdof, &re) in dm.eq.iter().enumerate() {
            if re == tricontact_fem::assembly::NO_EQ {
                continue;
            }
            let fd = (rp[rdof] - rm[rdof]) / (2.0 * h);
            err = err.max((fd - dense_col[re]).abs());
        }
    }
    assert!(err / kmax <= 1e-6, "relative error {:e}", err / kmax);
}
