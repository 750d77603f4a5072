//! Every kind of bad input gives its own clear error, never a panic or a
//! NaN result: malformed TOML, unknown group, missing mesh file,
//! unsupported element type, unsupported body, inverted and zero-volume
//! elements.
#![allow(clippy::needless_range_loop)]

use std::path::{Path, PathBuf};

use tricontact_fem::assembly::NoExtra;
use tricontact_fem::{FemError, analysis::Analysis, driver, gmsh, load_analysis, model::Model};

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tricontact-bad-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// A one-element Gmsh 4.1 ASCII mesh: physical volume "solid" (tag 1) and
/// physical surface "base" (tag 2, empty).
fn msh(element_type: u32, nodes: &[[f64; 3]]) -> String {
    let mut s = String::from(
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 2 \"base\"\n3 1 \"solid\"\n$EndPhysicalNames\n$Entities\n0 0 1 1\n1 0 0 0 1 1 0 1 2 0\n1 0 0 0 1 1 1 1 1 0\n$EndEntities\n",
    );
    let n = nodes.len();
    s += &format!("$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n");
    for i in 1..=n {
        s += &format!("{i}\n");
    }
    for p in nodes {
        s += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    s += &format!("$EndNodes\n$Elements\n1 1 1 1\n3 1 {element_type} 1\n1");
    for i in 1..=n {
        s += &format!(" {i}");
    }
    s += "\n$EndElements\n";
    s
}

const TET: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];

fn model_text(body_group: &str, extra: &str) -> String {
    format!(
        "[mesh]\nfile = \"m.msh\"\n[[material]]\nname = \"m\"\ntype = \"linear_elastic\"\nE = 1.0\nnu = 0.3\n[[body]]\ngroup = \"{body_group}\"\nmaterial = \"m\"\n{extra}[[step]]\n"
    )
}

fn setup(name: &str, mesh: &str, model: &str) -> PathBuf {
    let d = temp_dir(name);
    std::fs::write(d.join("m.msh"), mesh).expect("write mesh");
    std::fs::write(d.join("model.toml"), model).expect("write model");
    d.join("model.toml")
}

#[test]
fn malformed_toml_reports_line_and_column() {
    let p = setup(
        "toml",
        &msh(4, &TET),
        "[mesh]\nfile = \"m.msh\"\n\n[[material]\nname = \"x\"\n",
    );
    let e = Model::load(&p).expect_err("malformed");
    let msg = e.to_string();
    assert!(matches!(e, FemError::ModelSyntax { .. }));
    assert!(
        msg.starts_with("invalid model: ") && msg.contains(".toml:4:"),
        "{msg}"
    );
    // Wrong value type, with position too.
    let p = setup(
        "toml2",
        &msh(4, &TET),
        &model_text("solid", "").replace("E = 1.0", "E = \"stiff\""),
    );
    let msg = Model::load(&p).expect_err("type").to_string();
    assert!(msg.contains(".toml:6:5: "), "{msg}");
}

#[test]
fn unknown_group_lists_the_existing_groups() {
    let p = setup("group", &msh(4, &TET), &model_text("solidd", ""));
    let e = load_analysis(&p).expect_err("unknown group");
    let msg = e.to_string();
    assert!(matches!(e, FemError::UnknownGroup { .. }), "{msg}");
    assert!(
        msg.contains("'solidd'") && msg.contains("solid (3D)") && msg.contains("base (2D)"),
        "{msg}"
    );
}

#[test]
fn missing_mesh_file_names_the_path_and_the_model_line() {
    let d = temp_dir("missing");
    let p = d.join("model.toml");
    std::fs::write(&p, model_text("solid", "").replace("m.msh", "nowhere.msh")).expect("write");
    let e = load_analysis(&p).expect_err("missing mesh");
    assert!(matches!(e, FemError::Invalid(_)), "{e}");
    // Reported at the model's `[mesh] file` line.
    let text = std::fs::read_to_string(&p).expect("model");
    let line = 1 + text
        .lines()
        .position(|l| l.contains("nowhere.msh"))
        .expect("the file line");
    let msg = e.to_string();
    assert!(
        msg.contains(&format!("model.toml:{line}: mesh ")) && msg.contains("nowhere.msh"),
        "{msg}"
    );
}

/// A model path that is not a regular file (a device, a folder) is refused before it is read:
/// `/dev/zero` was read until memory ran out.
#[test]
fn a_model_path_that_is_not_a_file_is_refused() {
    let d = temp_dir("model-not-file");
    for path in [d.as_path(), Path::new("/dev/zero")] {
        if !path.exists() {
            continue;
        }
        let e = Model::load(path).expect_err("not a file");
        assert!(
            matches!(e, FemError::ModelSyntax { .. })
                && e.to_string()
                    .ends_with("not a regular file (a model is a .toml file)"),
            "{e}"
        );
    }
}

#[test]
fn unsupported_element_type_is_named() {
    let prism = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
    ];
    let e = gmsh::parse_msh(msh(6, &prism).as_bytes(), Path::new("p.msh")).expect_err("prism");
    assert!(matches!(e, FemError::UnsupportedElement { .. }));
    assert!(
        e.to_string().contains("Pri6") && e.to_string().contains("solid"),
        "{e}"
    );
}

#[test]
fn body_without_supports_is_reported_singular() {
    let p = setup("free", &msh(4, &TET), &model_text("solid", ""));
    let an: Analysis = load_analysis(&p).expect("valid model");
    let e = driver::run(&an, &mut NoExtra, &mut |_| Ok(())).expect_err("singular");
    assert!(matches!(e, FemError::Singular(_)), "{e}");
    assert!(
        e.to_string()
            .contains("6 unconstrained rigid-body mode(s); add supports"),
        "{e}"
    );
    // Partially supported: a single fixed node leaves the 3 rotations free.
    let mesh = gmsh::parse_msh(msh(4, &TET).as_bytes(), Path::new("m.msh")).expect("mesh");
    let mut an = Analysis::new(
        &Model::parse(&model_text("solid", ""), Path::new("m.toml")).expect("model"),
        mesh,
    )
    .expect("analysis");
    an.boundaries.push(tricontact_fem::analysis::Boundary {
        name: "pin".into(),
        nodes: vec![0],
        values: [Some(0.0); 3],
        active: vec![true],
    });
    let e = driver::run(&an, &mut NoExtra, &mut |_| Ok(())).expect_err("singular");
    assert!(
        e.to_string().contains("3 unconstrained rigid-body mode"),
        "{e}"
    );
}

#[test]
fn inverted_element_is_reported() {
    let mut nodes = TET;
    nodes.swap(1, 2);
    let p = setup("inverted", &msh(4, &nodes), &model_text("solid", ""));
    let e = load_analysis(&p).expect_err("inverted");
    assert!(matches!(e, FemError::InvertedElement { tag: 1, .. }), "{e}");
}

/// A volume element that names a node twice (a corner lost) is refused by the reader and by
/// [`Mesh::check`], naming the element and the node by their Gmsh tags: a hexahedron collapsed
/// that way kept positive Jacobians and split the mesh without a word. The message of an
/// inverted element names the mesh file and the element by its Gmsh tag alone (it gave the
/// internal index as well).
#[test]
fn an_element_naming_a_node_twice_is_refused() {
    let hex: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            let (x, y) = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)][i % 4];
            [x, y, (i / 4) as f64]
        })
        .collect();
    let good = msh(5, &hex);
    let line = "\n1 1 2 3 4 5 6 7 8\n";
    assert!(good.contains(line));
    let bad = good.replace(line, "\n1 1 2 3 4 5 6 7 7\n");
    let e = gmsh::parse_msh(bad.as_bytes(), Path::new("b.msh")).expect_err("repeated node");
    assert!(
        e.to_string()
            .contains("element 1 (Hex8) names node 7 twice"),
        "{e}"
    );
    let mut mesh = gmsh::parse_msh(good.as_bytes(), Path::new("g.msh")).expect("good");
    mesh.check().expect("valid");
    mesh.node_tags = (1..=8).map(|t| 10 * t).collect();
    mesh.elements[0].nodes[7] = mesh.elements[0].nodes[0];
    let e = mesh.check().expect_err("repeated node");
    assert!(
        e.to_string()
            .contains("element 1 (Hex8) names node 10 twice"),
        "{e}"
    );
    let mut nodes = TET;
    nodes.swap(1, 2);
    let p = setup(
        "inverted-message",
        &msh(4, &nodes),
        &model_text("solid", ""),
    );
    let e = load_analysis(&p).expect_err("inverted");
    assert!(
        e.to_string().starts_with("mesh ")
            && e.to_string()
                .contains("/m.msh: element 1 is inverted: Jacobian determinant"),
        "{e}"
    );
}

#[test]
fn zero_volume_element_is_reported() {
    let mut nodes = TET;
    nodes[3] = [0.5, 0.5, 0.0];
    let p = setup("flat", &msh(4, &nodes), &model_text("solid", ""));
    let e = load_analysis(&p).expect_err("flat");
    assert!(matches!(e, FemError::ZeroVolume { tag: 1, .. }), "{e}");
}

#[test]
fn several_problems_are_all_listed() {
    let extra = "[[boundary]]\ngroup = \"nope\"\nfix = [\"x\"]\n[[load]]\ngroup = \"solid\"\npressure = 1.0\n";
    let p = setup(
        "many",
        &msh(4, &TET),
        &model_text("solid", extra).replace("nu = 0.3", "nu = 0.7"),
    );
    let e = load_analysis(&p).expect_err("invalid");
    let msg = e.to_string();
    assert!(
        msg.contains("nu") && msg.contains("'nope'") && msg.contains("pressure needs a surface"),
        "{msg}"
    );
}

#[test]
fn old_msh_format_and_garbage_are_rejected_clearly() {
    let old = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
    let e = gmsh::parse_msh(old.as_bytes(), Path::new("old.msh")).expect_err("2.2");
    assert!(e.to_string().contains("4.1"), "{e}");
    let e = gmsh::parse_msh(b"hello", Path::new("x.msh")).expect_err("garbage");
    assert!(e.to_string().contains("not a Gmsh mesh"), "{e}");
    let truncated = &msh(4, &TET)[..200];
    let e = gmsh::parse_msh(truncated.as_bytes(), Path::new("t.msh")).expect_err("truncated");
    assert!(matches!(e, FemError::Mesh { .. }), "{e}");
    assert!(!e.to_string().contains('\n'), "one line: {e}");
    assert!(e.to_string().contains("is it complete?"), "{e}");
}

/// A `$Nodes` header whose node count is absurd (a corrupt or hand-edited file) is an error, not
/// an allocation of that many tags (which aborted the process) or a capacity overflow (a panic).
#[test]
fn an_absurd_node_count_in_the_header_is_an_error() {
    let good = msh(4, &TET);
    assert!(good.contains("$Nodes\n1 4 1 4\n"), "{good}");
    for count in ["999999999999999", "18446744073709551615", "1000000000"] {
        let bad = good.replace("$Nodes\n1 4 1 4\n", &format!("$Nodes\n1 {count} 1 4\n"));
        let e = gmsh::parse_msh(bad.as_bytes(), Path::new("n.msh")).expect_err(count);
        assert!(matches!(e, FemError::Mesh { .. }), "{count}: {e}");
        assert!(
            e.to_string().contains(&format!(
                "the $Nodes header counts {count} nodes but its blocks hold 4"
            )),
            "{e}"
        );
    }
    let bad = good.replace("$Elements\n1 1 1 1\n", "$Elements\n1 2 1 1\n");
    let e = gmsh::parse_msh(bad.as_bytes(), Path::new("e.msh")).expect_err("elements");
    assert!(
        e.to_string()
            .contains("the $Elements header counts 2 elements but its blocks hold 1"),
        "{e}"
    );
    // A block claiming more nodes than the file holds: `3 n` would overflow.
    let bad = good.replace("3 1 0 4\n", "3 1 0 9223372036854775807\n");
    let e = gmsh::parse_msh(bad.as_bytes(), Path::new("b.msh")).expect_err("block");
    assert!(matches!(e, FemError::Mesh { .. }), "{e}");
    // The walk that recovers the node tags, on its own (the reader refuses these files before it
    // runs): it gives up on them instead of reserving the header's count (which aborted the
    // process) or overflowing on the block's.
    let tags = |text: &str| tricontact_fem::gmsh_nodes::node_tags(text.as_bytes());
    assert_eq!(tags(&good), Some(vec![1, 2, 3, 4]));
    for count in ["999999999999999", "18446744073709551615"] {
        let bad = good.replace("$Nodes\n1 4 1 4\n", &format!("$Nodes\n1 {count} 1 4\n"));
        assert_eq!(tags(&bad), None, "{count}");
    }
    assert_eq!(tags(&bad), None, "block");
}

#[test]
fn values_that_would_give_nan_or_never_end_are_rejected_by_key() {
    // model_text ends with a bare `[[step]]`: its keys follow.
    let extra = "[[material]]\nname = \"tiny\"\ntype = \"linear_elastic\"\nE = 1e-200\nnu = 0.3\n\
                 [[body]]\ngroup = \"solid\"\nmaterial = \"m\"\n\
                 [[load]]\ngroup = \"base\"\npressure = nan\n\
                 [[load]]\ngroup = \"solid\"\nforce = [0.0, inf, 0.0]\n\
                 [[contact]]\nslave = \"solid\"\nmaster = \"base\"\nmethod = \"penalty\"\n\
                 [[contact]]\nslave = \"solid\"\nmaster = \"base\"\nmethod = \"penalty\"\n";
    let steps = "name = \"a\"\nmax_cutbacks = 1000\nresidual_tolerance = 0.0\n\
                 [[step]]\nname = \"a\"\nincrements = 0\n[[step]]\nname = \" \"\n\
                 [[boundary]]\ngroup = \"solid\"\ndisplacement = { x = 1.0 }\n\
                 [[boundary]]\ngroup = \"solid\"\ndisplacement = { x = 2.0 }\n\
                 [output]\nfolder = \"\"\n";
    let text = model_text("solid", extra).replace("E = 1.0", "E = inf") + steps;
    let text = text.replacen("nu = 0.3", "nu = 1e300", 1)
        + "[[material]]\nname = \" \"\ntype = \"linear_elastic\"\nE = 1.0\nnu = 0.3\n";
    let p = setup("nan", &msh(4, &TET), &text);
    let msg = load_analysis(&p).expect_err("invalid").to_string();
    for expected in [
        "material 'm': need 1e-100 < E < 1e100 and -1 < nu < 0.5 (got E = inf, nu = 1e300)",
        "material 'tiny': need 1e-100 < E < 1e100 and -1 < nu < 0.5 (got E = 1e-200",
        "body group 'solid' is listed twice",
        "load 'base': non-finite pressure",
        "load 'solid': non-finite force",
        "contact 'solid-base' is defined twice",
        "step name 'a' is used twice",
        "step 'a': max_cutbacks must be from 0 to 30 (got 1000)",
        "step 'a': residual_tolerance must be > 0 and < 1 (got 0)",
        "step 'a': increments must be from 1 to 1000000 (got 0)",
        "step 3: the name is empty",
        "material 3: the name is empty",
        "boundaries 1 ('solid') and 2 ('solid') prescribe different values on 4 node component(s), the first at node",
        "output.folder is empty",
    ] {
        assert!(msg.contains(expected), "missing «{expected}» in {msg}");
    }
    assert_eq!(msg.matches("invalid model").count(), 1, "{msg}");
}

#[test]
fn overlapping_bodies_are_reported_once_per_pair() {
    let extra = "[[body]]\ngroup = \"other\"\nmaterial = \"m\"\n[[boundary]]\ngroup = \"solid\"\nfix = [\"x\", \"y\", \"z\"]\n";
    // The volume entity in two physical groups: the same element under another name.
    let mesh = msh(4, &TET)
        .replace("$PhysicalNames\n2\n", "$PhysicalNames\n3\n3 3 \"other\"\n")
        .replace("1 0 0 0 1 1 1 1 1 0", "1 0 0 0 1 1 1 2 1 3 0");
    let p = setup("overlap", &mesh, &model_text("solid", extra));
    let msg = load_analysis(&p).expect_err("overlap").to_string();
    assert!(
        msg.contains("bodies 'solid' and 'other' share 1 element(s) (the first: Gmsh tag 1)"),
        "{msg}"
    );
}

#[test]
fn an_unresolved_body_is_reported_without_knock_on_errors() {
    let extra = "[[boundary]]\ngroup = \"solid\"\nfix = [\"x\"]\n[[load]]\ngroup = \"base\"\npressure = 1.0\n";
    let text = model_text("solid", extra).replace("material = \"m\"", "material = \"steel\"");
    // The pressure's surface holds a face of the tet (an empty one is a problem of its own).
    let mesh = msh(4, &TET).replace(
        "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n",
        "$Elements\n2 2 1 2\n3 1 4 1\n1 1 2 3 4\n2 1 2 1\n2 1 2 3\n",
    );
    assert!(mesh.contains("2 1 2 3\n"), "{mesh}");
    let p = setup("knock-on", &mesh, &text);
    let msg = load_analysis(&p).expect_err("unknown material").to_string();
    assert!(
        msg.contains("body 'solid': unknown material 'steel' (materials: m)"),
        "{msg}"
    );
    assert!(
        !msg.contains("no node of any body") && !msg.contains(';'),
        "one problem: {msg}"
    );
}

#[test]
fn a_name_used_in_two_dimensions_is_resolved_by_need_or_reported() {
    // "solid" names the volume (3D, tag 1) and a surface (2D, tag 2), as Gmsh allows.
    let mesh = msh(4, &TET).replace("2 2 \"base\"", "2 2 \"solid\"");
    // A body needs a volume: it takes the 3D group (it used to take the 2D one and fail).
    let fixed = "[[boundary]]\ngroup = \"solid\"\nfix = [\"x\", \"y\", \"z\"]\n";
    let p = setup("two-dims", &mesh, &model_text("solid", fixed));
    let msg = load_analysis(&p).expect_err("ambiguous").to_string();
    assert!(!msg.contains("dimension 2"), "{msg}");
    // A node set could be either: the boundary is refused, naming the dimensions.
    assert!(
        msg.contains("boundary: group 'solid' is ambiguous")
            && msg.contains("in 2D and 3D; give them different names"),
        "{msg}"
    );
}

/// `$PhysicalNames` that Gmsh would not write: one name for two groups of a dimension (a
/// reference to it would silently take the first), a group named twice, or a count that does not
/// match the lines. Each is an error naming the file and what is wrong.
#[test]
fn inconsistent_physical_names_are_rejected() {
    let cases = [
        (
            "$PhysicalNames\n3\n2 2 \"base\"\n2 3 \"base\"\n",
            "physical name 'base' is given to two 2D groups (tags 2 and 3)",
        ),
        (
            "$PhysicalNames\n3\n2 2 \"base\"\n2 2 \"top\"\n",
            "the 2D physical group 2 is named twice",
        ),
        ("$PhysicalNames\n3\n", "announces 3 names but lists 2"),
        ("$PhysicalNames\n1\n", "announces 1 names but lists more"),
    ];
    for (k, (header, expected)) in cases.into_iter().enumerate() {
        let mesh = msh(4, &TET).replacen("$PhysicalNames\n2\n", header, 1);
        let p = setup(&format!("names-{k}"), &mesh, &model_text("solid", ""));
        let msg = load_analysis(&p).expect_err("bad names").to_string();
        assert!(
            msg.contains(expected) && msg.contains("m.msh"),
            "{header:?}: {msg}"
        );
    }
}

/// A key given twice is named, with its line and column (the parser's message names none).
#[test]
fn a_duplicate_key_is_named() {
    for (text, expected) in [
        (
            "[mesh]\nfile = \"a.msh\"\nfile = \"b.msh\"\n",
            "m.toml:3:1: duplicate key `file`",
        ),
        (
            "[mesh]\nfile = \"a.msh\"\n[mesh]\n",
            "m.toml:3:2: duplicate key `mesh`",
        ),
    ] {
        let e = tricontact_fem::model::Model::parse(text, std::path::Path::new("m.toml"))
            .expect_err("duplicate")
            .to_string();
        assert!(e.contains(expected), "{e}");
    }
}

/// An invalid material is reported once, by its key: a contact pair on its body does not add a
/// default-penalty problem that blames a modulus the user never gave (`E = NaN` from `nu = 0.5`).
#[test]
fn an_invalid_material_gives_no_knock_on_default_penalty_problem() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/contact-block");
    let d = temp_dir("penalty-knock-on");
    std::fs::copy(example.join("blocks.msh"), d.join("blocks.msh")).expect("copy mesh");
    let text = std::fs::read_to_string(example.join("model.toml")).expect("read model");
    assert_eq!(
        text.matches("nu = 0.3").count(),
        2,
        "both materials give nu"
    );
    // The base (master) material, then the block (slave) material.
    for (which, name) in [(0, "base"), (1, "block")] {
        let mut parts: Vec<&str> = text.split("nu = 0.3").collect();
        let bad = format!("{}nu = 0.5{}", parts[which], parts[which + 1]);
        parts.splice(which..=which + 1, [bad.as_str()]);
        let model = parts.join("nu = 0.3");
        std::fs::write(d.join("model.toml"), &model).expect("write model");
        let msg = load_analysis(&d.join("model.toml"))
            .expect_err("invalid material")
            .to_string();
        assert!(
            msg.contains(&format!(
                "material '{name}': need 1e-100 < E < 1e100 and -1 < nu < 0.5"
            )),
            "{msg}"
        );
        assert!(!msg.contains("default penalty"), "knock-on problem: {msg}");
        assert!(!msg.contains("NaN"), "{msg}");
    }
}

/// Groups that resolve but hold nothing, or hold the wrong things, are named: a pressure on an
/// empty surface group (it was dropped silently), a body on an empty volume group (its supports and
/// loads were blamed instead), a face listed twice in a pressure group (its pressure counted
/// twice), and volume elements in a surface entity (they made the body empty).
#[test]
fn empty_repeated_and_misplaced_group_contents_are_named() {
    let pressure = "[[boundary]]\ngroup = \"solid\"\nfix = [\"x\", \"y\", \"z\"]\n[[load]]\ngroup = \"base\"\npressure = 1.0\n";
    let p = setup(
        "empty-pressure",
        &msh(4, &TET),
        &model_text("solid", pressure),
    );
    let msg = load_analysis(&p).expect_err("empty").to_string();
    assert!(
        msg.contains("load 'base': the surface group has no faces"),
        "{msg}"
    );

    let ghost = msh(4, &TET).replace("$PhysicalNames\n2\n", "$PhysicalNames\n3\n3 7 \"ghost\"\n");
    let p = setup("empty-body", &ghost, &model_text("ghost", ""));
    let msg = load_analysis(&p).expect_err("empty body").to_string();
    assert!(
        msg.contains("body 'ghost': the volume group has no elements"),
        "{msg}"
    );

    // The tet and, in the surface entity of "base", its face 1 2 3 twice (in either orientation).
    let twice = msh(4, &TET).replace(
        "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n",
        "$Elements\n2 3 1 3\n3 1 4 1\n1 1 2 3 4\n2 1 2 2\n2 1 3 2\n3 3 2 1\n",
    );
    assert!(twice.contains("3 3 2 1"), "{twice}");
    let p = setup("twice", &twice, &model_text("solid", pressure));
    let msg = load_analysis(&p).expect_err("twice").to_string();
    assert!(
        msg.contains("load 'base': elements 2 and 3 (Gmsh tags) are the same face"),
        "{msg}"
    );

    let misplaced = msh(4, &TET).replace("\n3 1 4 1\n", "\n2 1 4 1\n");
    let e = gmsh::parse_msh(misplaced.as_bytes(), Path::new("m.msh")).expect_err("misplaced");
    assert!(
        e.to_string().contains(
            "an element block of the 2D entity 1 (group 'base') holds Tet4 elements, which are 3D"
        ),
        "{e}"
    );
}

/// A load on a triangle that no body element has as a face: a pressure names the face, a force
/// the nodes of no body; `follower` on a force is named too.
#[test]
fn loads_off_every_body_and_a_follower_force_are_named() {
    let mut mesh = msh(4, &TET)
        .replace("$Nodes\n1 4 1 4\n3 1 0 4\n", "$Nodes\n1 7 1 7\n3 1 0 7\n")
        .replace("4\n0 0 0\n", "4\n5\n6\n7\n0 0 0\n")
        .replace(
            "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n",
            "$Elements\n2 2 1 2\n3 1 4 1\n1 1 2 3 4\n2 1 2 1\n2 5 6 7\n",
        );
    mesh = mesh.replace("0 0 1\n$EndNodes", "0 0 1\n5 0 0\n6 0 0\n5 1 0\n$EndNodes");
    assert!(
        mesh.contains("2 5 6 7") && mesh.contains("5 1 0\n$EndNodes"),
        "{mesh}"
    );
    let fixed = "[[boundary]]\ngroup = \"solid\"\nfix = [\"x\", \"y\", \"z\"]\n";
    for (name, load, expected) in [
        (
            "off-pressure",
            "pressure = 1.0",
            "load 'base': face 2 is not on the surface of a body",
        ),
        (
            "off-force",
            "force = [0.0, 0.0, 1.0]",
            "load 'base': applied to nodes of no body",
        ),
        (
            "follower-force",
            "force = [0.0, 0.0, 1.0]\nfollower = true",
            "load 'base': `follower` applies to a pressure only",
        ),
    ] {
        let extra = format!("{fixed}[[load]]\ngroup = \"base\"\n{load}\n");
        let p = setup(name, &mesh, &model_text("solid", &extra));
        let msg = load_analysis(&p).expect_err(name).to_string();
        assert!(msg.contains(expected), "{msg}");
    }
}

/// An element naming a node the `$Nodes` section does not define, and a face element in a curve
/// (1D) entity of a physical group, are named.
#[test]
fn an_unknown_node_and_a_face_in_a_curve_entity_are_named() {
    let unknown = msh(4, &TET).replace("\n1 1 2 3 4\n", "\n1 1 2 3 99\n");
    let e = gmsh::parse_msh(unknown.as_bytes(), Path::new("m.msh")).expect_err("unknown node");
    assert!(
        e.to_string()
            .contains("element 1 refers to unknown node 99"),
        "{e}"
    );
    let curve = msh(4, &TET)
        .replace("$PhysicalNames\n2\n", "$PhysicalNames\n3\n1 3 \"edge\"\n")
        .replace(
            "$Entities\n0 0 1 1\n",
            "$Entities\n0 1 1 1\n1 0 0 0 1 1 0 1 3 0\n",
        )
        .replace(
            "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n",
            "$Elements\n2 2 1 5\n3 1 4 1\n1 1 2 3 4\n1 1 2 1\n5 1 2 3\n",
        );
    assert!(curve.contains("5 1 2 3"), "{curve}");
    let e = gmsh::parse_msh(curve.as_bytes(), Path::new("m.msh")).expect_err("face in a curve");
    assert!(
        e.to_string().contains(
            "an element block of the 1D entity 1 (group 'edge') holds Tri3 elements, which are 2D"
        ),
        "{e}"
    );
}

/// A displacement is a table of components; an array (whose fourth value was ignored) is refused
/// with the line of the key.
#[test]
fn a_displacement_array_is_refused() {
    let extra = "[[boundary]]\ngroup = \"solid\"\ndisplacement = [0.1, 0.2, 0.3, 0.4]\n";
    let e = Model::parse(&model_text("solid", extra), Path::new("m.toml")).expect_err("array");
    let msg = e.to_string();
    assert!(msg.contains("m.toml:13:"), "{msg}");
    assert!(msg.contains("a table of components"), "{msg}");
}

/// An empty `[mesh] file` is named as such (it read the model's folder and said only
/// ": No such file or directory").
#[test]
fn an_empty_mesh_file_is_named() {
    let text = model_text("solid", "").replace("file = \"m.msh\"", "file = \"\"");
    let e = Model::parse(&text, Path::new("m.toml")).expect_err("empty file");
    assert!(
        e.to_string().contains("m.toml:2: [mesh] file is empty"),
        "{e}"
    );
}

/// A mesh path that is not a regular file is refused before it is read (`/dev/zero` was read until
/// memory ran out), and a byte-order mark before `$MeshFormat` is skipped.
#[test]
fn a_mesh_that_is_not_a_file_is_refused_and_a_byte_order_mark_is_skipped() {
    let d = temp_dir("not-a-file");
    let e = gmsh::read_msh(&d).expect_err("a folder");
    assert!(e.to_string().contains("not a regular file"), "{e}");
    #[cfg(unix)]
    {
        let e = gmsh::read_msh(Path::new("/dev/zero")).expect_err("a device");
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }
    let plain = gmsh::parse_msh(msh(4, &TET).as_bytes(), Path::new("m.msh")).expect("plain");
    let marked = [b"\xEF\xBB\xBF".as_slice(), msh(4, &TET).as_bytes()].concat();
    let marked = gmsh::parse_msh(&marked, Path::new("m.msh")).expect("with a byte-order mark");
    assert_eq!(plain.nodes, marked.nodes);
    assert!(plain.elements == marked.elements);
}

/// A `steps` list that names no step, or one step twice, is named (the first made a load or a
/// support that never acts, silently).
#[test]
fn empty_or_repeated_step_lists_are_named() {
    let extra = "[[boundary]]\ngroup = \"solid\"\nfix = [\"x\", \"y\", \"z\"]\nsteps = []\n[[load]]\ngroup = \"solid\"\nforce = [1.0, 0.0, 0.0]\nsteps = [\"a\", \"a\"]\n";
    let text = model_text("solid", extra) + "name = \"a\"\n";
    let p = setup("steps-lists", &msh(4, &TET), &text);
    let msg = load_analysis(&p).expect_err("steps").to_string();
    assert!(
        msg.contains("boundary 'solid': `steps = []` names no step, so it would never act"),
        "{msg}"
    );
    assert!(
        msg.contains("load 'solid': step 'a' is listed twice"),
        "{msg}"
    );
}

/// A coordinate so large that element volumes overflow is named with its node (the element was
/// reported as of zero or NaN volume instead).
#[test]
fn an_overflowing_coordinate_names_its_node() {
    let mut nodes = TET;
    nodes[2][1] = 1e300;
    let e = gmsh::parse_msh(msh(4, &nodes).as_bytes(), Path::new("m.msh")).expect_err("huge");
    assert!(
        e.to_string()
            .contains("node 3 has a coordinate beyond ±1e100"),
        "{e}"
    );
}

/// A component listed twice in `fix` is named (it was accepted, as a slip for another component
/// would be).
#[test]
fn a_component_fixed_twice_is_named() {
    let extra = "[[boundary]]\ngroup = \"solid\"\nfix = [\"x\", \"y\", \"x\"]\n";
    let p = setup("fix-twice", &msh(4, &TET), &model_text("solid", extra));
    let msg = load_analysis(&p).expect_err("fix twice").to_string();
    assert!(
        msg.contains("boundary 'solid': component x is listed twice in `fix`"),
        "{msg}"
    );
}

/// A mesh built by other code than the Gmsh reader is checked as the reader checks its own: a NaN
/// coordinate, an element with a node out of range or too few nodes, a group naming a missing
/// node are errors that name them (they passed, or panicked with an index out of bounds).
#[test]
fn a_mesh_built_in_code_is_checked_like_a_read_one() {
    use tricontact_fem::analysis::Analysis;
    use tricontact_fem::mesh::ElementKind;
    use tricontact_fem::model::Model;
    use tricontact_fem::structured::box_mesh;
    let text = model_text(
        "solid",
        "[[boundary]]\ngroup = \"xmin\"\nfix = [\"x\", \"y\", \"z\"]\n",
    );
    let text = format!("{text}\n").replace("file = \"m.msh\"", "file = \"unused.msh\"");
    let model = Model::parse(&text, std::path::Path::new("m.toml")).expect("model");
    let good = box_mesh([1.0, 1.0, 1.0], [1, 1, 1], ElementKind::Hex8);
    assert!(Analysis::new(&model, good.clone()).is_ok());
    let tag = good.node_tags[3];
    let mut nan = good.clone();
    nan.nodes[3][1] = f64::NAN;
    let mut out_of_range = good.clone();
    out_of_range.elements[0].nodes[2] = 99;
    let element = good.elements[0].tag;
    let mut short = good.clone();
    short.elements[0].nodes.truncate(3);
    let mut group = good.clone();
    group.groups[0].nodes.push(99);
    let name = good.groups[0].name.clone();
    let mut group_element = good.clone();
    group_element.groups[0].elements.push(42);
    let mut untagged = good.clone();
    untagged.node_tags.pop();
    for (mesh, expected) in [
        (nan, format!("node {tag} has a non-finite coordinate")),
        (
            out_of_range,
            format!("element {element} names node index 99 of 8"),
        ),
        (short, "has 3 nodes, not 8".to_string()),
        (group, format!("group '{name}' names node index 99 of 8")),
        (
            group_element,
            format!("group '{name}' names element index 42"),
        ),
        (untagged, "7 node tags for 8 nodes".to_string()),
    ] {
        let msg = Analysis::new(&model, mesh)
            .expect_err("bad mesh")
            .to_string();
        assert!(msg.contains(&expected), "{msg}");
    }
}

/// A problem found after parsing (a value out of range, a name that matches nothing) starts with
/// the model file and the line of the key at fault, as a compiler's message does.
#[test]
fn problems_found_after_parsing_name_the_line_of_their_key() {
    let extra = "[[boundary]]\ngroup = \"base\"\nfix = [\"x\"]\nsteps = [\"nope\"]\n";
    let text = model_text("solidd", extra)
        .replace("nu = 0.3", "nu = 0.7")
        .replace("[[step]]\n", "[[step]]\nname = \"s\"\nincrements = 0\n");
    let p = setup("lines", &msh(4, &TET), &text);
    let line_of = |key: &str| {
        1 + text
            .lines()
            .position(|l| l.starts_with(key))
            .expect("key in the text")
    };
    let e = load_analysis(&p).expect_err("several problems");
    let messages = e.messages();
    let expect = [
        (line_of("nu ="), "material 'm': need"),
        (
            line_of("group = \"solidd\""),
            "unknown volume group 'solidd'",
        ),
        (line_of("steps ="), "boundary 'base': unknown step 'nope'"),
        (line_of("increments ="), "step 's': increments must be"),
    ];
    for (line, what) in expect {
        let start = format!("{}:{line}: {what}", p.display());
        assert!(
            messages.iter().any(|m| m.starts_with(&start)),
            "{start} in {messages:#?}"
        );
    }
    // Two boundaries in conflict: the second one's header. A load given both a force and a
    // pressure is told so, whatever their values.
    let extra = "[[boundary]]\ngroup = \"solid\"\nfix = [\"x\"]\n\
                 [[boundary]]\ngroup = \"solid\"\ndisplacement = { x = 1.0 }\n\
                 [[load]]\ngroup = \"base\"\nforce = [0.0, nan, 0.0]\npressure = 1.0\n";
    let text = model_text("solid", extra);
    let p = setup("lines-clash", &msh(4, &TET), &text);
    let messages = load_analysis(&p).expect_err("clash").messages();
    let second = 1 + text
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == "[[boundary]]")
        .nth(1)
        .expect("two boundaries")
        .0;
    let load = 1 + text.lines().position(|l| l == "[[load]]").expect("load");
    for start in [
        format!(
            "{}:{second}: step 'step-1': boundaries 1 ('solid') and 2 ('solid') prescribe different values",
            p.display()
        ),
        format!(
            "{}:{load}: load 'base': give exactly one of `force` or `pressure`",
            p.display()
        ),
    ] {
        assert!(
            messages.iter().any(|m| m.starts_with(&start)),
            "{start} in {messages:#?}"
        );
    }
    // A modulus out of range points at the modulus, by whichever name it is given.
    for (from, to) in [
        ("E = 1.0", "E = -1.0"),
        ("E = 1.0", "youngs_modulus = -1.0"),
    ] {
        let text = model_text("solid", "").replace(from, to);
        let p = setup("lines-modulus", &msh(4, &TET), &text);
        let msg = load_analysis(&p).expect_err("bad modulus").to_string();
        let start = format!("invalid model: {}:6: material 'm'", p.display());
        assert!(msg.starts_with(&start), "{msg}");
    }
}

/// A material that no body uses is not an error, but it is noted, with its line: most often a
/// body was given the wrong one.
#[test]
fn an_unused_material_is_noted_with_its_line() {
    let text = model_text("solid", "").replace(
        "[[body]]",
        "[[material]]\nname = \"spare\"\ntype = \"neo_hooke\"\nE = 2.0\nnu = 0.3\n[[body]]",
    );
    let p = setup("unused-material", &msh(4, &TET), &text);
    let model = Model::load(&p).expect("model");
    let mesh = gmsh::read_msh(&model.mesh_path()).expect("mesh");
    let an = Analysis::new(&model, mesh).expect("a valid model");
    let line = 1 + text
        .lines()
        .position(|l| l == "name = \"spare\"")
        .expect("spare");
    assert_eq!(
        an.notes(),
        [format!(
            "{}:{line}: material 'spare' is used by no body",
            p.display()
        )]
    );
}

/// A line the Gmsh parser cannot read is named by its number (in an ASCII file), whichever
/// section it is in.
#[test]
fn a_malformed_mesh_line_is_named_by_its_number() {
    let good = msh(4, &TET);
    let lines: Vec<&str> = good.lines().collect();
    let at = |needle: &str| 1 + lines.iter().position(|l| *l == needle).expect(needle);
    for (from, to) in [
        ("0 1 0", "0 x 0"),                             // a node's coordinates
        ("3 1 4 1", "3 1 4 one"),                       // an element block's header
        ("1 4 1 4", "1 4 1 four"),                      // the $Nodes header
        ("1 0 0 0 1 1 1 1 1 0", "1 0 0 0 1 1 1 1 q 0"), // a volume entity
    ] {
        let line = at(from);
        let bad = good.replacen(&format!("\n{from}\n"), &format!("\n{to}\n"), 1);
        assert_ne!(bad, good, "{from}");
        let e = gmsh::parse_msh(bad.as_bytes(), Path::new("l.msh")).expect_err(to);
        let msg = e.to_string();
        assert!(matches!(e, FemError::Mesh { .. }), "{msg}");
        assert!(
            msg.contains(&format!("reading stopped at line {line}: ")),
            "{to}: {msg}"
        );
        assert!(!msg.contains('\n'), "one line: {msg}");
    }
}

/// A repeated line (one more than a section's header counts, or a stray line between sections) is
/// named by where reading stopped, with the likely cause: the parser's own message says only
/// "Unknown error occurred".
#[test]
fn a_repeated_mesh_line_is_reported_with_its_likely_cause() {
    let good = msh(4, &TET);
    for line in [
        "$EndMeshFormat",
        "0 1 0",
        "1 0 0 0 1 1 1 1 1 0",
        "1 1 2 3 4",
    ] {
        let bad = good.replacen(&format!("\n{line}\n"), &format!("\n{line}\n{line}\n"), 1);
        assert_ne!(bad, good, "{line}");
        let e = gmsh::parse_msh(bad.as_bytes(), Path::new("r.msh")).expect_err(line);
        let msg = e.to_string();
        assert!(
            msg.contains("reading stopped at line ")
                && msg.contains("holds more or fewer lines than its headers count"),
            "{line}: {msg}"
        );
        assert!(!msg.contains('\n'), "one line: {msg}");
    }
}

/// In a binary file the place is a byte offset (lines mean nothing there).
#[test]
fn a_malformed_binary_mesh_is_named_by_its_byte() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/beam_binary.msh");
    let bytes = std::fs::read(path).expect("binary mesh");
    let start = bytes
        .windows(9)
        .position(|w| w == b"$Elements")
        .expect("$Elements");
    let cut = &bytes[..start + 30];
    let e = gmsh::parse_msh(cut, Path::new("b.msh")).expect_err("cut short");
    let msg = e.to_string();
    assert!(msg.contains("reading stopped at byte "), "{msg}");
    assert!(!msg.contains("line"), "{msg}");
}
