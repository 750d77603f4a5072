//! Cantilever `L × 1 × 1` (L = 10), clamped at x = 0, total tip force P in
//! −y spread over the tip face. Reference: Timoshenko beam,
//! `δ = P L³ / (3 E I) + P L / (κ G A)`, `I = 1/12`, `κ = 5/6`, ν = 0 so the
//! 3D solution has no Poisson coupling. Also: equilibrium of reactions and
//! applied load, quadratic Newton convergence at finite strain, and
//! independence of the result from the number of threads.
#![allow(clippy::needless_range_loop)]

mod common;

use tricontact_fem::analysis::Analysis;
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::structured::box_mesh;

const L: f64 = 10.0;
const E: f64 = 1000.0;
const P: f64 = 0.1;

fn beam(kind: ElementKind, n: [usize; 3], law: &str, nu: f64, force: f64, step: &str) -> Analysis {
    beam_of(E, kind, n, (law, nu), force, step)
}

/// [`beam`] of Young's modulus `e`.
fn beam_of(
    e: f64,
    kind: ElementKind,
    n: [usize; 3],
    (law, nu): (&str, f64),
    force: f64,
    step: &str,
) -> Analysis {
    let mesh = box_mesh([L, 1.0, 1.0], n, kind);
    common::analysis(
        mesh,
        &format!(
            r#"
[[material]]
name = "m"
type = "{law}"
E = {e:e}
nu = {nu}
[[body]]
group = "solid"
material = "m"
[[boundary]]
group = "xmin"
fix = ["x", "y", "z"]
[[load]]
group = "xmax"
force = [0.0, {:e}, 0.0]
[[step]]
{step}
"#,
            -force
        ),
    )
}

fn tip_deflection(an: &Analysis, u: &[f64]) -> f64 {
    let tip = &an.mesh.group("xmax").expect("tip").nodes;
    -tip.iter().map(|&a| u[3 * a + 1]).sum::<f64>() / tip.len() as f64
}

fn reference_deflection() -> f64 {
    let i = 1.0 / 12.0;
    let g = E / 2.0;
    P * L.powi(3) / (3.0 * E * i) + P * L / (5.0 / 6.0 * g)
}

fn errors(kind: ElementKind, meshes: &[[usize; 3]]) -> Vec<f64> {
    let exact = reference_deflection();
    meshes
        .iter()
        .map(|&n| {
            let an = beam(kind, n, "linear_elastic", 0.0, P, "");
            let (_, rec) = common::solve(&an);
            let last = rec.last().expect("converged");
            // Sum of reactions balances the applied load.
            let r = last.reactions[0];
            assert!((r[1] - P).abs() <= 1e-9 * P, "reaction {r:?}");
            assert!(
                r[0].abs() <= 1e-9 * P && r[2].abs() <= 1e-9 * P,
                "reaction {r:?}"
            );
            let err = (tip_deflection(&an, &last.u) - exact).abs() / exact;
            eprintln!("{kind:?} {n:?}: tip deflection error {err:.4e}");
            err
        })
        .collect()
}

#[test]
fn hex8_tip_deflection_converges() {
    let e = errors(ElementKind::Hex8, &[[10, 1, 1], [20, 2, 2], [40, 4, 4]]);
    assert!(e[0] > e[1] && e[1] > e[2], "errors {e:?}");
    assert!(e[2] < 0.05, "errors {e:?}");
}

#[test]
fn tet10_tip_deflection_converges() {
    let e = errors(ElementKind::Tet10, &[[5, 1, 1], [10, 2, 2], [20, 4, 4]]);
    assert!(e[0] > e[1] && e[1] > e[2], "errors {e:?}");
    assert!(e[2] < 0.01, "errors {e:?}");
}

#[test]
fn newton_converges_quadratically_at_finite_strain() {
    // Tip force giving a deflection of ~40 % of the length, two increments, each started from
    // the last converged state: an extrapolated start (the default) begins closer, so its
    // residuals relative to the first one are not yet asymptotic at 1e-2 and the test would
    // judge the starting point rather than the tangent.
    let step = "nlgeom = true\nincrements = 2\nmax_iterations = 30\nresidual_tolerance = 1e-11\ndisplacement_tolerance = 1e-11\nextrapolation = \"none\"";
    let an = beam(ElementKind::Hex8, [10, 2, 2], "neo_hooke", 0.3, 1.0, step);
    let (_, rec) = common::solve(&an);
    let last = rec.last().expect("converged");
    assert!(
        tip_deflection(&an, &last.u) > 2.0,
        "large deflection expected"
    );
    let mut checked = 0;
    for r in &rec {
        let e: Vec<f64> = r.residuals.iter().map(|x| x / r.residuals[0]).collect();
        eprintln!("increment {}: relative residuals {e:?}", r.increment);
        // Pairs in the asymptotic range, above the round-off floor
        // (~1e-12): e_{k+1} ≤ C e_k².
        for k in 1..e.len() - 1 {
            if e[k] < 1e-2 && e[k + 1] > 1e-10 {
                assert!(e[k + 1] <= 100.0 * e[k] * e[k], "not quadratic: {e:?}");
                checked += 1;
            }
        }
        assert!(r.iterations <= 8, "too many iterations: {e:?}");
        // Reactions balance the applied load at every converged increment.
        let applied = r.load_factor;
        assert!(
            (r.reactions[0][1] - applied).abs() <= 1e-8 * applied,
            "{:?}",
            r.reactions
        );
    }
    assert!(checked >= 1, "no iteration pair in the asymptotic range");
}

/// Steel in SI units (E = 2.1·10¹¹) under a 1 N tip load: strains of about 10⁻⁹. At finite strain
/// the stress must keep its digits (no `F − F⁻ᵀ` or `ln det F` cancelling), or Newton stalls
/// above the default tolerance (it used to stop at a relative residual of 5·10⁻⁷ and fail after
/// five cutbacks); the deflection equals the small-strain one to the size of the strains.
#[test]
fn stiff_material_under_a_small_load_converges_at_default_tolerances() {
    for law in ["neo_hooke", "linear_elastic"] {
        let deflection = |step: &str| {
            let an = beam_of(2.1e11, ElementKind::Hex8, [10, 2, 2], (law, 0.3), 1.0, step);
            let (_, rec) = common::solve(&an);
            let last = rec.last().expect("converged");
            assert!(last.iterations <= 4, "{law}: {:?}", last.residuals);
            tip_deflection(&an, &last.u)
        };
        let (large, small) = (deflection("nlgeom = true"), deflection("nlgeom = false"));
        assert!(
            small > 0.0 && (large - small).abs() <= 1e-6 * small,
            "{law}: {large} vs {small}"
        );
    }
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let step = "nlgeom = true\nincrements = 2";
    let run_with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let an = beam(ElementKind::Tet10, [6, 2, 2], "neo_hooke", 0.3, 1.0, step);
            common::solve(&an).1.last().expect("converged").u.clone()
        })
    };
    let (u1, u2) = (run_with(1), run_with(2));
    let scale = u1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = u1
        .iter()
        .zip(&u2)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(
        diff <= 1e-12 * scale,
        "difference {diff:e} (scale {scale:e})"
    );
}

#[test]
fn cutback_recovers_and_matches_a_fine_run() {
    let tol = "residual_tolerance = 1e-10\ndisplacement_tolerance = 1e-10";
    let hard = beam(
        ElementKind::Hex8,
        [10, 2, 2],
        "neo_hooke",
        0.3,
        1.5,
        &format!("nlgeom = true\nincrements = 1\nmax_iterations = 6\n{tol}"),
    );
    let (summary, rec) = common::solve(&hard);
    let factors: Vec<f64> = rec.iter().map(|r| r.load_factor).collect();
    eprintln!("cutbacks {} load factors {factors:?}", summary.cutbacks);
    assert!(summary.cutbacks >= 1, "expected a cutback");
    assert!((factors.last().copied().unwrap_or(0.0) - 1.0).abs() < 1e-12);
    // Hyperelastic: the end state does not depend on the load path.
    let fine = beam(
        ElementKind::Hex8,
        [10, 2, 2],
        "neo_hooke",
        0.3,
        1.5,
        &format!("nlgeom = true\nincrements = 10\n{tol}"),
    );
    let (_, rec_fine) = common::solve(&fine);
    let (a, b) = (
        &rec.last().expect("converged").u,
        &rec_fine.last().expect("converged").u,
    );
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(diff <= 1e-7 * scale, "difference {diff:e}");
}

#[test]
fn exhausted_cutbacks_are_reported() {
    let an = beam(
        ElementKind::Hex8,
        [10, 2, 2],
        "neo_hooke",
        0.3,
        1.5,
        "nlgeom = true\nincrements = 1\nmax_iterations = 3\nmax_cutbacks = 1",
    );
    let e =
        tricontact_fem::driver::run(&an, &mut tricontact_fem::assembly::NoExtra, &mut |_| Ok(()))
            .expect_err("must fail");
    let msg = e.to_string();
    assert!(
        matches!(e, tricontact_fem::FemError::NotConverged { .. }),
        "{msg}"
    );
    assert!(msg.contains("(after 1 cutback): "), "{msg}");
    // One increment, halved once: the last attempt aimed at half the step.
    assert!(
        msg.contains("from load factor 0.000000 to 0.500000"),
        "{msg}"
    );
}

/// A tolerance tighter than double precision stalls Newton at round-off; the failure says so and
/// names the key to raise, instead of a bare iteration count.
#[test]
fn a_tolerance_below_round_off_is_named() {
    for (key, quantity) in [
        ("residual_tolerance", "residual"),
        ("displacement_tolerance", "displacement"),
    ] {
        let step = format!("nlgeom = true\nmax_iterations = 8\nmax_cutbacks = 0\n{key} = 1e-17");
        let an = beam(ElementKind::Hex8, [10, 2, 2], "neo_hooke", 0.3, 0.1, &step);
        let e =
            tricontact_fem::driver::run(&an, &mut tricontact_fem::assembly::NoExtra, &mut |_| {
                Ok(())
            })
            .expect_err("cannot converge");
        let msg = e.to_string();
        assert!(
            msg.contains(&format!("the {quantity} test stalled at round-off"))
                && msg.contains(&format!("`{quantity}_tolerance` asks for more")),
            "{msg}"
        );
    }
}

/// Loads of 10⁻¹⁷⁰ or 10²⁰⁰ (whose squares underflow or overflow): the residual norms are taken
/// without squaring them raw, so the run still solves and the reactions balance the load (a load
/// of 10⁻¹⁷⁰ used to end with zero displacement, and 10²⁰⁰ with a "non-finite residual").
#[test]
fn extreme_load_magnitudes_still_solve() {
    for force in [1e-170, 1e200] {
        let an = beam(
            ElementKind::Hex8,
            [10, 2, 2],
            "linear_elastic",
            0.3,
            force,
            "nlgeom = false",
        );
        let (_, rec) = common::solve(&an);
        let last = rec.last().expect("converged");
        assert!(last.iterations >= 1, "{force}: no iteration");
        let reaction = last.reactions[0][1];
        assert!(
            (reaction - force).abs() <= 1e-8 * force,
            "{force}: reaction {reaction}"
        );
        assert!(tip_deflection(&an, &last.u) > 0.0, "{force}: no deflection");
    }
}
