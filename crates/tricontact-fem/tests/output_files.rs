//! The result folder as a whole: a run that fails after an earlier one leaves only the files it
//! wrote itself (no stale `.pvd`, tables or plots of the earlier run), never touching files the
//! program did not name; CSV fields that hold commas, quotes or line breaks are quoted (RFC 4180);
//! a plot that cannot be written, or has nothing to show, fails with a one-line message.

mod common;

use common::CLAMPED_BLOCK;

use std::path::{Path, PathBuf};

use tricontact_fem::analysis::Analysis;
use tricontact_fem::assembly::NoExtra;
use tricontact_fem::driver::{Attempt, Retry, run};
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::output::ResultWriter;
use tricontact_fem::report::{RunRecord, compare_newton, read_newton};
use tricontact_fem::structured::box_mesh;
use tricontact_fem::{FemError, Result};

/// The clamped block pulled at `xmax` in three increments, with plots.
fn model() -> String {
    format!(
        "{CLAMPED_BLOCK}[[load]]\ngroup = \"xmax\"\nforce = [1.0, 0.0, 0.0]\n[[step]]\nname = \"pull\"\nincrements = 3\n[output]\nplots = true\n"
    )
}

fn analysis(model: &str) -> Analysis {
    common::analysis(
        box_mesh([2.0, 1.0, 1.0], [2, 1, 1], ElementKind::Tet4),
        model,
    )
}

fn fresh_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tricontact-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    dir
}

/// Runs like `tricontact run`: results and tables per increment, plots at the end; the run
/// fails (as a diverging increment would) when increment `fail_at` converges.
fn run_into(an: &Analysis, dir: &Path, fail_at: Option<usize>) -> Result<()> {
    let mut writer = ResultWriter::new(an, dir, "m")?;
    let mut record = RunRecord::new(None);
    let summary = run(an, &mut NoExtra, &mut |info| {
        if Some(info.increment) == fail_at {
            return Err(FemError::Output("did not converge".into()));
        }
        writer.write(an, info)?;
        record.record(an, info);
        record.write_tables_if_due(dir)
    });
    writer.finish(an)?;
    record.write_tables(dir)?;
    summary?;
    record.write_plots(dir).map(|_| ())
}

fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn failed_run_leaves_only_its_own_files() {
    let an = analysis(&model());
    let dir = fresh_dir("stale");
    run_into(&an, &dir, None).expect("first run");
    assert!(names(&dir).contains(&"newton.png".to_string()));
    // Files the program does not name, some looking much like its own: kept.
    let others = [
        "history.csv.bak",
        "m.pvd.old",
        "m_notes.txt",
        "mm.pvd",
        "my_history.csv",
        "newton.png.txt",
        "other.pvd",
        "other_001_0001.vtu",
    ];
    for name in others {
        std::fs::write(dir.join(name), "keep").expect("write");
    }
    // Left by a run with a Hertz comparison: also named by the program.
    for name in ["hertz.csv", "hertz_profile.csv", "hertz_pressure.png"] {
        std::fs::write(dir.join(name), "old").expect("write");
    }
    run_into(&an, &dir, Some(2)).expect_err("second run fails");
    let mut expected: Vec<String> = ["history.csv", "m.pvd", "m_001_0001.vtu", "newton.csv"]
        .iter()
        .chain(&others)
        .map(ToString::to_string)
        .collect();
    expected.sort();
    assert_eq!(names(&dir), expected);
    for name in others {
        assert_eq!(
            std::fs::read_to_string(dir.join(name)).expect("kept"),
            "keep"
        );
    }
    let pvd = std::fs::read_to_string(dir.join("m.pvd")).expect("pvd");
    assert!(pvd.contains("m_001_0001.vtu") && !pvd.contains("m_001_0002.vtu"));
    let history = std::fs::read_to_string(dir.join("history.csv")).expect("history");
    assert_eq!(history.lines().count(), 2, "{history}");
    let newton = std::fs::read_to_string(dir.join("newton.csv")).expect("newton");
    assert!(
        newton.lines().skip(1).all(|l| l.starts_with("1,1,")),
        "{newton}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The attempts of the increment a run stopped on follow its converged increments in
/// `newton.csv`, numbered as the next increment of their step; an error that is not a step's
/// failure to converge adds nothing.
#[test]
fn the_attempts_a_run_stopped_on_follow_its_increments() {
    let an = analysis(&model());
    let dir = fresh_dir("stopped-attempts");
    let mut record = RunRecord::new(None);
    run(&an, &mut NoExtra, &mut |info| {
        record.record(&an, info);
        Ok(())
    })
    .expect("the run converges");
    let attempt = |target, retry| Attempt {
        target,
        reason: format!("no convergence at {target}"),
        retry,
        relative: vec![1.0, 0.5, 0.4],
        solve_starts: vec![0],
        notes: Vec::new(),
    };
    let stop = FemError::NotConverged {
        step: "pull".into(),
        load_factor: 1.0,
        target: 1.25,
        reason: "no convergence".into(),
        exhausted: "after 1 cutback".into(),
        attempts: vec![attempt(1.5, Retry::CutBack), attempt(1.25, Retry::CutBack)],
    };
    record.record_failure(&an, &FemError::Output("disk full".into()));
    record.record_failure(&an, &stop);
    record.write_tables(&dir).expect("tables");
    let logs = read_newton(&dir).expect("newton.csv");
    let summary: Vec<(usize, usize, f64, &str)> = logs
        .iter()
        .map(|l| (l.step, l.increment, l.load_factor, l.outcome.as_str()))
        .collect();
    assert_eq!(summary.len(), 5, "{summary:?}");
    assert!(
        summary[..3].iter().all(|s| s.3 == "converged"),
        "{summary:?}"
    );
    assert_eq!(
        summary[3..],
        [
            (0, 4, 1.5, "cut back: no convergence at 1.5"),
            (0, 4, 1.25, "failed: no convergence at 1.25")
        ]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run whose first increment fails still writes `history.csv`: its header, no row.
#[test]
fn a_run_failing_at_its_first_increment_writes_the_history_header() {
    let an = analysis(&model());
    let dir = fresh_dir("first-fails");
    run_into(&an, &dir, Some(1)).expect_err("the run fails");
    assert_eq!(names(&dir), ["history.csv", "newton.csv"]);
    let history = std::fs::read_to_string(dir.join("history.csv")).expect("history");
    assert_eq!(history.lines().count(), 1, "{history}");
    assert!(
        history.starts_with("step,step_name,increment,"),
        "{history}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_without_history_or_vtu_removes_the_earlier_ones() {
    let an = analysis(&model());
    let dir = fresh_dir("stale-off");
    run_into(&an, &dir, None).expect("first run");
    let mut quiet = an.clone();
    quiet.output.vtu = false;
    quiet.output.history = false;
    quiet.output.plots = false;
    let mut writer = ResultWriter::new(&quiet, &dir, "m").expect("writer");
    run(&quiet, &mut NoExtra, &mut |info| writer.write(&quiet, info)).expect("run");
    assert!(names(&dir).is_empty(), "{:?}", names(&dir));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_result_folder_that_is_a_file_is_named() {
    let an = analysis(&model());
    let dir = fresh_dir("folder-file");
    let file = dir.join("results");
    std::fs::write(&file, "not a folder").expect("file");
    let Err(e) = ResultWriter::new(&an, &file, "m") else {
        panic!("a file accepted as the result folder");
    };
    let e = e.to_string();
    assert!(e.contains("results: exists and is not a folder"), "{e}");
    assert_eq!(
        std::fs::read_to_string(&file).expect("kept"),
        "not a folder"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Splits RFC 4180 text into records of fields (quoted fields may hold commas, `""` and line
/// breaks).
fn parse_csv(text: &str) -> Vec<Vec<String>> {
    let (mut rows, mut row, mut field) = (Vec::new(), Vec::new(), String::new());
    let (mut quoted, mut chars) = (false, text.chars().peekable());
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                field.push('"');
            }
            (true, '"') => quoted = false,
            (true, c) => field.push(c),
            (false, '"') if field.is_empty() => quoted = true,
            (false, ',') => row.push(std::mem::take(&mut field)),
            (false, '\n') => {
                row.push(std::mem::take(&mut field));
                rows.push(std::mem::take(&mut row));
            }
            (false, c) => field.push(c),
        }
    }
    assert!(
        !quoted && field.is_empty() && row.is_empty(),
        "unterminated"
    );
    rows
}

#[test]
fn names_with_commas_quotes_and_line_breaks_are_quoted() {
    let mut an = analysis(&model().replace("\"pull\"", "\"bend, phase 1\""));
    an.boundaries[0].name = "clamp,left".into();
    let mut second = an.boundaries[0].clone();
    second.name = "say \"hi\"\nthere".into();
    an.boundaries.push(second);
    let dir = fresh_dir("quoted");
    run_into(&an, &dir, None).expect("run");
    let text = std::fs::read_to_string(dir.join("history.csv")).expect("history");
    assert!(
        text.starts_with(
            "step,step_name,increment,load_factor,time,iterations,residual,relative_residual,\
             \"clamp,left_Rx\",\"clamp,left_Ry\",\"clamp,left_Rz\",\"say \"\"hi\"\"\nthere_Rx\","
        ),
        "{text}"
    );
    let rows = parse_csv(&text);
    assert_eq!(rows.len(), 4);
    assert_eq!(
        rows[0][8..11],
        ["clamp,left_Rx", "clamp,left_Ry", "clamp,left_Rz"]
    );
    assert_eq!(rows[0][11], "say \"hi\"\nthere_Rx");
    for row in &rows {
        assert_eq!(row.len(), 14, "{row:?}");
    }
    assert!(rows[1..].iter().all(|r| r[1] == "bend, phase 1"));
    assert!(text.contains("\n1,\"bend, phase 1\",1,"), "{text}");
    let newton = std::fs::read_to_string(dir.join("newton.csv")).expect("newton");
    assert!(parse_csv(&newton).iter().all(|r| r.len() == 7));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A result folder whose `newton.csv` holds `residuals` for increment 1 of step 1.
fn newton_folder(tag: &str, residuals: &[&str]) -> PathBuf {
    let dir = fresh_dir(tag);
    let mut csv =
        String::from("step,increment,load_factor,solve,iteration,relative_residual,outcome\n");
    for (k, r) in residuals.iter().enumerate() {
        csv.push_str(&format!("1,1,1,1,{k},{r},converged\n"));
    }
    std::fs::write(dir.join("newton.csv"), csv).expect("write");
    dir
}

#[test]
fn plot_errors_name_the_file_and_the_reason() {
    let dir = newton_folder("plot-errors", &["1", "1e-3", "1e-9"]);
    let folders = [dir.clone()];
    let missing = dir.join("missing").join("p.png");
    let e = compare_newton(&folders, None, &missing)
        .expect_err("no folder")
        .to_string();
    let want = format!(
        "cannot write plot {}: No such file or directory",
        missing.display()
    );
    assert!(e.ends_with(&want), "{e}");
    let txt = dir.join("p.txt");
    let e = compare_newton(&folders, None, &txt)
        .expect_err("not png")
        .to_string();
    let want = format!(
        "cannot write plot {}: the file name must end in .png",
        txt.display()
    );
    assert!(e.ends_with(&want), "{e}");
    assert!(!txt.exists() && !dir.join("p.tmp.txt").exists());
    let png = dir.join("p.png");
    compare_newton(&folders, None, &png).expect("plot");
    assert_eq!(&std::fs::read(&png).expect("png")[1..4], b"PNG");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn nothing_to_plot_is_an_error() {
    let dir = newton_folder("plot-empty", &["NaN", "0", "-1e-3", "inf"]);
    let png = dir.join("p.png");
    let e = compare_newton(std::slice::from_ref(&dir), None, &png)
        .expect_err("nothing to plot")
        .to_string();
    let file = dir.join("newton.csv");
    assert!(
        e.contains(&file.display().to_string()) && e.contains("nothing to plot"),
        "{e}"
    );
    assert!(!png.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The iteration column must count 0, 1, … within each increment: a non-numeric or out-of-order
/// value is a malformed row, named by line (it used to be skipped unread).
#[test]
fn newton_rows_out_of_sequence_are_malformed() {
    for (tag, bad) in [
        ("x", "1,1,1,1,x,1e-3,converged"),
        ("gap", "1,1,1,1,2,1e-3,converged"),
        ("start", "1,2,1,1,1,1e-3,converged"),
    ] {
        let dir = newton_folder(&format!("plot-seq-{tag}"), &["1"]);
        let file = dir.join("newton.csv");
        let mut text = std::fs::read_to_string(&file).expect("csv");
        text.push_str(bad);
        text.push('\n');
        std::fs::write(&file, text).expect("write");
        let e = compare_newton(std::slice::from_ref(&dir), None, &dir.join("p.png"))
            .expect_err("malformed")
            .to_string();
        assert!(
            e.contains(&format!("{}:3: malformed row '{bad}'", file.display())),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// `newton.csv` must start with its header (a file without one would lose its first row), may end
/// with a blank line, and increments count from 1; the default increment is the last by step and
/// increment, not by file order.
#[test]
fn newton_csv_header_blank_lines_and_last_increment() {
    let dir = newton_folder("plot-header", &["1", "1e-3"]);
    let file = dir.join("newton.csv");
    let good = std::fs::read_to_string(&file).expect("csv");
    let png = dir.join("p.png");
    let plot = |text: &str| {
        std::fs::write(&file, text).expect("write");
        compare_newton(std::slice::from_ref(&dir), None, &png).map_err(|e| e.to_string())
    };
    let e =
        plot(good.lines().skip(1).collect::<Vec<_>>().join("\n").as_str()).expect_err("no header");
    assert!(e.contains(":1: expected the header"), "{e}");
    plot(&format!("{good}\n\n")).expect("trailing blank lines");
    let e = plot(&format!("{good}2,0,1,1,0,1,converged\n")).expect_err("increment 0");
    assert!(
        e.contains(":4: malformed row '2,0,1,1,0,1,converged'"),
        "{e}"
    );
    // Step 2 written before step 1 (which has nothing to plot): the default is step 2.
    let rows = "step,increment,load_factor,solve,iteration,relative_residual,outcome\n\
                2,1,1,1,0,1,converged\n2,1,1,1,1,1e-6,converged\n\
                1,1,1,1,0,0,converged\n1,1,1,1,1,0,converged\n";
    plot(rows).expect("step 2 has something to plot");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run that fails after increments whose `.vtu` `output.every` skipped still leaves the last
/// converged state to open (it left only the tables), listed in the `.pvd`, with every converged
/// row in the tables.
#[test]
fn a_failed_run_keeps_its_last_converged_state() {
    let text = model().replace("increments = 3", "increments = 6") + "every = 4\n";
    let an = analysis(&text);
    let dir = fresh_dir("every-fail");
    run_into(&an, &dir, Some(3)).expect_err("the run fails");
    let mut expected = ["history.csv", "m.pvd", "m_001_0002.vtu", "newton.csv"];
    expected.sort_unstable();
    assert_eq!(names(&dir), expected);
    let pvd = std::fs::read_to_string(dir.join("m.pvd")).expect("pvd");
    assert!(pvd.contains("m_001_0002.vtu"), "{pvd}");
    let history = std::fs::read_to_string(dir.join("history.csv")).expect("history");
    assert_eq!(history.lines().count(), 3, "{history}");
    let _ = std::fs::remove_dir_all(&dir);
}
