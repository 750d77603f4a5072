//! A concave valley of the master: a wedge pressed into a V-groove, a row of its bottom nodes on
//! the valley line. One constraint per node cannot hold such a node (it is pushed from one flank
//! across to the other); the flank across the kink is a second constraint
//! (`contact::flank::second_flank`), with each method.

mod common;

use tricontact_fem::contact::ContactTerms;
use tricontact_fem::mesh::ElementKind;

/// The V-groove model (`common::v_groove_model`) with the pair of the wedge's bottom against the
/// groove, by `method`.
fn model(method: &str) -> String {
    common::v_groove_model(&format!(
        "slave = \"upper_zmin\"\nmaster = \"lower_zmax\"\nmethod = \"{method}\""
    ))
}

/// Each method: the press converges in its four increments, the nodes on the valley line end on
/// two flanks, and nothing lies deeper behind any flank than the method's own gaps (the
/// penalty's about `F/α`, the augmented's within its tolerance, the multipliers' round-off).
/// With one constraint per node the multipliers left the valley nodes 7.8·10⁻³ behind the other
/// flank (hex8) and the other two methods failed at 75 % of the press.
#[test]
fn a_wedge_pressed_into_a_v_groove_is_held_by_both_flanks() {
    for kind in [ElementKind::Hex8, ElementKind::Tet4] {
        let mesh = common::v_groove([16, 4, 4], [8, 3, 3], kind);
        let mut forces = Vec::new();
        for method in ["penalty", "augmented", "multiplier"] {
            let an = common::analysis(mesh.clone(), &model(method));
            let (terms, records, _) = common::solve_contact(&an);
            let last = records.last().expect("increments");
            let (two, _) = common::second_flanks(&terms);
            let force = common::contact_column(&terms, "_normal_force");
            let depth = common::contact_column(&terms, "_max_penetration");
            println!(
                "{kind:?} {method}: {} increments, {two} nodes on two flanks, normal force {force:.6e}, largest penetration {depth:.3e}",
                records.len()
            );
            assert_eq!(last.load_factor, 1.0, "{kind:?} {method}");
            // Four increments: none cut back.
            assert_eq!(records.len(), 4, "{kind:?} {method}");
            assert!(two >= 4, "{kind:?} {method}: {two} nodes on two flanks");
            // The groove is 2 wide and 1 deep: lengths of order one.
            let bound = match method {
                "penalty" => 1e-3,
                "augmented" => 1e-5,
                _ => 1e-12,
            };
            assert!(depth < bound, "{kind:?} {method}: penetration {depth}");
            forces.push(force);
        }
        // The augmented Lagrangian and the multipliers agree on the force within its tolerance,
        // the penalty within its compliance.
        let [penalty, augmented, multiplier] = forces[..] else {
            panic!("three methods");
        };
        assert!(
            (multiplier - augmented).abs() < 1e-3 * multiplier,
            "{forces:?}"
        );
        assert!(
            (penalty - multiplier).abs() < 0.02 * multiplier,
            "{forces:?}"
        );
    }
}

/// The press in one increment with at most four Newton iterations (three with multipliers):
/// each method cuts it back (restoring the node states, second flanks and their multipliers
/// included, from the last converged state) and still ends on two flanks with the normal force
/// of the four increments (frictionless and elastic, the end state does not depend on the path;
/// measured: the same to eight digits with the penalty and the multipliers).
#[test]
fn the_v_groove_pressed_at_once_is_cut_back_and_ends_as_in_four_increments() {
    let mesh = common::v_groove([16, 4, 4], [8, 3, 3], ElementKind::Hex8);
    for method in ["penalty", "augmented", "multiplier"] {
        let force_of = |text: &str| {
            let an = common::analysis(mesh.clone(), text);
            let (terms, records, _) = common::solve_contact(&an);
            assert_eq!(records.last().expect("increments").load_factor, 1.0);
            let (two, _) = common::second_flanks(&terms);
            assert!(two >= 4, "{method}: {two} nodes on two flanks");
            (
                common::contact_column(&terms, "_normal_force"),
                records.len(),
            )
        };
        let (stepped, _) = force_of(&model(method));
        // Fewer iterations than the first increment needs (the multipliers need four).
        let most = if method == "multiplier" { 3 } else { 4 };
        let at_once = model(method).replace(
            "increments = 4",
            &format!("increments = 1\nmax_iterations = {most}"),
        );
        let (force, increments) = force_of(&at_once);
        println!(
            "{method}: {increments} increments after cutbacks, normal force {force:.7e} against {stepped:.7e}"
        );
        assert!(increments > 1, "{method}: no cutback");
        // The augmented Lagrangian stops its Uzawa updates once the gaps are within its
        // tolerance, at a force that depends on the path by as much (2.6·10⁻⁵ measured).
        let within = if method == "augmented" { 1e-4 } else { 1e-6 };
        assert!(
            (force - stepped).abs() < within * stepped,
            "{method}: {force} against {stepped}"
        );
    }
}

/// Two passes (penalty and augmented Lagrangian; multipliers take one): the groove's pass holds
/// the valley nodes on two flanks as the single pass does (the wedge's pass, its master a ridge,
/// has no concave kink), in four increments, with the single pass's normal force within 1 %
/// (measured: 6.969 and 7.027 against 6.962 and 7.027).
#[test]
fn two_passes_hold_the_valley_nodes_on_both_flanks_too() {
    let mesh = common::v_groove([16, 4, 4], [8, 3, 3], ElementKind::Hex8);
    for method in ["penalty", "augmented"] {
        let run = |text: &str| {
            let an = common::analysis(mesh.clone(), text);
            let (terms, records, _) = common::solve_contact(&an);
            assert_eq!(records.len(), 4, "{method}");
            assert_eq!(records.last().expect("increments").load_factor, 1.0);
            let (two, _) = common::second_flanks(&terms);
            (common::contact_column(&terms, "_normal_force"), two)
        };
        let (single, _) = run(&model(method));
        let passes = model(method).replace(
            &format!("method = \"{method}\""),
            &format!("method = \"{method}\"\ntwo_pass = true"),
        );
        let (force, two) = run(&passes);
        println!(
            "{method}, two passes: {two} nodes on two flanks, normal force {force:.6e} against {single:.6e}"
        );
        assert!(two >= 4, "{method}: {two} nodes on two flanks");
        assert!(
            (force - single).abs() < 0.01 * single,
            "{method}: {force} against {single}"
        );
    }
}

/// Multipliers against a fixed base, the wedge's bottom nodes free only along `y` and `z`: at a
/// valley node the two flanks' normals agree in those components, so its two constraints
/// repeat each other and the system is singular. The run fails naming those nodes and the way
/// out; with `small_sliding` (one constraint per node) the same model converges.
#[test]
fn parallel_flanks_in_the_free_components_are_named_as_the_cause() {
    let mesh = common::v_groove([16, 4, 4], [8, 3, 3], ElementKind::Hex8);
    let fixed = model("multiplier")
        .replace("group = \"lower_zmin\"", "group = \"lower_solid\"")
        .replace(
            "[[contact]]",
            "[[boundary]]\ngroup = \"upper_zmin\"\nfix = [\"x\"]\n[[contact]]",
        );
    let an = common::analysis(mesh.clone(), &fixed);
    let mut terms = ContactTerms::new(&an);
    let err = tricontact_fem::driver::run(&an, &mut terms, &mut |_| Ok(()))
        .expect_err("singular")
        .to_string();
    assert!(
        err.contains("closed on both flanks of a concave kink")
            && err.contains("parallel in their free components")
            && err.contains("small_sliding = true"),
        "{err}"
    );
    let small = fixed.replace(
        "method = \"multiplier\"",
        "method = \"multiplier\"\nsmall_sliding = true",
    );
    let (_, records, _) = common::solve_contact(&common::analysis(mesh, &small));
    assert_eq!(records.last().expect("increments").load_factor, 1.0);
}
