//! `tricontact export`: the CalculiX deck describes the model's mesh, materials, supports, loads
//! and contact surfaces. The element faces are checked against CalculiX's face definitions as the
//! manual lists them (not against the exporter's own table), and the geometry of the extruded
//! wedges and of the tet10 edge nodes is checked from the coordinates in the deck.

use std::collections::{BTreeSet, HashMap};
use std::path::Path;

use tricontact_fem::analysis::Analysis;
use tricontact_fem::inp;
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::model::Model;
use tricontact_fem::structured::{box_mesh, stack};

/// Keyword blocks of a deck: `(keyword line, data lines)`, comments dropped.
fn blocks(text: &str) -> Vec<(String, Vec<Vec<String>>)> {
    let mut out: Vec<(String, Vec<Vec<String>>)> = Vec::new();
    for line in text.lines() {
        if line.starts_with("**") {
            continue;
        }
        if line.starts_with('*') {
            out.push((line.to_string(), Vec::new()));
        } else if let Some(last) = out.last_mut() {
            last.1
                .push(line.split(',').map(|s| s.trim().to_string()).collect());
        }
    }
    out
}

fn nodes(b: &[(String, Vec<Vec<String>>)]) -> HashMap<usize, [f64; 3]> {
    let mut x = HashMap::new();
    for (k, lines) in b.iter().filter(|(k, _)| k.starts_with("*NODE,")) {
        assert!(k.contains("NSET=NALL"));
        for l in lines {
            let id: usize = l[0].parse().expect("node number");
            let p = [1, 2, 3].map(|i| l[i].parse::<f64>().expect("coordinate"));
            assert!(x.insert(id, p).is_none(), "node {id} written twice");
        }
    }
    x
}

fn elements(b: &[(String, Vec<Vec<String>>)], ty: &str) -> HashMap<usize, Vec<usize>> {
    let mut e = HashMap::new();
    for (_, lines) in b
        .iter()
        .filter(|(k, _)| k.starts_with(&format!("*ELEMENT, TYPE={ty},")))
    {
        for l in lines {
            let v: Vec<usize> = l.iter().map(|s| s.parse().expect("number")).collect();
            e.insert(v[0], v[1..].to_vec());
        }
    }
    e
}

/// `(element, face)` lines of the surface named `name`.
fn surface(b: &[(String, Vec<Vec<String>>)], name: &str) -> Vec<(usize, usize)> {
    let (_, lines) = b
        .iter()
        .find(|(k, _)| k == &format!("*SURFACE, NAME={name}"))
        .unwrap_or_else(|| panic!("surface {name}"));
    lines
        .iter()
        .map(|l| {
            (
                l[0].parse().expect("element"),
                l[1].trim_start_matches('S').parse().expect("face"),
            )
        })
        .collect()
}

/// CalculiX's faces as its manual lists them (1-based local nodes).
fn manual_face(kind: &str, face: usize) -> &'static [usize] {
    match (kind, face) {
        ("C3D8", 1) => &[1, 2, 3, 4],
        ("C3D8", 2) => &[5, 8, 7, 6],
        ("C3D8", 3) => &[1, 5, 6, 2],
        ("C3D8", 4) => &[2, 6, 7, 3],
        ("C3D8", 5) => &[3, 7, 8, 4],
        ("C3D8", 6) => &[4, 8, 5, 1],
        ("C3D4", 1) => &[1, 2, 3],
        ("C3D4", 2) => &[1, 4, 2],
        ("C3D4", 3) => &[2, 4, 3],
        ("C3D4", 4) => &[3, 4, 1],
        ("C3D6", 1) => &[1, 2, 3],
        _ => panic!("no face {face} of {kind}"),
    }
}

fn analysis(text: &str, mesh: tricontact_fem::mesh::Mesh) -> Analysis {
    let model = Model::parse(text, Path::new("m.toml")).expect("model");
    Analysis::new(&model, mesh).expect("analysis")
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[test]
fn hex8_contact_deck_has_the_master_faces_the_slave_nodes_and_the_steps() {
    let lower = box_mesh([1.0, 1.0, 0.2], [6, 6, 2], ElementKind::Hex8);
    let upper = box_mesh([0.9, 0.9, 0.2], [5, 5, 2], ElementKind::Hex8);
    let mesh = stack(&lower, &upper, [0.05, 0.05, 0.2]);
    let text = "[mesh]\nfile = \"none\"\n\
        [[material]]\nname = \"m\"\ntype = \"linear_elastic\"\nE = 1000.0\nnu = 0.3\n\
        [[body]]\ngroup = \"lower_solid\"\nmaterial = \"m\"\n\
        [[body]]\ngroup = \"upper_solid\"\nmaterial = \"m\"\n\
        [[boundary]]\ngroup = \"lower_zmin\"\nfix = [\"x\", \"y\", \"z\"]\n\
        [[boundary]]\ngroup = \"upper_zmax\"\ndisplacement = { x = 0.0, y = 0.0, z = -0.002 }\n\
        [[contact]]\nslave = \"upper_zmin\"\nmaster = \"lower_zmax\"\nmethod = \"multiplier\"\n\
        [[step]]\nincrements = 4\n";
    let an = analysis(text, mesh);
    let deck = inp::write(&an, "two blocks").expect("exportable");
    let b = blocks(&deck.text);
    let x = nodes(&b);
    let hexes = elements(&b, "C3D8");
    assert_eq!(hexes.len(), an.body.len());
    assert_eq!(x.len(), an.active_nodes.iter().filter(|&&a| a).count());
    // Every hexahedron has a positive volume in CalculiX's node order (face S1's listed normal
    // points inwards, towards node 5).
    for v in hexes.values() {
        let p = |i: usize| x[&v[i - 1]];
        assert!(dot(cross(sub(p(2), p(1)), sub(p(4), p(1))), sub(p(5), p(1))) > 0.0);
    }
    // Master faces: the 36 top faces of the lower block, each once, all at z = 0.2.
    let master = surface(&b, "SURF1_M_LOWER_ZMAX");
    assert_eq!(master.len(), 36);
    let mut seen = BTreeSet::new();
    for &(e, f) in &master {
        let corners: BTreeSet<usize> = manual_face("C3D8", f)
            .iter()
            .map(|&i| hexes[&e][i - 1])
            .collect();
        for n in &corners {
            assert!((x[n][2] - 0.2).abs() < 1e-12, "face S{f} of element {e}");
        }
        assert!(seen.insert(corners), "face listed twice");
    }
    // Slave: the node set of the upper block's bottom, as a node surface.
    let slaves: BTreeSet<usize> = an.contacts[0].passes[0]
        .slaves
        .iter()
        .map(|a| a + 1)
        .collect();
    let (_, lines) = b
        .iter()
        .find(|(k, _)| k == "*NSET, NSET=NSURF1_S_UPPER_ZMIN")
        .expect("slave node set");
    let listed: BTreeSet<usize> = lines
        .iter()
        .flatten()
        .map(|s| s.parse().expect("node"))
        .collect();
    assert_eq!(listed, slaves);
    assert!(
        deck.text
            .contains("*SURFACE, NAME=SURF1_S_UPPER_ZMIN, TYPE=NODE\nNSURF1_S_UPPER_ZMIN")
    );
    assert!(deck.text.contains(
        "*CONTACT PAIR, INTERACTION=SI1, TYPE=NODE TO SURFACE\nSURF1_S_UPPER_ZMIN, SURF1_M_LOWER_ZMAX"
    ));
    // Spring slope: α over the slave nodes' smallest tributary area (uniform here: 0.18² / 4 at
    // the corners).
    let pair = &an.contacts[0];
    let least = pair.passes[0]
        .areas
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let (_, behaviour) = b
        .iter()
        .find(|(k, _)| k.starts_with("*SURFACE BEHAVIOR"))
        .expect("surface behaviour");
    let slope: f64 = behaviour[0][0].parse().expect("slope");
    assert!((slope - pair.penalty / least).abs() <= 1e-10 * slope);
    assert!(
        deck.notes
            .iter()
            .any(|n| n.contains("method multiplier exported"))
    );
    // Material and step.
    let (_, elastic) = b.iter().find(|(k, _)| k == "*ELASTIC").expect("elastic");
    let e: f64 = elastic[0][0].parse().expect("E");
    let nu: f64 = elastic[0][1].parse().expect("nu");
    assert!((e - 1000.0).abs() < 1e-9 && (nu - 0.3).abs() < 1e-12);
    assert!(deck.text.contains("*STATIC\n2.500000000000e-1, 1., "));
    assert!(
        deck.text
            .contains("NB2_UPPER_ZMAX, 3, 3, -2.000000000000e-3")
    );
    assert!(deck.text.contains("NB1_LOWER_ZMIN, 1, 1, 0.000000000000e0"));
}

#[test]
fn rigid_flat_becomes_held_wedges_facing_the_slave() {
    let model = Model::load_with_mesh(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/hertz/penalty.toml"),
        Some(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/hertz/hertz-coarse.msh")),
    )
    .expect("model");
    let mesh = tricontact_fem::gmsh::read_msh(&model.mesh_path()).expect("mesh");
    let an = Analysis::new(&model, mesh).expect("analysis");
    let deck = inp::write(&an, "hertz").expect("exportable");
    let b = blocks(&deck.text);
    let x = nodes(&b);
    let wedges = elements(&b, "C3D6");
    let facets = an.contacts[0].passes[0].surface.facets();
    assert_eq!(wedges.len(), facets.len());
    let master = surface(&b, "SURF1_M_FLAT");
    assert_eq!(master.len(), facets.len());
    let flat: BTreeSet<BTreeSet<usize>> = facets
        .iter()
        .map(|f| f.iter().map(|&a| a as usize + 1).collect())
        .collect();
    for (e, f) in master {
        let v = &wedges[&e];
        let p = |i: usize| x[&v[i - 1]];
        // Positive volume; face S1 is a facet of the flat (z = 0) and the wedge lies below it,
        // away from the sphere (z > 0).
        assert!(dot(cross(sub(p(2), p(1)), sub(p(3), p(1))), sub(p(4), p(1))) > 0.0);
        let face: BTreeSet<usize> = manual_face("C3D6", f).iter().map(|&i| v[i - 1]).collect();
        assert!(flat.contains(&face));
        for i in 4..=6 {
            assert!(p(i)[2] < -1e-3, "wedge {e} node {i} at z = {}", p(i)[2]);
        }
    }
    // The extruded nodes are held as the flat's nodes are: all in the flat's support set.
    let (_, lines) = b
        .iter()
        .find(|(k, _)| k == "*NSET, NSET=NB3_FLAT")
        .expect("flat set");
    let held: BTreeSet<usize> = lines
        .iter()
        .flatten()
        .map(|s| s.parse().expect("node"))
        .collect();
    for v in wedges.values() {
        assert!(v.iter().all(|n| held.contains(n)));
    }
    assert!(deck.text.contains("NB3_FLAT, 3, 3, 0.000000000000e0"));
    // The sphere's tetrahedra, all with a positive volume in CalculiX's order.
    let tets = elements(&b, "C3D4");
    assert_eq!(tets.len(), an.body.len());
    for v in tets.values() {
        let p = |i: usize| x[&v[i - 1]];
        assert!(dot(cross(sub(p(2), p(1)), sub(p(3), p(1))), sub(p(4), p(1))) > 0.0);
    }
}

#[test]
fn tet10_edge_nodes_follow_calculix_order_and_neo_hooke_is_noted() {
    let mesh = box_mesh([1.0, 1.0, 1.0], [2, 2, 2], ElementKind::Tet10);
    let text = "[mesh]\nfile = \"none\"\n\
        [[material]]\nname = \"unused\"\ntype = \"linear_elastic\"\nE = 1.0\nnu = 0.3\n\
        [[material]]\nname = \"m\"\ntype = \"neo_hooke\"\nE = 100.0\nnu = 0.25\n\
        [[body]]\ngroup = \"solid\"\nmaterial = \"m\"\n\
        [[boundary]]\ngroup = \"zmin\"\nfix = [\"x\", \"y\", \"z\"]\n\
        [[load]]\ngroup = \"zmax\"\nforce = [0.0, 0.0, -1.0]\n\
        [[step]]\nincrements = 2\nnlgeom = true\n";
    let an = analysis(text, mesh);
    let deck = inp::write(&an, "tet10").expect("exportable");
    let b = blocks(&deck.text);
    let x = nodes(&b);
    let tets = elements(&b, "C3D10");
    assert_eq!(tets.len(), an.body.len());
    // Only the material a body uses is written: its section names the element set written.
    assert!(!deck.text.contains("MAT1") && !deck.text.contains("EMAT1"));
    assert!(
        deck.text.contains("ELSET=EMAT2")
            && deck
                .text
                .contains("*SOLID SECTION, ELSET=EMAT2, MATERIAL=MAT2")
    );
    // CalculiX C3D10: nodes 5–10 on edges 1–2, 2–3, 3–1, 1–4, 2–4, 3–4.
    for v in tets.values() {
        let p = |i: usize| x[&v[i - 1]];
        for (m, (a, c)) in [
            (5, (1, 2)),
            (6, (2, 3)),
            (7, (3, 1)),
            (8, (1, 4)),
            (9, (2, 4)),
            (10, (3, 4)),
        ] {
            for k in 0..3 {
                assert!((p(m)[k] - 0.5 * (p(a)[k] + p(c)[k])).abs() < 1e-12);
            }
        }
    }
    // Neo-Hooke: C10 = μ/2, D1 = 2/K, with a note.
    let (mu, k) = (100.0 / 2.5, 100.0 / 1.5);
    let (_, hyper) = b
        .iter()
        .find(|(k, _)| k == "*HYPERELASTIC, NEO HOOKE")
        .expect("neo-Hooke");
    let c10: f64 = hyper[0][0].parse().expect("C10");
    let d1: f64 = hyper[0][1].parse().expect("D1");
    assert!((c10 - mu / 2.0).abs() < 1e-9 && (d1 - 2.0 / k).abs() < 1e-12);
    assert!(deck.notes.iter().any(|n| n.contains("NEO HOOKE")));
    assert!(deck.text.contains("*STEP, NLGEOM,"));
    // The load as nodal forces summing to the total.
    let (_, cload) = b
        .iter()
        .find(|(k, _)| k == "*CLOAD, OP=NEW")
        .expect("loads");
    let total: f64 = cload
        .iter()
        .filter(|l| l[1] == "3")
        .map(|l| l[2].parse::<f64>().expect("force"))
        .sum();
    assert!((total + 1.0).abs() < 1e-12);
}

#[test]
fn follower_pressure_is_refused_with_its_name() {
    let mesh = box_mesh([1.0, 1.0, 1.0], [2, 2, 2], ElementKind::Hex8);
    let text = "[mesh]\nfile = \"none\"\n\
        [[material]]\nname = \"m\"\ntype = \"neo_hooke\"\nE = 100.0\nnu = 0.25\n\
        [[body]]\ngroup = \"solid\"\nmaterial = \"m\"\n\
        [[boundary]]\ngroup = \"zmin\"\nfix = [\"x\", \"y\", \"z\"]\n\
        [[load]]\ngroup = \"zmax\"\npressure = 1.0\nfollower = true\n\
        [[step]]\nnlgeom = true\n";
    let an = analysis(text, mesh);
    let err = inp::write(&an, "follower").expect_err("follower pressure");
    assert!(err.to_string().contains("load 'zmax'"), "{err}");
}

#[test]
fn every_face_number_matches_the_manual() {
    use tricontact_fem::mesh::Element;
    for (kind, ty, faces) in [
        (ElementKind::Hex8, "C3D8", 6),
        (ElementKind::Tet4, "C3D4", 4),
        (ElementKind::Tet10, "C3D4", 4),
    ] {
        // Distinct, unordered node numbers, so that positions cannot be mistaken for nodes.
        let nodes: Vec<usize> = (0..kind.num_nodes()).map(|i| 100 + 7 * i).collect();
        let el = Element {
            kind,
            nodes: nodes.clone(),
            tag: 1,
        };
        for f in 1..=faces {
            let corners: Vec<usize> = manual_face(ty, f).iter().map(|&i| nodes[i - 1]).collect();
            assert_eq!(inp::calculix_face(&el, &corners), Some(f), "{ty} S{f}");
            // A triangle of a quadrilateral face (two facets per hex face) names the same face.
            assert_eq!(inp::calculix_face(&el, &corners[..3]), Some(f), "{ty} S{f}");
        }
        assert_eq!(inp::calculix_face(&el, &[nodes[0], 5]), None);
    }
}

#[test]
fn a_rigid_surface_in_two_pairs_is_extruded_once() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/hertz/penalty.toml");
    let mut text = std::fs::read_to_string(&path).expect("model");
    text = text.replace(
        "[[step]]",
        "[[contact]]\nslave = \"sym_x\"\nmaster = \"flat\"\nmethod = \"penalty\"\n\n[[step]]",
    );
    let mut model = Model::parse(&text, &path).expect("model");
    model.mesh.file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/hertz/hertz-coarse.msh");
    let mesh = tricontact_fem::gmsh::read_msh(&model.mesh_path()).expect("mesh");
    let an = Analysis::new(&model, mesh).expect("analysis");
    assert_eq!(an.contacts.len(), 2);
    let deck = inp::write(&an, "two pairs").expect("exportable");
    let b = blocks(&deck.text);
    let facets = an.contacts[0].passes[0].surface.len();
    assert_eq!(elements(&b, "C3D6").len(), facets);
    assert!(deck.text.contains("SURF2_S_SYM_X, SURF1_M_FLAT"));
    // Every node of the deck is written once (no second copy of the extruded nodes).
    let x = nodes(&b);
    let flat_nodes: BTreeSet<u32> = an.contacts[0].passes[0]
        .surface
        .facets()
        .iter()
        .flatten()
        .copied()
        .collect();
    assert_eq!(
        x.len(),
        an.active_nodes.iter().filter(|&&a| a).count() + flat_nodes.len()
    );
}

#[test]
fn a_master_face_of_no_element_with_free_nodes_is_refused() {
    use tricontact_fem::mesh::Element;
    let lower = box_mesh([1.0, 1.0, 0.2], [2, 2, 2], ElementKind::Hex8);
    let upper = box_mesh([0.9, 0.9, 0.2], [2, 2, 2], ElementKind::Hex8);
    let mut mesh = stack(&lower, &upper, [0.05, 0.05, 0.2]);
    // A triangle inside the lower block across two elements (its nodes at z = 0.1 are a body's
    // free nodes, and it is no element's face), added to the master group: it can only be
    // exported as a wedge, whose nodes are not held.
    let pick = |x: f64, y: f64| {
        (0..mesh.nodes.len())
            .find(|&a| {
                let p = mesh.nodes[a];
                (p[0] - x).abs() < 1e-9 && (p[1] - y).abs() < 1e-9 && (p[2] - 0.1).abs() < 1e-9
            })
            .expect("grid node")
    };
    mesh.elements.push(Element {
        kind: ElementKind::Tri3,
        nodes: vec![pick(0.0, 0.0), pick(1.0, 0.0), pick(1.0, 1.0)],
        tag: 999_999,
    });
    let index = mesh.elements.len() - 1;
    let g = mesh
        .groups
        .iter_mut()
        .find(|g| g.name == "lower_zmax")
        .expect("group");
    g.elements.push(index);
    let text = "[mesh]\nfile = \"none\"\n\
        [[material]]\nname = \"m\"\ntype = \"linear_elastic\"\nE = 1000.0\nnu = 0.3\n\
        [[body]]\ngroup = \"lower_solid\"\nmaterial = \"m\"\n\
        [[body]]\ngroup = \"upper_solid\"\nmaterial = \"m\"\n\
        [[boundary]]\ngroup = \"lower_zmin\"\nfix = [\"x\", \"y\", \"z\"]\n\
        [[boundary]]\ngroup = \"upper_zmax\"\ndisplacement = { z = -0.002 }\n\
        [[contact]]\nslave = \"upper_zmin\"\nmaster = \"lower_zmax\"\nmethod = \"penalty\"\n\
        [[step]]\n";
    let model = Model::parse(text, Path::new("m.toml")).expect("model");
    let an = Analysis::new(&model, mesh).expect("analysis");
    let err = inp::write(&an, "mixed").expect_err("unheld wedge nodes");
    assert!(err.to_string().contains("surface 'lower_zmax'"), "{err}");
    assert!(err.to_string().contains("not held"), "{err}");
}
