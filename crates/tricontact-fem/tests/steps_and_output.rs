//! Multi-step semantics and result files: a prescribed stretch released in
//! a second step unloads linearly (the released reaction ramps to zero), a
//! load switched off ramps down, and `[output] every` / `vtu` / `history`
//! control what is written.

mod common;

use common::CLAMPED_BLOCK;

use tricontact_fem::assembly::NoExtra;
use tricontact_fem::driver::run;
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::output::ResultWriter;
use tricontact_fem::structured::box_mesh;

#[test]
fn released_displacement_unloads_linearly() {
    let text = format!(
        "{CLAMPED_BLOCK}[[boundary]]\ngroup = \"xmax\"\ndisplacement = {{ x = 0.2 }}\nsteps = [\"pull\"]\n[[step]]\nname = \"pull\"\n[[step]]\nname = \"release\"\nincrements = 4\n"
    );
    let an = common::analysis(
        box_mesh([2.0, 1.0, 1.0], [4, 2, 2], ElementKind::Hex8),
        &text,
    );
    let (_, rec) = common::solve(&an);
    assert_eq!(rec.len(), 5);
    let pulled = &rec[0].u;
    let scale = pulled.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!((scale - 0.2).abs() < 1e-12);
    for r in &rec[1..] {
        let remaining = 1.0 - r.load_factor;
        let err =
            r.u.iter()
                .zip(pulled)
                .fold(0.0f64, |m, (a, b)| m.max((a - remaining * b).abs()));
        assert!(err <= 1e-9 * scale, "t = {}: error {err:e}", r.load_factor);
        // The clamp carries what the released face still transmits.
        let rx = r.reactions[0][0];
        assert!(
            (rx - remaining * rec[0].reactions[0][0]).abs() <= 1e-8 * rec[0].reactions[0][0].abs()
        );
    }
}

#[test]
fn every_vtu_and_history_switches() {
    let text = format!(
        "{CLAMPED_BLOCK}[[load]]\ngroup = \"xmax\"\nforce = [1.0, 0.0, 0.0]\n[[step]]\nname = \"a\"\nincrements = 3\n[output]\nevery = 2\n"
    );
    let an = common::analysis(
        box_mesh([2.0, 1.0, 1.0], [2, 1, 1], ElementKind::Tet4),
        &text,
    );
    let dir = std::env::temp_dir().join(format!("tricontact-every-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    // Left over from an earlier run: removed. Unrelated files: kept.
    // Names past the padding (increment 10000, step 1000) too.
    for old in ["m_001_0007.vtu", "m_001_10000.vtu", "m_1000_0001.vtu"] {
        std::fs::write(dir.join(old), "old").expect("write");
    }
    std::fs::write(dir.join("notes_001_0007.vtu"), "keep").expect("write");
    let mut w = ResultWriter::new(&an, &dir, "m").expect("writer");
    run(&an, &mut NoExtra, &mut |info| w.write(&an, info)).expect("run");
    w.finish(&an).expect("finish");
    std::fs::remove_file(dir.join("notes_001_0007.vtu")).expect("unrelated file kept");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["history.csv", "m.pvd", "m_001_0002.vtu", "m_001_0003.vtu"]
    );
    let history = std::fs::read_to_string(dir.join("history.csv")).expect("history");
    assert_eq!(history.lines().count(), 4);

    let mut an2 = an.clone();
    an2.output.vtu = false;
    an2.output.history = false;
    let dir2 = dir.with_extension("none");
    let _ = std::fs::remove_dir_all(&dir2);
    let mut w = ResultWriter::new(&an2, &dir2, "m").expect("writer");
    run(&an2, &mut NoExtra, &mut |info| w.write(&an2, info)).expect("run");
    w.finish(&an2).expect("finish");
    assert_eq!(std::fs::read_dir(&dir2).expect("dir").count(), 0);
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&dir2);
}

#[test]
fn fully_prescribed_model_needs_no_solve() {
    let mesh = box_mesh([1.0, 1.0, 1.0], [1, 1, 1], ElementKind::Hex8);
    let all: Vec<usize> = (0..mesh.nodes.len()).collect();
    let mut an = common::analysis(
        mesh,
        "[[material]]\nname = \"m\"\ntype = \"neo_hooke\"\nE = 1.0\nnu = 0.3\n[[body]]\ngroup = \"solid\"\nmaterial = \"m\"\n[[step]]\nnlgeom = true\nincrements = 2\n",
    );
    common::prescribe_field(&mut an, &all, |x| [0.5 * x[1], 0.0, 0.0]);
    let (summary, rec) = common::solve(&an);
    assert_eq!(summary.increments, 2);
    let total: f64 = rec
        .last()
        .expect("converged")
        .reactions
        .iter()
        .map(|r| r[0])
        .sum();
    assert!(
        total.abs() < 1e-12,
        "reactions of a free-standing shear balance: {total}"
    );
}

/// A block carried by its support without strain, in many increments: every increment after the
/// first starts, extrapolated, exactly at its answer, with round-off for residual and no force to
/// compare it with. It converges, small strain and finite strain alike, and stays unstrained.
#[test]
fn a_rigid_translation_converges_in_every_increment() {
    for (law, nlgeom) in [("linear_elastic", false), ("neo_hooke", true)] {
        let text = format!(
            "[[material]]\nname = \"m\"\ntype = \"{law}\"\nE = 210e3\nnu = 0.3\n[[body]]\ngroup = \"solid\"\nmaterial = \"m\"\n[[boundary]]\ngroup = \"xmin\"\ndisplacement = {{ x = 0.1, y = -0.05, z = 0.02 }}\n[[step]]\nincrements = 6\nnlgeom = {nlgeom}\n"
        );
        let an = common::analysis(
            box_mesh([2.0, 1.0, 1.0], [4, 2, 2], ElementKind::Hex8),
            &text,
        );
        let (summary, rec) = common::solve(&an);
        assert_eq!((summary.increments, summary.cutbacks), (6, 0), "{law}");
        for r in &rec {
            let want = [0.1, -0.05, 0.02].map(|v| v * r.load_factor);
            for (i, v) in r.u.iter().enumerate() {
                assert!((v - want[i % 3]).abs() <= 1e-12, "{law}: u[{i}] = {v}");
            }
        }
    }
}
