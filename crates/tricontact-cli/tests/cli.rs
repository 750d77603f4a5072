//! End-to-end tests of the `tricontact` binary on the committed example.

use std::path::{Path, PathBuf};
use std::process::Command;

use tricontact_fem::report::{NewtonLog, read_newton};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tricontact"))
}

fn example() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cantilever/model.toml")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tricontact-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

#[test]
fn run_writes_vtu_pvd_and_history() {
    let out = temp_dir("run");
    let o = bin()
        .args([
            "run",
            example().to_str().expect("utf8"),
            "--verbose",
            "--output",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("step 1 'bend' inc   1"), "{stdout}");
    assert!(stdout.contains("done: 6 increments"), "{stdout}");
    // No contact pair, so no per-iteration contact notes.
    assert!(!stdout.contains("contact:"), "{stdout}");
    let history = std::fs::read_to_string(out.join("history.csv")).expect("history");
    let rows: Vec<&str> = history.lines().collect();
    assert_eq!(rows.len(), 7, "{history}");
    assert!(rows[0].starts_with("step,step_name,increment,load_factor"));
    assert!(rows[0].contains("clamp_Ry"));
    // Clamp reaction balances tip force (50) plus pressure (2 × 10 × 1) at the end of step 1.
    let cols: Vec<&str> = rows[4].split(',').collect();
    let ry: f64 = cols[9].parse().expect("number");
    assert!((ry - 70.0).abs() < 1e-6, "{}", rows[4]);
    let pvd = std::fs::read_to_string(out.join("model.pvd")).expect("pvd");
    assert_eq!(pvd.matches("<DataSet").count(), 6);
    let vtu = std::fs::read_to_string(out.join("model_001_0004.vtu")).expect("vtu");
    assert!(vtu.contains("NumberOfPoints=\"189\"") && vtu.contains("NumberOfCells=\"80\""));
    assert!(
        std::fs::read_dir(&out).expect("dir").all(|e| !e
            .expect("entry")
            .path()
            .to_string_lossy()
            .contains(".tmp"))
    );
}

#[test]
fn check_prints_summary() {
    let o = bin()
        .args(["check", example().to_str().expect("utf8")])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}");
    assert!(stdout.contains("nodes: 189"), "{stdout}");
    assert!(stdout.contains("hex8") && stdout.contains("80"), "{stdout}");
    assert!(
        stdout.contains("567 DOFs") && stdout.contains("540 free DOFs"),
        "{stdout}"
    );
    assert!(
        stdout.contains("nlgeom = true, line_search = \"auto\""),
        "{stdout}"
    );
    assert!(stdout.contains("no problems found"), "{stdout}");
}

#[test]
fn failures_exit_non_zero_with_one_line() {
    let d = temp_dir("bad");
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cantilever/beam.msh");
    std::fs::copy(mesh, d.join("beam.msh")).expect("copy");
    let good = std::fs::read_to_string(example()).expect("model");
    let cases = [
        (
            "syntax.toml",
            good.replace("[[body]]", "[[body]"),
            "syntax.toml:",
        ),
        (
            "group.toml",
            good.replace("group = \"tip\"", "group = \"tipp\""),
            "clamp (2D)",
        ),
        (
            "unsupported.toml",
            good.replace("fix = [\"x\", \"y\", \"z\"]", "fix = [\"x\"]"),
            "rigid-body",
        ),
        (
            "key.toml",
            good.replace("nlgeom = true", "nlgoem = true"),
            "nlgoem",
        ),
    ];
    for (name, text, needle) in cases {
        let p = d.join(name);
        std::fs::write(&p, text).expect("write");
        let cmd = if name == "unsupported.toml" {
            "run"
        } else {
            "check"
        };
        let mut c = bin();
        c.args([cmd, p.to_str().expect("utf8")]);
        if cmd == "run" {
            c.arg("--output").arg(d.join("out"));
        }
        let o = c.output().expect("runs");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name} should fail");
        assert_eq!(stderr.lines().count(), 1, "{name}: {stderr}");
        assert!(
            stderr.starts_with("error: ") && stderr.contains(needle),
            "{name}: {stderr}"
        );
    }
    let o = bin()
        .args(["run", d.join("absent.toml").to_str().expect("utf8")])
        .output()
        .expect("runs");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("absent.toml"));
}

#[test]
fn tet10_example_reactions_balance_the_pressure() {
    let out = temp_dir("block");
    let model =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/block-stretch/model.toml");
    let o = bin()
        .args(["run", model.to_str().expect("utf8"), "--output"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(
        o.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let history = std::fs::read_to_string(out.join("history.csv")).expect("history");
    let header: Vec<&str> = history.lines().next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect("column");
    let last: Vec<f64> = history
        .lines()
        .last()
        .expect("row")
        .split(',')
        .enumerate()
        .filter(|(i, _)| *i != 1)
        .map(|(_, v)| v.parse().expect("number"))
        .collect();
    // Column indices shift by one after dropping step_name (index 1).
    let get = |name: &str| last[col(name) - 1];
    // Dead pressure 0.5 on the 2 × 1 top face pushes with 1.0 in −z.
    let rz = get("left_Rz") + get("right_Rz");
    assert!((rz - 1.0).abs() < 1e-6, "ΣRz = {rz}");
    let rx = get("left_Rx") + get("right_Rx");
    assert!(
        rx.abs() < 1e-6 * get("right_Rx").abs().max(1.0),
        "ΣRx = {rx}"
    );
    assert!(get("right_Rx") > 0.0, "stretching needs a positive force");
}

#[test]
fn contact_example_checks() {
    let model =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/contact-block/model.toml");
    let o = bin()
        .args(["check", model.to_str().expect("utf8")])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout} {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("no problems found"), "{stdout}");
}

/// The self-contact example: `check` says the pair is self-contact, and `export` refuses it in
/// one line, writing nothing.
#[test]
fn self_contact_example_checks_and_is_not_exported() {
    let model = examples_dir().join("self-contact/model.toml");
    let stdout = run_ok(&["check".as_ref(), model.as_os_str()]);
    assert!(
        stdout.contains("contact slot-slot: augmented, 235 slave nodes, 396 facets, self-contact, facing facets only")
            && stdout.contains("no problems found"),
        "{stdout}"
    );
    let out = temp_dir("self-export").join("clip.inp");
    let o = bin()
        .args([
            "export".as_ref(),
            model.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("contact 'slot-slot': self-contact (slave = master) is not exported"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(!out.exists());
}

fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn run_ok(args: &[&std::ffi::OsStr]) -> String {
    let o = bin().args(args).output().expect("runs");
    assert!(
        o.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn hertz_coarse_writes_tables_plots_and_summary() {
    let out = temp_dir("hertz");
    let ex = examples_dir().join("hertz");
    let mut runs = Vec::new();
    for method in ["multiplier", "penalty"] {
        let dir = out.join(method);
        let stdout = run_ok(&[
            "run".as_ref(),
            ex.join(format!("{method}.toml")).as_os_str(),
            "--mesh".as_ref(),
            ex.join("hertz-coarse.msh").as_os_str(),
            "--output".as_ref(),
            dir.as_os_str(),
        ]);
        assert!(stdout.contains("hertz: force"), "{stdout}");
        assert!(
            stdout.contains("contact contact-flat: normal force"),
            "{stdout}"
        );
        for f in [
            "hertz.csv",
            "hertz_profile.csv",
            "newton.csv",
            "newton.png",
            "contact_force.png",
            "hertz_pressure.png",
            "hertz_force_approach.png",
        ] {
            assert!(dir.join(f).is_file(), "{method}: {f} missing");
        }
        let table = std::fs::read_to_string(dir.join("hertz.csv")).expect("hertz.csv");
        assert_eq!(table.lines().count(), 9, "header + 8 increments");
        runs.push(dir);
    }
    // `plot` overlays one increment of both runs; a missing increment is an error naming it.
    let png = out.join("compare.png");
    let stdout = run_ok(&[
        "plot".as_ref(),
        runs[0].as_os_str(),
        runs[1].as_os_str(),
        "--increment".as_ref(),
        "1:8".as_ref(),
        "--output".as_ref(),
        png.as_os_str(),
    ]);
    assert!(stdout.contains("wrote"), "{stdout}");
    assert_eq!(&std::fs::read(&png).expect("png")[1..4], b"PNG");
    let o = bin()
        .args([
            "plot".as_ref(),
            runs[0].as_os_str(),
            "--increment".as_ref(),
            "1:99".as_ref(),
        ])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("no converged increment 99 of step 1"),
        "{stderr}"
    );
    let o = bin()
        .args([
            "plot".as_ref(),
            runs[0].as_os_str(),
            "--increment".as_ref(),
            "8".as_ref(),
        ])
        .output()
        .expect("runs");
    assert!(!o.status.success());
    let o = bin()
        .args(["plot".as_ref(), out.join("nothing").as_os_str()])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("newton.csv"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&out).ok();
}

/// `tricontact CMD MODEL`: whether it succeeded, its stdout and stderr together, its stderr.
fn outcome(cmd: &str, model: &Path) -> (bool, String, String) {
    let o = bin()
        .args([cmd.as_ref(), model.as_os_str()])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    let text = format!("{}{stderr}", String::from_utf8_lossy(&o.stdout));
    (o.status.success(), text, stderr)
}

#[test]
fn hertz_table_errors_name_the_key() {
    let out = temp_dir("hertz-bad");
    let ex = examples_dir().join("hertz");
    let text = std::fs::read_to_string(ex.join("multiplier.toml")).expect("model");
    let mesh = ex.join("hertz-coarse.msh");
    let base = text.replace(
        "file = \"hertz-fine.msh\"",
        &format!("file = {:?}", mesh.to_str().expect("utf8")),
    );
    // Each case: the change, the message, and the line it must point at (the first line that
    // starts with the given text; `None`: a schema error, at the first line that starts with
    // the unknown key, column 1).
    for (from, to, expect, key) in [
        (
            "loaded = \"top\"",
            "loaded = \"lid\"",
            "[hertz] loaded: unknown group 'lid'",
            Some("loaded ="),
        ),
        (
            "radius = 20.0",
            "radius = -20.0",
            "[hertz] radius must be finite and > 0 (got -20)",
            Some("radius ="),
        ),
        (
            "radius = 20.0",
            "radius = 20.0\nradious = 1.0",
            "unknown field `radious`",
            None,
        ),
        (
            "radius = 20.0",
            "radius = 20.0\ncentre = [nan, 0.0, 0.0]",
            "[hertz] centre must be three finite numbers",
            Some("centre ="),
        ),
        (
            // A rejected pair is reported alone, not again as a [hertz] without its pair.
            "method = \"multiplier\"",
            "method = \"multiplier\"\ntolerance = 0.0",
            "contact 'contact-flat': tolerance must be > 0",
            Some("tolerance ="),
        ),
        (
            "symmetry = 4 ",
            "contact = \"a-b\"\nsymmetry = 4 ",
            "[hertz] contact: no pair 'a-b' (pairs: contact-flat)",
            Some("contact ="),
        ),
        (
            "[[step]]",
            "[[contact]]\nslave = \"top\"\nmaster = \"flat\"\nmethod = \"penalty\"\n\n[[step]]",
            "[hertz] contact: name the pair, the model has 2",
            Some("[hertz]"),
        ),
        (
            // Every problem of the table at once, each at its key.
            "symmetry = 4 ",
            "centre = [1e300, 0.0, 0.0]\nsymmetry = 0 ",
            "[hertz] symmetry must be ≥ 1 (got 0)",
            Some("symmetry = 0"),
        ),
        (
            "symmetry = 4 ",
            "centre = [1e300, 0.0, 0.0]\nsymmetry = 0 ",
            "[hertz] centre [1e300, 0.0, 0.0] is more than",
            Some("centre ="),
        ),
    ] {
        assert!(base.contains(from), "{from}");
        let model = out.join("bad.toml");
        let text = base.replacen(from, to, 1);
        std::fs::write(&model, &text).expect("write");
        let line_of = |key: &str| {
            1 + text
                .lines()
                .position(|l| l.starts_with(key))
                .expect("key in the model")
        };
        let expect = match key {
            Some(key) => format!("{}:{}: {expect}", model.display(), line_of(key)),
            None => format!("{}:{}:1: {expect}", model.display(), line_of("radious")),
        };
        for cmd in ["check", "run"] {
            let (ok, text, stderr) = outcome(cmd, &model);
            assert!(!ok && text.contains(&expect), "{cmd}: {expect} in {text}");
            assert!(!text.contains("needs a [[contact]] pair"), "{cmd}: {text}");
            assert!(
                stderr.matches("invalid model").count() <= 1,
                "{cmd}: {stderr}"
            );
        }
    }
    // `run` reports a [hertz] problem beside the model's others, as `check` does (it stopped at
    // the others).
    let model = out.join("both.toml");
    let text = base
        .replacen("loaded = \"top\"", "loaded = \"lid\"", 1)
        .replacen("increments = ", "increments = 0 # ", 1);
    std::fs::write(&model, &text).expect("write");
    for cmd in ["check", "run"] {
        let (ok, text, _) = outcome(cmd, &model);
        assert!(
            !ok && text.contains("[hertz] loaded: unknown group 'lid'")
                && text.contains("increments must be from 1"),
            "{cmd}: {text}"
        );
    }
    // Without any contact pair, `check` says the [hertz] table needs one (`run` stops earlier,
    // at the rigid flat that no pair holds any more).
    let pair = "[[contact]]\nslave = \"contact\"\nmaster = \"flat\"\nmethod = \"multiplier\"\n";
    assert!(base.contains(pair));
    let model = out.join("no-pair.toml");
    std::fs::write(&model, base.replace(pair, "")).expect("write");
    let o = bin()
        .args(["check".as_ref(), model.as_os_str()])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(!o.status.success(), "{stdout}");
    assert!(
        stdout.contains("[hertz] needs a [[contact]] pair"),
        "{stdout}"
    );
    // A missing `--mesh` file is named.
    let missing = out.join("missing.msh");
    for cmd in ["check", "run"] {
        let o = bin()
            .args([
                cmd.as_ref(),
                ex.join("multiplier.toml").as_os_str(),
                "--mesh".as_ref(),
                missing.as_os_str(),
            ])
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && stderr.contains("missing.msh"),
            "{cmd}: {stderr}"
        );
    }
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn closed_stdout_ends_quietly_without_panic() {
    // A pipe whose reading end is closed before the program starts: every write fails (closing
    // it after the start raced with the program's first lines under load).
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    let out = bin()
        .args(["check".as_ref(), example().as_os_str()])
        .stdout(writer)
        .stderr(std::process::Stdio::piped())
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(1));
}

/// The sliding example with a penalty, `line_search` in each step set to `line_search`, run
/// with `--verbose` in a temporary folder named `name`: its standard output and its `newton.csv`
/// as read.
fn penalty_sliding(name: &str, line_search: &str) -> (String, Vec<NewtonLog>) {
    let out = temp_dir(name);
    let ex = examples_dir().join("sliding");
    let text = std::fs::read_to_string(ex.join("model.toml")).expect("model");
    let text = text
        .replace("method = \"multiplier\"", "method = \"penalty\"")
        .replace(
            "file = \"sliding.msh\"",
            &format!(
                "file = {:?}",
                ex.join("sliding.msh").to_str().expect("utf8")
            ),
        )
        .replace("plots = true", "plots = false")
        .replace(
            "[[step]]",
            &format!("[[step]]\nline_search = {line_search}"),
        );
    let model = out.join("penalty.toml");
    std::fs::write(&model, text).expect("write");
    let stdout = run_ok(&[
        "run".as_ref(),
        model.as_os_str(),
        "--verbose".as_ref(),
        "--output".as_ref(),
        out.join("results").as_os_str(),
    ]);
    let logs = read_newton(&out.join("results")).expect("newton.csv");
    std::fs::remove_dir_all(&out).ok();
    (stdout, logs)
}

/// A contact run whose first increment fails writes `history.csv` with its whole header (the
/// contact pair's columns too) and no row.
#[test]
fn a_failed_first_increment_leaves_the_whole_history_header() {
    let out = temp_dir("first-fails");
    let ex = examples_dir().join("patch");
    let text = std::fs::read_to_string(ex.join("penalty.toml"))
        .expect("model")
        .replace(
            "file = \"matching-hex.msh\"",
            &format!(
                "file = {:?}",
                ex.join("matching-hex.msh").to_str().expect("utf8")
            ),
        )
        .replace("plots = true", "plots = false")
        .replace("[[step]]", "[[step]]\nmax_iterations = 1\nmax_cutbacks = 0");
    let model = out.join("first.toml");
    std::fs::write(&model, text).expect("write");
    let o = bin()
        .args(["run".as_ref(), model.as_os_str(), "--output".as_ref()])
        .arg(out.join("results"))
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(1));
    let history = std::fs::read_to_string(out.join("results/history.csv")).expect("history");
    assert_eq!(history.lines().count(), 1, "{history}");
    let header = history.trim_end();
    assert!(
        header.starts_with("step,step_name,increment,")
            && header.ends_with("upper_zmin-lower_zmax_max_pressure"),
        "{header}"
    );
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn verbose_log_names_each_cut_back_attempt() {
    // The sliding example with a penalty and no line search needs cutbacks (VERIFICATION.md):
    // each failed attempt is reported with its target load factor and reason before the
    // increment that converged.
    let (stdout, logs) = penalty_sliding("cutbacks", "false");
    let attempts: Vec<&str> = stdout.lines().filter(|l| l.contains("cut back:")).collect();
    assert!(!attempts.is_empty(), "{stdout}");
    assert!(
        attempts.iter().all(|l| l.contains("attempt t = ")
            && (l.contains("inverted") || l.contains("no convergence"))),
        "{attempts:?}"
    );
    let done = stdout
        .lines()
        .find(|l| l.starts_with("done:"))
        .expect("summary");
    assert!(
        done.contains(&format!("{} cutbacks", attempts.len())),
        "{done} vs {}",
        attempts.len()
    );
    // `newton.csv` holds each failed attempt, with its residuals (as the verbose log lists them
    // on the line after it), before the attempt at the same increment that converged.
    let listed: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("    rel. residuals ["))
        .collect();
    let failed: Vec<&NewtonLog> = logs.iter().filter(|l| !l.converged()).collect();
    assert_eq!(failed.len(), attempts.len(), "{failed:?}");
    // Each attempt's line is followed by its residuals and its contact note per iteration.
    let lines: Vec<&str> = stdout.lines().collect();
    for (k, line) in lines.iter().enumerate() {
        if line.contains("cut back:") {
            assert!(
                lines[k + 1].starts_with("    rel. residuals [")
                    && lines[k + 2].starts_with("    iteration 0: contact: "),
                "{:?}",
                &lines[k..k + 3]
            );
        }
    }
    for (k, f) in logs.iter().enumerate() {
        if f.converged() {
            continue;
        }
        assert!(
            f.outcome.starts_with("cut back: ") && !f.relative.is_empty(),
            "{f:?}"
        );
        let next = logs[k..]
            .iter()
            .find(|l| l.converged())
            .expect("converged after");
        assert_eq!((next.step, next.increment), (f.step, f.increment), "{f:?}");
        assert!(f.load_factor > next.load_factor, "{f:?} then {next:?}");
        let text: Vec<String> = f.relative.iter().map(|r| format!("{r:.1e}")).collect();
        let line = format!("    rel. residuals [{}]", text.join(" "));
        assert!(listed.contains(&line.as_str()), "{line}");
    }
}

#[test]
fn the_automatic_line_search_is_reported_where_it_comes_on() {
    // The same run with the default `line_search = "auto"`: the first inverted element switches
    // the line search on; that attempt is reported as failed and retried, not cut back.
    let (stdout, logs) = penalty_sliding("auto-line-search", "\"auto\"");
    let failed: Vec<&str> = stdout.lines().filter(|l| l.contains(" failed: ")).collect();
    assert_eq!(failed.len(), 1, "{stdout}");
    assert!(
        failed[0].contains("inverted")
            && failed[0].ends_with(
                "retried at the same size with the line search, on for the rest of the step"
            ),
        "{}",
        failed[0]
    );
    assert!(!stdout.contains("cut back:"), "{stdout}");
    let done = stdout
        .lines()
        .find(|l| l.starts_with("done:"))
        .expect("summary");
    assert!(
        done.contains("0 cutbacks, line search switched on in 1 step;"),
        "{done}"
    );
    // In `newton.csv`, the attempt retried with the line search, at the load factor of the one
    // that converged.
    let failed: Vec<&NewtonLog> = logs.iter().filter(|l| !l.converged()).collect();
    assert_eq!(failed.len(), 1, "{failed:?}");
    assert!(
        failed[0].outcome.starts_with("failed: ") && failed[0].outcome.contains("inverted"),
        "{failed:?}"
    );
    let next = logs
        .iter()
        .find(|l| l.converged() && (l.step, l.increment) == (failed[0].step, failed[0].increment))
        .expect("the same increment converged");
    assert_eq!(next.load_factor, failed[0].load_factor);
}

/// A run that fails after its cutbacks lists, with `--verbose`, every attempt of the increment
/// that failed (the error line gives the last).
#[test]
fn verbose_log_lists_the_attempts_of_a_failed_increment() {
    let out = temp_dir("failed-attempts");
    let ex = examples_dir().join("cantilever");
    let text = std::fs::read_to_string(ex.join("model.toml")).expect("model");
    let text = text
        .replace(
            "residual_tolerance = 1e-9",
            "residual_tolerance = 1e-16\nmax_cutbacks = 2",
        )
        .replace(
            "file = \"beam.msh\"",
            &format!("file = {:?}", ex.join("beam.msh").to_str().expect("utf8")),
        );
    let model = out.join("tight.toml");
    std::fs::write(&model, text).expect("write");
    let run = bin()
        .args([
            "run".as_ref(),
            model.as_os_str(),
            "--verbose".as_ref(),
            "--output".as_ref(),
            out.join("results").as_os_str(),
        ])
        .output()
        .expect("runs");
    assert_eq!(run.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&run.stdout);
    let failed: Vec<&str> = stdout
        .lines()
        .filter(|l| l.contains(" attempt t = "))
        .collect();
    let targets: Vec<(&str, &str)> = failed
        .iter()
        .filter_map(|l| {
            let (t, outcome) = l.split("t = ").nth(1)?.split_once(' ')?;
            Some((t, outcome.split(':').next()?))
        })
        .collect();
    // Labelled as in newton.csv: the first two cut back, the last failed.
    assert_eq!(
        targets,
        [
            ("0.2500", "cut back"),
            ("0.1250", "cut back"),
            ("0.0625", "failed")
        ],
        "{stdout}"
    );
    assert!(
        failed
            .iter()
            .all(|l| l.starts_with("step 1 'bend' attempt") && l.contains("stalled at round-off")),
        "{failed:?}"
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("to 0.062500") && stderr.contains("after 2 cutbacks"),
        "{stderr}"
    );
    // `newton.csv` holds the three attempts: the first two cut back, the last failed, each
    // with its iterations from the predictor on.
    let logs = read_newton(&out.join("results")).expect("newton.csv");
    let attempts: Vec<(f64, &str, usize)> = logs
        .iter()
        .map(|l| {
            let kind = l.outcome.split(':').next().unwrap_or_default();
            (l.load_factor, kind, l.increment)
        })
        .collect();
    assert_eq!(
        attempts,
        [
            (0.25, "cut back", 1),
            (0.125, "cut back", 1),
            (0.0625, "failed", 1)
        ],
        "{logs:?}"
    );
    assert!(
        logs.iter()
            .all(|l| l.relative.len() > 2 && l.outcome.contains("stalled at round-off")),
        "{logs:?}"
    );
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn export_writes_a_calculix_deck_and_names_what_it_cannot() {
    let dir = temp_dir("export");
    let deck = dir.join("blocks.inp");
    let model = examples_dir().join("contact-block/model.toml");
    let stdout = run_ok(&[
        "export".as_ref(),
        model.as_os_str(),
        "-o".as_ref(),
        deck.as_os_str(),
    ]);
    // neo-Hooke and multipliers are approximations: each is printed as a note.
    assert!(stdout.contains("NEO HOOKE"), "{stdout}");
    assert!(stdout.contains("method multiplier exported"), "{stdout}");
    let text = std::fs::read_to_string(&deck).expect("deck written");
    assert!(text.starts_with("*HEADING"));
    assert_eq!(text.matches("*STEP").count(), 2);
    assert!(text.contains("TYPE=NODE TO SURFACE"));
    // A follower pressure in an nlgeom step cannot be exported: exit 1, one line, no file.
    let bad = dir.join("follower.toml");
    let mut src =
        std::fs::read_to_string(examples_dir().join("block-stretch/model.toml")).expect("model");
    src = src.replace("pressure = 0.5", "pressure = 0.5\nfollower = true");
    src = src.replace(
        "\"block.msh\"",
        &format!("{:?}", examples_dir().join("block-stretch/block.msh")),
    );
    std::fs::write(&bad, src).expect("write model");
    let out = dir.join("follower.inp");
    let o = bin()
        .args([
            "export".as_ref(),
            bad.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("load 'top' is a follower pressure"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(!out.exists());
}

/// `export -o` writes only a regular `.inp` file: never the model, its mesh, a symbolic link or a
/// device; the file it would have replaced is untouched.
#[test]
fn export_refuses_to_replace_what_is_not_a_deck() {
    let dir = temp_dir("export-target");
    let model = dir.join("model.toml");
    let src = std::fs::read_to_string(examples_dir().join("patch/penalty.toml")).expect("model");
    let mesh = examples_dir().join("patch/matching-hex.msh");
    let src = src.replace("\"matching-hex.msh\"", &format!("{mesh:?}"));
    std::fs::write(&model, &src).expect("write model");
    let target = dir.join("target.inp");
    std::fs::write(&target, "kept").expect("target");
    let link = dir.join("link.inp");
    std::os::unix::fs::symlink(&target, &link).expect("symlink");
    let as_deck = dir.join("model.inp");
    std::fs::write(&as_deck, &src).expect("model named .inp");
    let o = bin()
        .args(["export".as_ref(), as_deck.as_os_str()])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("is an input of the model"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&as_deck).expect("kept"), src);
    for (out, expected) in [
        (model.clone(), "is an input of the model"),
        (mesh.clone(), "is an input of the model"),
        (dir.join("deck.txt"), "must end in .inp"),
        (link.clone(), "not a regular file"),
    ] {
        let o = bin()
            .args([
                "export".as_ref(),
                model.as_os_str(),
                "-o".as_ref(),
                out.as_os_str(),
            ])
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && stderr.contains(expected),
            "{}: {stderr}",
            out.display()
        );
    }
    assert_eq!(std::fs::read_to_string(&model).expect("model"), src);
    assert!(
        std::fs::symlink_metadata(&link)
            .expect("link")
            .file_type()
            .is_symlink()
    );
    assert_eq!(std::fs::read_to_string(&target).expect("target"), "kept");
}

/// More threads than cores are capped, with a note, instead of slowing the run to a crawl.
#[test]
fn threads_beyond_the_cores_are_capped() {
    let dir = temp_dir("threads");
    let o = bin()
        .args([
            "run".as_ref(),
            examples_dir().join("patch/penalty.toml").as_os_str(),
            "--mesh".as_ref(),
            examples_dir().join("patch/matching-hex.msh").as_os_str(),
            "--output".as_ref(),
            dir.as_os_str(),
            "--threads".as_ref(),
            "100000".as_ref(),
        ])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("note: --threads 100000: this machine has"),
        "{stderr}"
    );
}

/// The cantilever example with two problems (`nu = 0.7`; two steps named `bend`), written to a
/// folder of its own: the model's path, and the prefixes (`"  - model.toml:N: "`, as listed) of
/// the two problems' messages, at the lines of `nu` and of the second step's name.
fn two_problem_model(name: &str) -> (PathBuf, [String; 2]) {
    let dir = temp_dir(name);
    let src = std::fs::read_to_string(example()).expect("model");
    let mesh = example().with_file_name("beam.msh");
    let src = src
        .replace("\"beam.msh\"", &format!("{mesh:?}"))
        .replace("nu = 0.3", "nu = 0.7")
        .replace("name = \"release-pressure\"", "name = \"bend\"");
    let lines = |key: &str| {
        src.lines()
            .enumerate()
            .filter(|(_, l)| l.starts_with(key))
            .map(|(i, _)| i + 1)
            .collect::<Vec<_>>()
    };
    let (nu, names) = (lines("nu ="), lines("name = \"bend\""));
    assert_eq!((nu.len(), names.len()), (1, 2), "{src}");
    let model = dir.join("model.toml");
    std::fs::write(&model, &src).expect("write");
    let at = |line: usize| format!("  - {}:{line}: ", model.display());
    let prefixes = [
        at(nu[0]) + "material",
        at(names[1]) + "step name 'bend' is used twice",
    ];
    (model, prefixes)
}

/// `run` lists a model's several problems one per line, each with the line of its key.
#[test]
fn run_lists_several_problems_with_their_lines() {
    let (model, prefixes) = two_problem_model("run-many");
    let (ok, _, stderr) = outcome("run", &model);
    assert!(!ok);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines[0], "error: invalid model, 2 problems:", "{stderr}");
    for p in &prefixes {
        assert!(
            lines[1..].iter().any(|l| l.starts_with(p)),
            "{p} in {stderr}"
        );
    }
}

/// `check` lists every problem once, each with the line of its key, and its final error line
/// has one `invalid model:` prefix.
#[test]
fn check_lists_several_problems_with_one_prefix() {
    let (model, prefixes) = two_problem_model("check-many");
    let (ok, text, stderr) = outcome("check", &model);
    assert!(!ok);
    assert!(text.contains("2 problem(s):"), "{text}");
    for p in &prefixes {
        assert!(text.lines().any(|l| l.starts_with(p)), "{p} in {text}");
    }
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert_eq!(stderr.matches("invalid model").count(), 1, "{stderr}");
}

/// An `[output] folder` that names an existing file is a problem of the model, at its line, for
/// `check` and for `run` (which found it only once the analysis was set up); `run --output`
/// elsewhere does not use that folder and runs.
#[test]
fn an_output_folder_that_is_a_file_is_a_model_problem() {
    let dir = temp_dir("folder-file");
    let mesh = example().with_file_name("beam.msh");
    let src = std::fs::read_to_string(example())
        .expect("model")
        .replace("\"beam.msh\"", &format!("{mesh:?}"))
        .replace("folder = \"results\"", &format!("folder = {mesh:?}"));
    let line = 1 + src
        .lines()
        .position(|l| l.starts_with("folder ="))
        .expect("folder");
    let model = dir.join("model.toml");
    std::fs::write(&model, &src).expect("write");
    // `check` and `run` both fail with `expect`.
    let refused = |expect: &str| {
        for cmd in ["check", "run"] {
            let o = bin()
                .args([cmd.as_ref(), model.as_os_str()])
                .output()
                .expect("runs");
            let stderr = String::from_utf8_lossy(&o.stderr);
            assert!(
                !o.status.success() && stderr.contains(expect),
                "{cmd}: {stderr}"
            );
        }
    };
    refused(&format!(
        "{}:{line}: output.folder {}: exists and is not a folder",
        model.display(),
        mesh.display()
    ));
    let o = bin()
        .args([
            "run".as_ref(),
            model.as_os_str(),
            "--output".as_ref(),
            dir.join("out").as_os_str(),
        ])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A folder below a file cannot be created: the same problem, at the same line.
    let below = mesh.join("sub");
    std::fs::write(
        &model,
        src.replace(
            &format!("folder = {mesh:?}"),
            &format!("folder = {below:?}"),
        ),
    )
    .expect("write");
    refused(&format!(
        "{}:{line}: output.folder {}: cannot be created: {} is a file, not a folder",
        model.display(),
        below.display(),
        mesh.display()
    ));
    std::fs::remove_dir_all(&dir).ok();
}

/// A mesh that cannot be read is reported at the model's `[mesh] file` line, by every command
/// that reads it; one given by `--mesh` is reported by its path alone.
#[test]
fn an_unreadable_mesh_names_the_model_line() {
    let dir = temp_dir("mesh-missing");
    let text = std::fs::read_to_string(example()).expect("model");
    let line = 1 + text
        .lines()
        .position(|l| l.trim_start().starts_with("file"))
        .expect("a [mesh] file line");
    let model = dir.join("model.toml");
    std::fs::create_dir_all(dir.join("folder.msh")).expect("a folder");
    for (name, reason) in [
        ("nosuch.msh", "No such file"),
        ("folder.msh", "not a regular file"),
    ] {
        let src = text.replace("beam.msh", name);
        assert_ne!(src, text, "the example names beam.msh");
        std::fs::write(&model, src).expect("model");
        for cmd in ["check", "run", "export"] {
            let (ok, _, stderr) = outcome(cmd, &model);
            let at = format!("{}:{line}: mesh ", model.display());
            assert!(
                !ok && stderr.contains(&at) && stderr.contains(name) && stderr.contains(reason),
                "{cmd} {name}: {stderr}"
            );
        }
    }
    let o = bin()
        .args(["check".as_ref(), example().as_os_str(), "--mesh".as_ref()])
        .arg(dir.join("nosuch.msh"))
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("nosuch.msh") && !stderr.contains(".toml:"),
        "{stderr}"
    );
}

/// A model with no `[[step]]` is told so, naming the file, and only that: the loads that name
/// steps are not reported as naming unknown ones.
#[test]
fn a_model_without_steps_names_the_file_once() {
    let dir = temp_dir("no-steps");
    let mesh = example().with_file_name("beam.msh");
    let text = std::fs::read_to_string(example()).expect("model");
    let (head, tail) = text.split_at(text.find("[[step]]").expect("steps"));
    let src = format!("{head}{}", &tail[tail.find("[output]").expect("output")..])
        .replace("\"beam.msh\"", &format!("{mesh:?}"));
    let model = dir.join("model.toml");
    std::fs::write(&model, src).expect("write");
    let o = bin()
        .args(["check".as_ref(), model.as_os_str()])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(!o.status.success(), "{stdout}");
    assert!(
        stderr.contains(&format!("{}: no [[step]] defined", model.display())),
        "{stderr}"
    );
    assert!(
        !format!("{stdout}{stderr}").contains("unknown step"),
        "{stdout}{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A rigid flat held along its normal only: the error names a node of the rigid surface, and so
/// does the note on rigid-body modes (it called the node's part a body part, which has none).
#[test]
fn an_under_held_rigid_surface_is_named_as_such() {
    let dir = temp_dir("rigid-held");
    let ex = examples_dir().join("hertz");
    let src = std::fs::read_to_string(ex.join("penalty.toml"))
        .expect("model")
        .replace(
            "\"hertz-fine.msh\"",
            &format!("{:?}", ex.join("hertz-coarse.msh")),
        );
    let at = src.find("group = \"flat\"").expect("flat");
    let fix = at + src[at..].find("fix = [\"x\", \"y\", \"z\"]").expect("fix");
    let src = format!(
        "{}fix = [\"z\"]{}",
        &src[..fix],
        &src[fix + "fix = [\"x\", \"y\", \"z\"]".len()..]
    );
    let model = dir.join("model.toml");
    std::fs::write(&model, src).expect("write");
    let o = bin()
        .args(["check".as_ref(), model.as_os_str()])
        .output()
        .expect("runs");
    let all = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!o.status.success(), "{all}");
    assert!(
        all.contains(
            "of a rigid contact surface (no volume element) must have x, y and z prescribed"
        ),
        "{all}"
    );
    assert!(
        all.contains("of a rigid contact surface (no volume element) has 2 unconstrained"),
        "{all}"
    );
    assert!(!all.contains("body part"), "{all}");
    std::fs::remove_dir_all(&dir).ok();
}
