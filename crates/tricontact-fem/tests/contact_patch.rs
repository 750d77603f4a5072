//! Contact patch test: a block pressed by a uniform pressure `p` onto a block resting on rollers.
//! Both blocks are on lateral rollers (a confined, uniform stress state), so slave nodes on the
//! block edges stay on the master's edges. The contact pressure at every slave node must equal `p`.
#![allow(clippy::needless_range_loop)]

mod common;

use tricontact_fem::contact::ContactTerms;
use tricontact_fem::mesh::{ElementKind, Mesh};
use tricontact_fem::structured::box_mesh;

const P: f64 = 1.0;

fn model(method: &str, extra: &str) -> String {
    format!(
        r#"
[[material]]
name = "m"
type = "linear_elastic"
E = 1000.0
nu = 0.3
[[body]]
group = "lower_solid"
material = "m"
[[body]]
group = "upper_solid"
material = "m"
[[boundary]]
group = "lower_zmin"
fix = ["z"]
[[boundary]]
group = "lower_xmin"
fix = ["x"]
[[boundary]]
group = "lower_xmax"
fix = ["x"]
[[boundary]]
group = "lower_ymax"
fix = ["y"]
[[boundary]]
group = "lower_ymin"
fix = ["y"]
[[boundary]]
group = "upper_xmin"
fix = ["x"]
[[boundary]]
group = "upper_xmax"
fix = ["x"]
[[boundary]]
group = "upper_ymax"
fix = ["y"]
[[boundary]]
group = "upper_ymin"
fix = ["y"]
[[load]]
group = "upper_zmax"
pressure = {P}
[[contact]]
slave = "upper_zmin"
master = "lower_zmax"
method = "{method}"
{extra}
[[step]]
residual_tolerance = 1e-11
displacement_tolerance = 1e-10
"#
    )
}

fn blocks(lower: ([usize; 3], ElementKind), upper: ([usize; 3], ElementKind)) -> Mesh {
    let l = box_mesh([1.0, 1.0, 0.5], lower.0, lower.1);
    let u = box_mesh([1.0, 1.0, 0.5], upper.0, upper.1);
    tricontact_fem::structured::stack(&l, &u, [0.0, 0.0, 0.5])
}

/// Largest relative deviation of the slave pressures from `p`.
fn pressure_error(terms: &ContactTerms) -> f64 {
    let pass = &terms.pairs()[0].passes[0];
    let f = terms.forces();
    let mut worst = 0.0f64;
    for (j, &s) in pass.slaves.iter().enumerate() {
        let m = (f[3 * s].powi(2) + f[3 * s + 1].powi(2) + f[3 * s + 2].powi(2)).sqrt();
        worst = worst.max((m / pass.areas[j] - P).abs() / P);
    }
    worst
}

fn run(mesh: Mesh, method: &str, extra: &str) -> (f64, ContactTerms, Vec<common::Record>) {
    let mut text = model(method, extra);
    if extra.contains("penalty") {
        // A stiff penalty amplifies round-off: a looser residual test.
        text = text.replace("residual_tolerance = 1e-11", "residual_tolerance = 1e-9");
    }
    let an = common::analysis(mesh, &text);
    let (terms, rec, _) = common::solve_contact(&an);
    (pressure_error(&terms), terms, rec)
}

#[test]
fn matching_meshes_transmit_uniform_pressure() {
    for kind in [ElementKind::Hex8, ElementKind::Tet4] {
        let mesh = || blocks(([2, 2, 1], kind), ([2, 2, 1], kind));
        let (e_mult, _, rec) = run(mesh(), "multiplier", "");
        eprintln!(
            "{kind:?} multiplier: error {e_mult:.3e}, iterations {}",
            rec[0].iterations
        );
        assert!(e_mult < 1e-8, "multiplier {e_mult:e}");
        let (e_aug, _, rec) = run(mesh(), "augmented", "tolerance = 1e-13");
        eprintln!(
            "{kind:?} augmented: error {e_aug:.3e}, iterations {}",
            rec[0].iterations
        );
        assert!(e_aug < 1e-8, "augmented {e_aug:e}");
        let (e_pen, _, rec) = run(mesh(), "penalty", "");
        eprintln!(
            "{kind:?} penalty: error {e_pen:.3e}, iterations {}",
            rec[0].iterations
        );
        assert!(e_pen < 5e-2, "penalty {e_pen:e}");
        // The penalty error is the penalty's compliance: ten times stiffer, about ten times smaller.
        let (e_stiff, _, _) = run(mesh(), "penalty", "penalty = 5e4");
        eprintln!("{kind:?} penalty x10: error {e_stiff:.3e}");
        assert!(e_stiff < 0.2 * e_pen, "penalty x10 {e_stiff:e}");
    }
}

#[test]
fn refining_slave_mesh_transmits_uniform_pressure() {
    let mesh = || {
        blocks(
            ([2, 2, 1], ElementKind::Tet4),
            ([4, 4, 2], ElementKind::Tet4),
        )
    };
    let (e_mult, _, rec) = run(mesh(), "multiplier", "");
    eprintln!(
        "refining multiplier: error {e_mult:.3e}, iterations {}",
        rec[0].iterations
    );
    assert!(e_mult < 1e-8, "multiplier {e_mult:e}");
    let (e_aug, _, rec) = run(mesh(), "augmented", "tolerance = 1e-13");
    eprintln!(
        "refining augmented: error {e_aug:.3e}, iterations {}",
        rec[0].iterations
    );
    assert!(e_aug < 1e-8, "augmented {e_aug:e}");
    let (e_pen, _, rec) = run(mesh(), "penalty", "");
    eprintln!(
        "refining penalty: error {e_pen:.3e}, iterations {}",
        rec[0].iterations
    );
    assert!(e_pen < 5e-2, "penalty {e_pen:e}");
    let (e_stiff, _, _) = run(mesh(), "penalty", "penalty = 5e4");
    eprintln!("refining penalty x10: error {e_stiff:.3e}");
    assert!(e_stiff < 0.2 * e_pen, "penalty x10 {e_stiff:e}");
}
