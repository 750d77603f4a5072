//! Patch tests: on distorted meshes, a displacement field `u = A X + b`
//! prescribed on the boundary must be reproduced at the interior nodes and
//! give the constant stress `σ(A)` in every element, to round-off — for
//! every element kind (tet10 distorted with straight edges), small strain and (with the homogeneous deformation
//! `F = I + A`) finite-strain neo-Hooke.
#![allow(clippy::needless_range_loop)]

mod common;

use nalgebra::Matrix3;
use tricontact_fem::material::{Law, Material, cauchy};
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::results::stress_fields;
use tricontact_fem::structured::{box_mesh, distort_interior};

const A: [[f64; 3]; 3] = [
    [0.012, 0.004, -0.003],
    [0.002, -0.006, 0.005],
    [-0.004, 0.003, 0.009],
];
const B: [f64; 3] = [0.01, -0.02, 0.005];

fn run_patch(kind: ElementKind, law: &str, nlgeom: bool, scale: f64) {
    let size = [1.0, 1.2, 0.9];
    let n = [3, 3, 3];
    let mut mesh = box_mesh(size, n, kind);
    // Strong distortion, limited so that all reference Jacobians stay positive.
    let amount = match kind {
        ElementKind::Hex8 => 0.25,
        _ => 0.1,
    };
    distort_interior(&mut mesh, size, n, amount);
    let boundary = common::box_boundary_nodes(&mesh, size);
    let e = 1000.0;
    let nu = 0.3;
    let mut an = common::analysis(
        mesh,
        &format!(
            "[[material]]\nname = \"m\"\ntype = \"{law}\"\nE = {e}\nnu = {nu}\n[[body]]\ngroup = \"solid\"\nmaterial = \"m\"\n[[step]]\nnlgeom = {nlgeom}\nincrements = 2\nresidual_tolerance = 1e-12\ndisplacement_tolerance = 1e-12\n"
        ),
    );
    let a = A.map(|r| r.map(|v| v * scale));
    let field = move |x: [f64; 3]| -> [f64; 3] {
        let mut u = B;
        for i in 0..3 {
            for j in 0..3 {
                u[i] += a[i][j] * x[j];
            }
        }
        u
    };
    common::prescribe_field(&mut an, &boundary, field);
    let (_, rec) = common::solve(&an);
    let u = &rec.last().expect("converged").u;
    let mut err = 0.0f64;
    let mut umax = 0.0f64;
    for (p, x) in an.mesh.nodes.iter().enumerate() {
        let exact = field(*x);
        for i in 0..3 {
            err = err.max((u[3 * p + i] - exact[i]).abs());
            umax = umax.max(exact[i].abs());
        }
    }
    assert!(
        err <= 1e-10 * umax,
        "{kind:?} {law} nlgeom={nlgeom}: displacement error {err:e}"
    );
    // Constant stress equal to the material response to H = A.
    let law_e = if law == "neo_hooke" {
        Law::NeoHooke
    } else {
        Law::LinearElastic
    };
    let mat = Material::from_e_nu(law_e, e, nu);
    let h = Matrix3::from_fn(|i, j| a[i][j]);
    let (p, _) = mat.response(&h, nlgeom).expect("admissible");
    let sigma = cauchy(&p, &h, nlgeom);
    let expect = [
        sigma[(0, 0)],
        sigma[(1, 1)],
        sigma[(2, 2)],
        sigma[(0, 1)],
        sigma[(1, 2)],
        sigma[(0, 2)],
    ];
    let fields = stress_fields(&an, u, nlgeom);
    let smax = sigma.abs().max();
    for cell in fields.cell_stress.chunks(6) {
        for c in 0..6 {
            assert!(
                (cell[c] - expect[c]).abs() <= 1e-9 * smax,
                "{kind:?} {law} nlgeom={nlgeom}: stress {c} {} vs {}",
                cell[c],
                expect[c]
            );
        }
    }
}

#[test]
fn small_strain_patch_all_elements() {
    for kind in [ElementKind::Tet4, ElementKind::Tet10, ElementKind::Hex8] {
        run_patch(kind, "linear_elastic", false, 1.0);
    }
}

#[test]
fn finite_strain_patch_all_elements() {
    // Large homogeneous deformation (|A| ~ 0.5).
    for kind in [ElementKind::Tet4, ElementKind::Tet10, ElementKind::Hex8] {
        run_patch(kind, "neo_hooke", true, 40.0);
        run_patch(kind, "linear_elastic", true, 20.0);
    }
}

/// The same patch test on the unstructured Gmsh tet10 mesh of a 2 × 1 × 1
/// block (`tests/data/block_tet10.msh`), at finite strain.
#[test]
fn gmsh_tet10_mesh_patch() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/block_tet10.msh");
    let mesh = tricontact_fem::gmsh::read_msh(&path).expect("mesh");
    let size = [2.0, 1.0, 1.0];
    let boundary = common::box_boundary_nodes(&mesh, size);
    let mut an = common::analysis(
        mesh,
        "[[material]]\nname = \"m\"\ntype = \"neo_hooke\"\nE = 10.0\nnu = 0.4\n[[body]]\ngroup = \"block\"\nmaterial = \"m\"\n[[step]]\nnlgeom = true\nincrements = 2\nresidual_tolerance = 1e-12\ndisplacement_tolerance = 1e-12\n",
    );
    let a = A.map(|r| r.map(|v| v * 30.0));
    let field = move |x: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|i| B[i] + (0..3).map(|j| a[i][j] * x[j]).sum::<f64>())
    };
    common::prescribe_field(&mut an, &boundary, field);
    let (_, rec) = common::solve(&an);
    let u = &rec.last().expect("converged").u;
    let interior = an.mesh.nodes.len() - boundary.len();
    assert!(interior > 10, "the mesh has interior nodes");
    for (p, x) in an.mesh.nodes.iter().enumerate() {
        let exact = field(*x);
        for i in 0..3 {
            assert!((u[3 * p + i] - exact[i]).abs() <= 1e-10, "node {p}");
        }
    }
}
