//! Self-contact: a pair whose slave and master are one surface group. Every node of the group is
//! a slave against the group's facets that face its own side (`contact::pair`, "Self-contact").
//! Checks: the faces of two blocks named as one group (and all their outer faces) are held exactly
//! as a two-pass pair between them holds them; a U-shaped body whose slot is squeezed shut does
//! not pass through itself, and is held as a pair between the slot's sides holds it; so is a
//! wedge pressed into a V-groove, its valley nodes on both flanks; the crossing check catches a
//! node carried through the other side in one step; and what self-contact refuses is refused.

mod common;

use std::path::Path;

use tricontact_fem::analysis::Analysis;
use tricontact_fem::assembly::ExtraTerms;
use tricontact_fem::contact::ContactTerms;
use tricontact_fem::mesh::{Element, ElementKind, Group, Mesh};
use tricontact_fem::model::Model;

/// A surface group named `name` of the faces `elements` of `mesh`.
fn face_group(mesh: &Mesh, name: &str, elements: Vec<usize>) -> Group {
    let mut nodes: Vec<usize> = elements
        .iter()
        .flat_map(|&e| mesh.elements[e].nodes.iter().copied())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    Group {
        name: name.into(),
        dim: 2,
        elements,
        nodes,
    }
}

/// Adds to `mesh` the surface group `name` of the faces of the groups `parts`.
fn add_union(mesh: &mut Mesh, name: &str, parts: &[&str]) {
    let faces: Vec<usize> = parts.iter().flat_map(|g| elements_of(mesh, g)).collect();
    let group = face_group(mesh, name, faces);
    mesh.groups.push(group);
}

/// The elements of group `name`.
fn elements_of(mesh: &Mesh, name: &str) -> Vec<usize> {
    mesh.groups
        .iter()
        .find(|g| g.name == name)
        .map(|g| g.elements.clone())
        .expect("group")
}

/// A block 0.6 × 0.6 × 0.5 (5 × 5 × 2 bricks) standing on a block 1 × 1 × 0.5 (4 × 4 × 2), the
/// meshes not matching, with the upper block's bottom and the lower block's top also in one
/// group, `touching`, and every outer face of both blocks in another, `outside`.
fn two_blocks() -> Mesh {
    let lower = tricontact_fem::structured::box_mesh([1.0, 1.0, 0.5], [4, 4, 2], ElementKind::Hex8);
    let upper = tricontact_fem::structured::box_mesh([0.6, 0.6, 0.5], [5, 5, 2], ElementKind::Hex8);
    let mut mesh = tricontact_fem::structured::stack(&lower, &upper, [0.2, 0.2, 0.5]);
    add_union(&mut mesh, "touching", &["lower_zmax", "upper_zmin"]);
    let sides = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"];
    let all: Vec<String> = ["lower", "upper"]
        .iter()
        .flat_map(|b| sides.iter().map(move |s| format!("{b}_{s}")))
        .collect();
    let all: Vec<&str> = all.iter().map(String::as_str).collect();
    add_union(&mut mesh, "outside", &all);
    mesh
}

/// The two blocks, the upper one's top pressed 0.02 down in two increments, with the pair
/// `pair` (a `[[contact]]` body without its method) and `method`; the penalty given, so that both
/// pairs have the same.
fn blocks_model(pair: &str, method: &str) -> String {
    format!(
        r#"
[[material]]
name = "m"
type = "linear_elastic"
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
[[boundary]]
group = "upper_zmax"
displacement = {{ x = 0.0, y = 0.0, z = -0.02 }}
[[contact]]
{pair}
method = "{method}"
penalty = 5000.0
tolerance = 1e-5
[[step]]
name = "press"
increments = 2
"#
    )
}

/// The faces of two blocks named as one group, in contact with itself, are held as a two-pass
/// pair between the two faces holds them: each node faces the other block's facets only, so the
/// constraints are the same, and so are the Newton iterations and the force (to round-off; the
/// penalty and the augmented Lagrangian). So are all the outer faces of both blocks in one group
/// (contact of everything with everything): a node next to an edge of its block projects onto
/// the edge of the side face beyond it, behind that face's plane by an element, but the side
/// face does not face it.
#[test]
fn two_blocks_named_as_one_surface_are_held_as_a_two_pass_pair_holds_them() {
    let mesh = two_blocks();
    for method in ["penalty", "augmented"] {
        let touching = "slave = \"touching\"\nmaster = \"touching\"";
        let outside = "slave = \"outside\"\nmaster = \"outside\"";
        let two = "slave = \"upper_zmin\"\nmaster = \"lower_zmax\"\ntwo_pass = true";
        let mut runs = Vec::new();
        for pair in [touching, outside, two] {
            let an = common::analysis(mesh.clone(), &blocks_model(pair, method));
            let (terms, records, _) = common::solve_contact(&an);
            let iterations: Vec<usize> = records.iter().map(|r| r.iterations).collect();
            let force = common::contact_column(&terms, "_normal_force");
            let area = common::contact_column(&terms, "_area");
            let active = common::contact_column(&terms, "_active");
            println!(
                "{method}, {pair:?}: iterations {iterations:?}, force {force:.9e}, area {area:.6}, active {active}"
            );
            runs.push((iterations, force, area, active));
        }
        let pair_run = &runs[2];
        assert!(
            pair_run.1 > 0.5,
            "{method}: the blocks press ({})",
            pair_run.1
        );
        for self_run in &runs[..2] {
            assert_eq!(self_run.0, pair_run.0, "{method}: iterations");
            assert_eq!(self_run.3, pair_run.3, "{method}: closed nodes");
            assert!(
                (self_run.1 - pair_run.1).abs() <= 1e-9 * pair_run.1.abs(),
                "{method}: forces {} and {}",
                self_run.1,
                pair_run.1
            );
        }
        // The area counts each touching region once: both sides' closed nodes, halved (a two-pass
        // pair gives the mean of its two sides). (The group of all outer faces gives its edge
        // nodes the area of their side faces too.)
        let self_run = &runs[0];
        assert!(
            (self_run.2 - pair_run.2).abs() <= 1e-12,
            "{method}: areas {} and {}",
            self_run.2,
            pair_run.2
        );
    }
}

/// Node index of grid point `(i, j, k)` of a structured box mesh of `n` bricks.
fn grid(n: [usize; 3], i: usize, j: usize, k: usize) -> usize {
    i + (n[0] + 1) * (j + (n[1] + 1) * k)
}

/// A U-shaped body, 2.1 wide, 1 deep and 4 high: a base 1 high and two arms 1 wide with a slot
/// 0.1 wide between them (7 × 2 × 8 hex8 bricks of a box, the column of the slot removed above
/// the base). Groups: `solid`, `xmin`, `xmax`, `zmin` (the outer faces), `left_wall` and
/// `right_wall` (the slot's sides), and `slot` (both sides and its bottom).
fn u_body() -> Mesh {
    let n = [7, 2, 8];
    let mut bx = tricontact_fem::structured::box_mesh([7.0, 1.0, 4.0], n, ElementKind::Hex8);
    // Columns 0–2 the left arm (1 wide), column 3 the slot (0.1), columns 4–6 the right arm.
    for p in &mut bx.nodes {
        p[0] = match p[0] {
            x if x <= 3.0 => x / 3.0,
            x if x <= 4.0 => 1.0 + 0.1 * (x - 3.0),
            x => 1.1 + (x - 4.0) / 3.0,
        };
    }
    let mut mesh = Mesh {
        nodes: bx.nodes.clone(),
        node_tags: bx.node_tags.clone(),
        ..Mesh::default()
    };
    let centroid_in_slot = |e: &Element| {
        let c = e.nodes.iter().fold([0.0; 3], |c, &a| {
            [
                c[0] + bx.nodes[a][0],
                c[1] + bx.nodes[a][1],
                c[2] + bx.nodes[a][2],
            ]
        });
        let k = e.nodes.len() as f64;
        (1.0..1.1).contains(&(c[0] / k)) && c[2] / k > 1.0
    };
    let push = |mesh: &mut Mesh, e: Element| {
        mesh.elements.push(e);
        mesh.elements.len() - 1
    };
    let solid: Vec<usize> = elements_of(&bx, "solid")
        .into_iter()
        .map(|e| bx.elements[e].clone())
        .filter(|e| !centroid_in_slot(e))
        .map(|e| push(&mut mesh, e))
        .collect();
    mesh.groups.push(Group {
        name: "solid".into(),
        dim: 3,
        elements: solid,
        nodes: Vec::new(),
    });
    for name in ["xmin", "xmax", "zmin"] {
        let faces: Vec<usize> = elements_of(&bx, name)
            .into_iter()
            .map(|e| push(&mut mesh, bx.elements[e].clone()))
            .collect();
        let group = face_group(&mesh, name, faces);
        mesh.groups.push(group);
    }
    let mut tag = 1000;
    let mut quad = |mesh: &mut Mesh, nodes: [usize; 4]| {
        tag += 1;
        push(
            mesh,
            Element {
                kind: ElementKind::Quad4,
                nodes: nodes.to_vec(),
                tag,
            },
        )
    };
    let wall = |mesh: &mut Mesh, quad: &mut dyn FnMut(&mut Mesh, [usize; 4]) -> usize, i| {
        let mut faces = Vec::new();
        for j in 0..n[1] {
            for k in 2..n[2] {
                let g = |j, k| grid(n, i, j, k);
                faces.push(quad(
                    mesh,
                    [g(j, k), g(j + 1, k), g(j + 1, k + 1), g(j, k + 1)],
                ));
            }
        }
        faces
    };
    let left = wall(&mut mesh, &mut quad, 3);
    let right = wall(&mut mesh, &mut quad, 4);
    let bottom: Vec<usize> = (0..n[1])
        .map(|j| {
            let g = |i, j| grid(n, i, j, 2);
            quad(&mut mesh, [g(3, j), g(4, j), g(4, j + 1), g(3, j + 1)])
        })
        .collect();
    let slot: Vec<usize> = left.iter().chain(&right).chain(&bottom).copied().collect();
    for (name, faces) in [("left_wall", left), ("right_wall", right), ("slot", slot)] {
        let group = face_group(&mesh, name, faces);
        mesh.groups.push(group);
    }
    let mut all: Vec<usize> = mesh.elements.iter().flat_map(|e| e.nodes.clone()).collect();
    all.sort_unstable();
    all.dedup();
    assert_eq!(all.len(), mesh.nodes.len(), "every node in an element");
    mesh
}

/// The U-shaped body's arms pressed together: its outer sides moved 0.1 inwards each, twice
/// the slot's width, in four increments, with `contact` (a `[[contact]]` table or nothing).
fn u_model(contact: &str) -> String {
    format!(
        r#"
[[material]]
name = "m"
type = "neo_hooke"
E = 100.0
nu = 0.3
[[body]]
group = "solid"
material = "m"
[[boundary]]
group = "zmin"
fix = ["y", "z"]
[[boundary]]
group = "xmin"
displacement = {{ x = 0.1 }}
[[boundary]]
group = "xmax"
displacement = {{ x = -0.1 }}
{contact}
[[step]]
name = "squeeze"
increments = 4
nlgeom = true
"#
    )
}

/// The largest amount by which a node of the left wall has passed the right wall's face at the
/// same height and depth (`x` of the left node less `x` of the right one), at displacements `u`.
fn crossing(mesh: &Mesh, u: &[f64]) -> f64 {
    let n = [7, 2, 8];
    let x = |a: usize| mesh.nodes[a][0] + u[3 * a];
    let mut worst = f64::NEG_INFINITY;
    for j in 0..=n[1] {
        for k in 2..=n[2] {
            worst = worst.max(x(grid(n, 3, j, k)) - x(grid(n, 4, j, k)));
        }
    }
    worst
}

/// A U-shaped body squeezed shut: without contact its arms pass through each other; with the
/// slot's surface in contact with itself (the penalty and the augmented Lagrangian) they meet and
/// stay apart, and the force is the one of a two-pass pair between the slot's two sides (the
/// slot's bottom faces neither side: its facets face up, the sides sideways).
#[test]
fn a_u_shaped_body_squeezed_shut_does_not_pass_through_itself() {
    let mesh = u_body();
    let an = common::analysis(mesh.clone(), &u_model(""));
    let (_, records) = common::solve(&an);
    let through = crossing(&mesh, &records.last().expect("increments").u);
    println!("no contact: the left wall {through:.4} past the right one");
    assert!(through > 0.05, "without contact the arms cross ({through})");
    for (method, bound) in [("penalty", 2e-3), ("augmented", 1e-5)] {
        let mut forces = Vec::new();
        for pair in [
            "slave = \"slot\"\nmaster = \"slot\"",
            "slave = \"left_wall\"\nmaster = \"right_wall\"\ntwo_pass = true",
        ] {
            let contact = format!("[[contact]]\n{pair}\nmethod = \"{method}\"\npenalty = 2000.0");
            let an = common::analysis(mesh.clone(), &u_model(&contact));
            let (terms, records, _) = common::solve_contact(&an);
            let last = records.last().expect("increments");
            let gap = crossing(&mesh, &last.u);
            let force = common::contact_column(&terms, "_normal_force");
            let depth = common::contact_column(&terms, "_max_penetration");
            println!(
                "{method}, {pair:?}: {} increments, {} iterations, force {force:.9e}, penetration {depth:.3e}, left wall past the right {gap:.3e}",
                records.len(),
                records.iter().map(|r| r.iterations).sum::<usize>()
            );
            assert_eq!(last.load_factor, 1.0, "{method}, {pair}");
            assert!(depth < bound, "{method}, {pair}: penetration {depth}");
            assert!(gap < bound, "{method}, {pair}: crossing {gap}");
            forces.push(force);
        }
        assert!(forces[1] > 1.0, "{method}: the walls press ({forces:?})");
        assert!(
            (forces[0] - forces[1]).abs() <= 1e-6 * forces[1],
            "{method}: {forces:?}"
        );
    }
}

/// What self-contact refuses, each naming its key: two passes, multipliers and `adjust`; and a
/// group holding both faces of a plate one element thick (each face's nodes start behind the
/// other face, which faces them), naming the node.
#[test]
fn self_contact_refuses_two_passes_multipliers_and_adjust() {
    let mesh = two_blocks();
    for (extra, method, key, words) in [
        (
            "two_pass = true",
            "penalty",
            "two_pass",
            "needs no two_pass",
        ),
        ("", "multiplier", "method", "redundant constraints"),
        (
            "adjust = 0.01",
            "augmented",
            "adjust",
            "adjust is not available",
        ),
    ] {
        let pair = format!("slave = \"touching\"\nmaster = \"touching\"\n{extra}");
        let text = format!(
            "[mesh]\nfile = \"unused.msh\"\n{}",
            blocks_model(&pair, method)
        );
        let model = Model::parse(&text, Path::new("self.toml")).expect("valid model");
        let Err(error) = Analysis::new(&model, mesh.clone()) else {
            panic!("{key}: refused");
        };
        let error = error.to_string();
        assert!(
            error.contains("self-contact")
                && error.contains(words)
                && error.contains("self.toml:")
                && error.contains(key),
            "{error}"
        );
    }
    let mut plate =
        tricontact_fem::structured::box_mesh([1.0, 1.0, 0.1], [4, 4, 1], ElementKind::Hex8);
    add_union(&mut plate, "faces", &["zmin", "zmax"]);
    let text = r#"
[mesh]
file = "unused.msh"
[[material]]
name = "m"
type = "linear_elastic"
E = 100.0
nu = 0.3
[[body]]
group = "solid"
material = "m"
[[boundary]]
group = "xmin"
fix = ["x", "y", "z"]
[[contact]]
slave = "faces"
master = "faces"
method = "penalty"
[[step]]
name = "s"
"#;
    let model = Model::parse(text, Path::new("plate.toml")).expect("valid model");
    let Err(error) = Analysis::new(&model, plate) else {
        panic!("the plate's faces: refused");
    };
    let error = error.to_string();
    assert!(
        error.contains("plate.toml:")
            && error.contains("start behind facets of the group that face them, largest 1.000e-1")
            && error.contains("thinner than the search radius"),
        "{error}"
    );
}

/// The crossing check with self-contact: two blocks whose touching faces are one group, the
/// upper block moved down 0.19 in one step (beyond the search radius, the group's longest edge,
/// 0.118): every node of the group is then without a facet, behind a facet of the other block
/// that faces it, and the increment is refused, naming a node and the face it went through. A
/// move of 0.05 (within reach) is accepted, the nodes held.
#[test]
fn a_self_contact_node_pushed_through_in_one_step_is_caught() {
    let base =
        tricontact_fem::structured::box_mesh([1.0, 1.0, 0.5], [12, 12, 1], ElementKind::Hex8);
    let block = tricontact_fem::structured::box_mesh([0.5, 0.5, 1.0], [6, 6, 4], ElementKind::Hex8);
    let mut mesh = tricontact_fem::structured::stack(&base, &block, [0.26, 0.27, 0.51]);
    add_union(&mut mesh, "faces", &["lower_zmax", "upper_zmin"]);
    let upper = mesh
        .groups
        .iter()
        .find(|g| g.name == "upper_solid")
        .expect("block");
    let mut block_nodes: Vec<usize> = upper
        .elements
        .iter()
        .flat_map(|&e| mesh.elements[e].nodes.clone())
        .collect();
    block_nodes.sort_unstable();
    block_nodes.dedup();
    let text = blocks_model("slave = \"faces\"\nmaster = \"faces\"", "penalty");
    let an = common::analysis(mesh.clone(), &text);
    assert!((an.contacts[0].passes[0].radius - 0.5 / 6.0 * 2f64.sqrt()).abs() < 1e-12);
    for (down, through) in [(0.19, true), (0.05, false)] {
        let mut terms = ContactTerms::new(&an);
        let dofs = 3 * mesh.nodes.len() + terms.num_extra();
        terms.begin_increment(&vec![0.0; dofs]).expect("begin");
        let mut u = vec![0.0; dofs];
        for &a in &block_nodes {
            u[3 * a + 2] = -down;
        }
        terms
            .add_terms(&u, &mut vec![0.0; dofs], &mut Vec::new())
            .expect("terms");
        let checked = terms.after_converged(&u);
        println!("moved {down}: {checked:?}");
        match checked {
            Err(e) if through => assert!(
                e.contains("contact 'faces-faces': slave node") && e.contains("went through"),
                "{e}"
            ),
            Ok(_) if !through => {}
            other => panic!("moved {down}: {other:?}"),
        }
    }
}

/// A wedge pressed into a V-groove (the valley example of `contact_valley.rs`), the groove's and
/// the wedge's bottom one group in contact with itself, held as a two-pass pair between them
/// holds it: the same iterations, force and nodes on two flanks (the wedge's nodes on the valley
/// line held by both flanks of the groove), the cutbacks included. (Second flanks, too, must face
/// the node; on this model the kink test leaves no candidate that does not, so the filter is
/// not what this checks.)
#[test]
fn a_v_groove_named_as_one_surface_is_held_as_a_two_pass_pair_holds_it() {
    let mut mesh = common::v_groove([16, 4, 4], [8, 3, 3], ElementKind::Hex8);
    add_union(&mut mesh, "groove", &["lower_zmax", "upper_zmin"]);
    let model = |pair: &str| {
        common::v_groove_model(&format!("{pair}\nmethod = \"penalty\"\npenalty = 2000.0"))
    };
    let mut runs = Vec::new();
    for pair in [
        "slave = \"groove\"\nmaster = \"groove\"",
        "slave = \"upper_zmin\"\nmaster = \"lower_zmax\"\ntwo_pass = true",
    ] {
        let an = common::analysis(mesh.clone(), &model(pair));
        let (terms, records, _) = common::solve_contact(&an);
        let iterations: Vec<usize> = records.iter().map(|r| r.iterations).collect();
        let force = common::contact_column(&terms, "_normal_force");
        let (two, _) = common::second_flanks(&terms);
        println!("{pair:?}: iterations {iterations:?}, force {force:.9e}, {two} on two flanks");
        runs.push((iterations, force, two));
    }
    assert!(
        runs[1].2 >= 4,
        "the valley nodes on two flanks: {}",
        runs[1].2
    );
    assert_eq!(runs[0].0, runs[1].0, "iterations");
    assert_eq!(runs[0].2, runs[1].2, "nodes on two flanks");
    assert!(
        (runs[0].1 - runs[1].1).abs() <= 1e-9 * runs[1].1,
        "forces {} and {}",
        runs[0].1,
        runs[1].1
    );
}
