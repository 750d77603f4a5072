//! A concave valley of the master: a wedge pressed into a V-groove, a row of its bottom nodes on
//! the valley line. One constraint per node cannot hold such a node (it is pushed from one flank
//! across to the other); with a penalty or the augmented Lagrangian the flank across the kink is
//! a second constraint (`contact::flank::second_flank`).

mod common;

use tricontact_fem::assembly::ExtraTerms;
use tricontact_fem::contact::ContactTerms;
use tricontact_fem::mesh::ElementKind;

/// The V-groove model: a stiff base (`E` 1000) and a soft wedge (100), neo-Hookean, the wedge's
/// top pressed 0.04 down in four increments.
fn model(method: &str) -> String {
    format!(
        r#"
[[material]]
name = "base"
type = "neo_hooke"
E = 1000.0
nu = 0.3
[[material]]
name = "wedge"
type = "neo_hooke"
E = 100.0
nu = 0.3
[[body]]
group = "lower_solid"
material = "base"
[[body]]
group = "upper_solid"
material = "wedge"
[[boundary]]
group = "lower_zmin"
fix = ["x", "y", "z"]
[[boundary]]
group = "upper_zmax"
displacement = {{ x = 0.0, y = 0.0, z = -0.04 }}
[[contact]]
slave = "upper_zmin"
master = "lower_zmax"
method = "{method}"
[[step]]
name = "press"
increments = 4
nlgeom = true
"#
    )
}

fn column(terms: &ContactTerms, key: &str) -> f64 {
    terms
        .history()
        .into_iter()
        .find(|(k, _)| k.ends_with(key))
        .map(|(_, v)| v)
        .expect("column")
}

/// Penalty and augmented Lagrangian: the press converges in its four increments, the nodes on the
/// valley line end on two flanks, and nothing lies deeper behind any flank than the method's
/// own gaps (the penalty's about `F/α`, the augmented's within its tolerance). Multipliers, one
/// constraint per node, converge too but leave the valley nodes behind the other flank, and
/// report it.
#[test]
fn a_wedge_pressed_into_a_v_groove_is_held_by_both_flanks() {
    let mut forces = Vec::new();
    for kind in [ElementKind::Hex8, ElementKind::Tet4] {
        let mesh = common::v_groove([16, 4, 4], [8, 3, 3], kind);
        for method in ["penalty", "augmented", "multiplier"] {
            let an = common::analysis(mesh.clone(), &model(method));
            let (terms, records, _) = common::solve_contact(&an);
            let last = records.last().expect("increments");
            let (two, _) = common::second_flanks(&terms);
            let force = column(&terms, "_normal_force");
            let depth = column(&terms, "_max_penetration");
            println!(
                "{kind:?} {method}: {} increments, {two} nodes on two flanks, normal force {force:.6e}, largest penetration {depth:.3e}",
                records.len()
            );
            assert_eq!(last.load_factor, 1.0, "{kind:?} {method}");
            match method {
                "multiplier" => {
                    assert_eq!(two, 0);
                    assert!(depth > 1e-3, "{kind:?}: the unheld flank reported: {depth}");
                }
                _ => {
                    // Four increments: none cut back.
                    assert_eq!(records.len(), 4, "{kind:?} {method}");
                    assert!(two >= 4, "{kind:?} {method}: {two} nodes on two flanks");
                    let bound = if method == "penalty" { 1e-3 } else { 1e-5 };
                    assert!(depth < bound, "{kind:?} {method}: penetration {depth}");
                    forces.push(force);
                }
            }
        }
    }
    // Penalty and augmented agree on the force within the penalty's compliance.
    for pair in forces.chunks(2) {
        assert!((pair[0] - pair[1]).abs() < 0.02 * pair[1], "{pair:?}");
    }
}
