//! Hertz contact (examples/hertz): a steel sphere pressed on a rigid flat, quarter model, run
//! from the example model files on the coarse and medium meshes with each enforcement method.
//! Checks, against Hertz theory at the computed force: the fitted contact radius and peak pressure
//! on the medium mesh within the targets (3 %, 5 %), the errors falling from coarse to
//! medium, the force near the nominal 20 kN, and the fitted approach coefficient within 5 %.

mod common;

use tricontact_fem::hertz::{HertzErrors, fit_approach};

struct Outcome {
    errors: HertzErrors,
    force: f64,
    approach_error: f64,
    iterations: Vec<usize>,
}

fn run(method: &str, level: &str) -> Outcome {
    let mesh = format!("hertz-{level}.msh");
    let (_, record) = common::run_example("hertz", &format!("{method}.toml"), Some(&mesh));
    let (setup, samples) = record.hertz.as_ref().expect("hertz record");
    let last = samples.last().expect("increments");
    let curve: Vec<(f64, f64)> = samples.iter().map(|s| (s.force, s.approach)).collect();
    let (k, _) = fit_approach(&curve).expect("approach fit");
    Outcome {
        errors: last.errors(&setup.theory),
        force: last.force,
        approach_error: k / setup.theory.approach_coefficient() - 1.0,
        iterations: samples.iter().map(|s| s.iterations).collect(),
    }
}

fn check_method(method: &str) {
    let coarse = run(method, "coarse");
    let medium = run(method, "medium");
    for (name, o) in [("coarse", &coarse), ("medium", &medium)] {
        println!(
            "{method} {name}: F {:.1}, radius {:+.3} %, p0 {:+.3} %, max nodal {:+.3} %, k {:+.3} %, iterations {:?}",
            o.force,
            100.0 * o.errors.fit_radius,
            100.0 * o.errors.fit_peak,
            100.0 * o.errors.max_pressure,
            100.0 * o.approach_error,
            o.iterations
        );
        assert!(
            (o.force / 20_000.0 - 1.0).abs() < 0.05,
            "{method} {name}: force {}",
            o.force
        );
        assert!(o.iterations.iter().all(|&n| n <= 12), "{method} {name}");
    }
    let e = &medium.errors;
    assert!(
        e.fit_radius.abs() < 0.03,
        "{method}: radius {}",
        e.fit_radius
    );
    assert!(e.fit_peak.abs() < 0.05, "{method}: p0 {}", e.fit_peak);
    assert!(medium.approach_error.abs() < 0.05, "{method}: approach");
    assert!(
        e.fit_radius.abs() < coarse.errors.fit_radius.abs(),
        "{method}: radius not refined"
    );
    assert!(
        e.fit_peak.abs() < coarse.errors.fit_peak.abs(),
        "{method}: p0 not refined"
    );
    assert!(
        medium.approach_error.abs() < coarse.approach_error.abs(),
        "{method}: approach not refined"
    );
}

#[test]
fn hertz_multiplier() {
    check_method("multiplier");
}

#[test]
fn hertz_penalty() {
    check_method("penalty");
}

#[test]
fn hertz_augmented() {
    check_method("augmented");
}

/// The targets on the finest level (contact radius within 3 %, peak pressure within 5 % — the
/// fitted `p0` and also the largest nodal value), every method. About two minutes on two cores,
/// so not part of the default run: `cargo test --release -p tricontact-fem --test hertz -- --ignored`.
#[test]
#[ignore = "fine mesh, about two minutes; run with --ignored"]
fn hertz_fine_meets_the_targets() {
    for method in ["multiplier", "penalty", "augmented"] {
        let o = run(method, "fine");
        let e = &o.errors;
        println!(
            "{method} fine: F {:.1}, radius {:+.3} %, p0 {:+.3} %, max nodal {:+.3} %, k {:+.3} %",
            o.force,
            100.0 * e.fit_radius,
            100.0 * e.fit_peak,
            100.0 * e.max_pressure,
            100.0 * o.approach_error
        );
        assert!(
            e.fit_radius.abs() < 0.03,
            "{method}: radius {}",
            e.fit_radius
        );
        assert!(e.fit_peak.abs() < 0.05, "{method}: p0 {}", e.fit_peak);
        assert!(
            e.max_pressure.abs() < 0.05,
            "{method}: max nodal {}",
            e.max_pressure
        );
        assert!(
            o.approach_error.abs() < 0.01,
            "{method}: approach {}",
            o.approach_error
        );
    }
}

/// A `centre` or `radius` far outside the model's scale (a unit slip) is refused by name: a centre
/// at 10³⁰⁰ made every distance from the axis infinite in `hertz_profile.csv`.
#[test]
fn a_centre_or_radius_far_outside_the_model_is_refused() {
    let (m, an) = common::example("hertz", "penalty.toml", Some("hertz-coarse.msh"));
    let def = m.hertz.expect("[hertz]");
    tricontact_fem::hertz::HertzSetup::resolve(&def, &an).expect("the example's table resolves");
    let mut far = def.clone();
    far.centre = [1e300, 0.0, 0.0];
    let e = tricontact_fem::hertz::HertzSetup::resolve(&far, &an).expect_err("far centre");
    assert!(
        e.to_string()
            .contains("centre [1e300, 0.0, 0.0] is more than"),
        "{e}"
    );
    let mut huge = def.clone();
    huge.radius = 1e300;
    let e = tricontact_fem::hertz::HertzSetup::resolve(&huge, &an).expect_err("huge radius");
    assert!(e.to_string().contains("radius 1e300 exceeds"), "{e}");
    // An axis is normalised without squaring its components (1e200 overflowed and was refused
    // as zero); one that is not finite is refused as such.
    let mut long = def.clone();
    long.axis = [0.0, 0.0, 1e200];
    let setup = tricontact_fem::hertz::HertzSetup::resolve(&long, &an).expect("a long axis");
    assert_eq!(setup.axis, [0.0, 0.0, 1.0]);
    let mut nan = def;
    nan.axis = [f64::NAN, 0.0, 1.0];
    let e = tricontact_fem::hertz::HertzSetup::resolve(&nan, &an).expect_err("NaN axis");
    assert!(
        e.to_string()
            .contains("[hertz] axis must be finite and not zero"),
        "{e}"
    );
}

/// A modulus taken from an invalid slave material is not quoted back as if the user had given
/// it (`modulus must be > 0 (got -1.1)`): the message says where it came from.
#[test]
fn a_modulus_from_an_invalid_material_says_where_it_came_from() {
    let (m, mut an) = common::example("hertz", "penalty.toml", Some("hertz-coarse.msh"));
    let def = m.hertz.expect("[hertz]");
    assert!(def.modulus.is_none(), "the example takes the sphere's");
    // Both Lamé constants negated: the Young's modulus E = μ(3λ + 2μ)/(λ + μ) changes sign.
    for material in &mut an.materials {
        material.mu = -material.mu;
        material.lambda = -material.lambda;
    }
    let e = tricontact_fem::hertz::HertzSetup::resolve(&def, &an).expect_err("invalid material");
    assert_eq!(
        e.messages(),
        [
            "[hertz] modulus: taken from the slave body's material, which is invalid; fix the material or give `modulus`"
        ]
    );
}
