//! Neo-Hookean homogeneous states at large stretch against closed forms.
//!
//! `W = μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)²`.
//! Uniaxial stress, stretch λ₁ = 2: the lateral stretch `a` solves
//! `μ (a² − 1) + λ ln(λ₁ a²) = 0` and `P₁₁ = μ (λ₁ − 1/λ₁) + λ ln J / λ₁`,
//! `σ₁₁ = P₁₁ λ₁ / J`, `J = λ₁ a²`.
//! Simple shear `γ = 1.5` (largest principal stretch 2): `J = 1`,
//! `σ = μ (b − I)`: `σ₁₂ = μ γ`, `σ₁₁ = μ γ²`, `σ₂₂ = σ₃₃ = 0`.
#![allow(clippy::needless_range_loop)]

mod common;

use tricontact_fem::material::{Law, Material};
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::results::stress_fields;
use tricontact_fem::structured::box_mesh;

const E: f64 = 10.0;
const NU: f64 = 0.3;

fn material_text() -> String {
    format!(
        "[[material]]\nname = \"rubber\"\ntype = \"neo_hooke\"\nE = {E}\nnu = {NU}\n[[body]]\ngroup = \"solid\"\nmaterial = \"rubber\"\n"
    )
}

#[test]
fn uniaxial_stretch_two() {
    let stretch = 2.0;
    let mat = Material::from_e_nu(Law::NeoHooke, E, NU);
    let (lam, mu) = (mat.lambda, mat.mu);
    // Lateral stretch by Newton on g(a) = μ(a² − 1) + λ ln(λ₁ a²).
    let mut a: f64 = 1.0;
    for _ in 0..50 {
        let g = mu * (a * a - 1.0) + lam * (stretch * a * a).ln();
        let dg = 2.0 * mu * a + 2.0 * lam / a;
        a -= g / dg;
    }
    let j = stretch * a * a;
    let p11 = mu * (stretch - 1.0 / stretch) + lam * j.ln() / stretch;
    let s11 = p11 * stretch / j;

    for kind in [ElementKind::Hex8, ElementKind::Tet4, ElementKind::Tet10] {
        let mesh = box_mesh([1.0, 1.0, 1.0], [2, 2, 2], kind);
        let an = common::analysis(
            mesh,
            &format!(
                "{}\n[[boundary]]\ngroup = \"xmin\"\nfix = [\"x\"]\n[[boundary]]\ngroup = \"ymin\"\nfix = [\"y\"]\n[[boundary]]\ngroup = \"zmin\"\nfix = [\"z\"]\n[[boundary]]\ngroup = \"xmax\"\ndisplacement = {{ x = {} }}\n[[step]]\nnlgeom = true\nincrements = 4\nresidual_tolerance = 1e-12\ndisplacement_tolerance = 1e-12\n",
                material_text(),
                stretch - 1.0
            ),
        );
        let (_, rec) = common::solve(&an);
        let last = rec.last().expect("converged");
        // Corner (1, 1, 1) moves laterally by a − 1.
        let corner = an
            .mesh
            .nodes
            .iter()
            .position(|p| p.iter().all(|&c| (c - 1.0).abs() < 1e-12))
            .expect("corner");
        for i in [1, 2] {
            let got = last.u[3 * corner + i];
            assert!(
                (got - (a - 1.0)).abs() <= 1e-9,
                "{kind:?}: lateral {got} vs {}",
                a - 1.0
            );
        }
        // Reaction on the loaded face equals P11 × reference area 1.
        let rx = last.reactions[3][0];
        assert!(
            (rx - p11).abs() <= 1e-9 * p11.abs(),
            "{kind:?}: force {rx} vs {p11}"
        );
        let f = stress_fields(&an, &last.u, true);
        for cell in f.cell_stress.chunks(6) {
            assert!(
                (cell[0] - s11).abs() <= 1e-9 * s11,
                "{kind:?}: σ11 {} vs {s11}",
                cell[0]
            );
            for c in 1..6 {
                assert!(
                    cell[c].abs() <= 1e-9 * s11,
                    "{kind:?}: σ[{c}] = {}",
                    cell[c]
                );
            }
        }
    }
}

#[test]
fn simple_shear_gamma_one_and_a_half() {
    let gamma = 1.5;
    let mu = Material::from_e_nu(Law::NeoHooke, E, NU).mu;
    for kind in [ElementKind::Hex8, ElementKind::Tet10] {
        let size = [1.0, 1.0, 1.0];
        let mesh = box_mesh(size, [2, 2, 2], kind);
        let boundary = common::box_boundary_nodes(&mesh, size);
        let mut an = common::analysis(
            mesh,
            &format!(
                "{}\n[[step]]\nnlgeom = true\nincrements = 3\nresidual_tolerance = 1e-12\ndisplacement_tolerance = 1e-12\n",
                material_text()
            ),
        );
        common::prescribe_field(&mut an, &boundary, |x| [gamma * x[1], 0.0, 0.0]);
        let (_, rec) = common::solve(&an);
        let last = rec.last().expect("converged");
        let f = stress_fields(&an, &last.u, true);
        let expect = [mu * gamma * gamma, 0.0, 0.0, mu * gamma, 0.0, 0.0];
        for cell in f.cell_stress.chunks(6) {
            for c in 0..6 {
                assert!(
                    (cell[c] - expect[c]).abs() <= 1e-9 * mu,
                    "{kind:?}: σ[{c}] = {} vs {}",
                    cell[c],
                    expect[c]
                );
            }
        }
    }
}

/// Hydrostatic compression by a follower pressure `p` on the three outer
/// faces of a cube with symmetry supports: `b = l² I`, `J = l³`, and the
/// Cauchy stress `(μ (l² − 1) + 3 λ ln l) / l³ = −p`. A dead pressure (the
/// same nominal load on the reference faces) gives a different stretch.
#[test]
fn hydrostatic_follower_pressure() {
    let p = 3.0;
    let mat = Material::from_e_nu(Law::NeoHooke, E, NU);
    let (lam, mu) = (mat.lambda, mat.mu);
    let mut l: f64 = 1.0;
    for _ in 0..60 {
        let g = (mu * (l * l - 1.0) + 3.0 * lam * l.ln()) / l.powi(3) + p;
        let dg = (2.0 * mu * l + 3.0 * lam / l) / l.powi(3)
            - 3.0 * (mu * (l * l - 1.0) + 3.0 * lam * l.ln()) / l.powi(4);
        l -= g / dg;
    }
    let run_with = |follower: bool| {
        let mesh = box_mesh([1.0, 1.0, 1.0], [2, 2, 2], ElementKind::Hex8);
        let mut text = material_text();
        for (g, c) in [("xmin", "x"), ("ymin", "y"), ("zmin", "z")] {
            text += &format!("[[boundary]]\ngroup = \"{g}\"\nfix = [\"{c}\"]\n");
        }
        for g in ["xmax", "ymax", "zmax"] {
            text += &format!("[[load]]\ngroup = \"{g}\"\npressure = {p}\nfollower = {follower}\n");
        }
        text += "[[step]]\nnlgeom = true\nincrements = 4\nresidual_tolerance = 1e-12\ndisplacement_tolerance = 1e-12\n";
        let an = common::analysis(mesh, &text);
        let (_, rec) = common::solve(&an);
        let u = rec.last().expect("converged").u.clone();
        let corner = an
            .mesh
            .nodes
            .iter()
            .position(|q| q.iter().all(|&c| (c - 1.0).abs() < 1e-12))
            .expect("corner");
        let f = stress_fields(&an, &u, true);
        (u[3 * corner], f.cell_stress)
    };
    let (uc, stress) = run_with(true);
    assert!((uc - (l - 1.0)).abs() <= 1e-9, "corner {uc} vs {}", l - 1.0);
    for cell in stress.chunks(6) {
        for c in 0..3 {
            assert!((cell[c] + p).abs() <= 1e-9 * p, "σ = {cell:?}");
        }
    }
    let (uc_dead, _) = run_with(false);
    assert!(
        (uc_dead - uc).abs() > 1e-2,
        "dead and follower loads should differ at this strain"
    );
}
