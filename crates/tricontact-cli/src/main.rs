//! The `tricontact` command-line solver.
//!
//! `tricontact run MODEL [--output DIR] [--mesh FILE] [--verbose]` solves a model and
//! writes VTU/PVD/history.csv/newton.csv (and the Hertz tables and PNG plots when the model
//! asks); `tricontact check MODEL` parses and validates it and prints a summary with every
//! problem found; `tricontact plot DIR...` overlays the Newton residuals of one increment of
//! several result folders; `tricontact export MODEL [-o DECK.inp]` writes the model as a
//! CalculiX input deck. Exit code 0 on success; on failure 1 with a one-line cause on stderr.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use tricontact_fem::analysis::Analysis;
use tricontact_fem::assembly::ExtraTerms;
use tricontact_fem::contact::ContactTerms;
use tricontact_fem::driver::{self, IncrementInfo};
use tricontact_fem::error::load_factor_text;
use tricontact_fem::hertz::HertzSetup;
use tricontact_fem::model::Model;
use tricontact_fem::output::ResultWriter;
use tricontact_fem::report::{self, RunRecord};
use tricontact_fem::{FemError, atomic, inp, rigid};

/// `println!` that ends the program quietly when standard output is closed (e.g. piped into
/// `head`), instead of panicking: results are written atomically, so nothing is left half-written.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if writeln!(std::io::stdout(), $($arg)*).is_err() {
            std::process::exit(1);
        }
    }};
}

#[derive(Parser)]
#[command(
    name = "tricontact",
    version,
    about = "Implicit finite-element solver for 3D solids"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Solve a model and write the results.
    Run {
        /// Model file (TOML).
        model: PathBuf,
        /// Result folder (default: `[output] folder` of the model).
        #[arg(long)]
        output: Option<PathBuf>,
        /// Mesh file to use instead of `[mesh] file` (relative to the current folder).
        #[arg(long)]
        mesh: Option<PathBuf>,
        /// Print a line per increment (iterations, relative residuals) and, with contact, one per
        /// Newton iteration (closed nodes, status and facet changes); the same for each failed
        /// attempt.
        #[arg(long)]
        verbose: bool,
        /// Worker threads for assembly and factorization (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Parse and validate a model, print a summary and every problem.
    Check {
        /// Model file (TOML).
        model: PathBuf,
        /// Mesh file to use instead of `[mesh] file` (relative to the current folder).
        #[arg(long)]
        mesh: Option<PathBuf>,
    },
    /// Write the model as a CalculiX (Abaqus-format) input deck, to cross-check with `ccx`.
    Export {
        /// Model file (TOML).
        model: PathBuf,
        /// Deck to write (default: the model file with the extension `.inp`).
        #[arg(long, short)]
        output: Option<PathBuf>,
        /// Mesh file to use instead of `[mesh] file` (relative to the current folder).
        #[arg(long)]
        mesh: Option<PathBuf>,
    },
    /// Overlay the Newton residuals of one increment of several result folders (PNG).
    Plot {
        /// Result folders written by `tricontact run` (each holds `newton.csv`).
        #[arg(required = true)]
        folders: Vec<PathBuf>,
        /// Increment to compare, `STEP:INCREMENT` (1-based; default: the last converged one of
        /// each run).
        #[arg(long, value_parser = parse_increment)]
        increment: Option<(usize, usize)>,
        /// Output PNG.
        #[arg(long, short, default_value = "newton-compare.png")]
        output: PathBuf,
    },
}

fn parse_increment(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("'{s}': expected STEP:INCREMENT, e.g. 1:5");
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let step = a.trim().parse().map_err(|_| bad())?;
    let inc = b.trim().parse().map_err(|_| bad())?;
    if step == 0 || inc == 0 {
        return Err(bad());
    }
    Ok((step, inc))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            model,
            output,
            mesh,
            verbose,
            threads,
        } => set_threads(threads)
            .and_then(|()| run(&model, output, mesh, verbose).map_err(|e| describe(&e))),
        Command::Check { model, mesh } => check(&model, mesh).map_err(|e| e.to_string()),
        Command::Export {
            model,
            output,
            mesh,
        } => export(&model, output, mesh),
        Command::Plot {
            folders,
            increment,
            output,
        } => report::compare_newton(&folders, increment, &output)
            .map(|()| say!("wrote {}", output.display()))
            .map_err(|e| e.to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// An error's text for the terminal: a model's several problems one per line (`check` lists them
/// itself, then ends with the one-line form).
fn describe(e: &FemError) -> String {
    match e {
        FemError::Invalid(list) if list.len() > 1 => {
            let mut text = format!("invalid model, {} problems:", list.len());
            for m in list {
                text.push_str("\n  - ");
                text.push_str(m);
            }
            text
        }
        other => other.to_string(),
    }
}

/// The analysis of a model on its mesh, the setup of its `[hertz]` table, and every problem
/// found in either (`run` and `check` report the same ones).
fn resolve(
    model: &Model,
    mesh: tricontact_fem::mesh::Mesh,
) -> (Analysis, Option<HertzSetup>, Vec<FemError>) {
    let (an, mut problems) = Analysis::build(model, mesh);
    let mut hertz = None;
    // A [hertz] table names a pair: only meaningful once every pair resolved.
    if let Some(h) = &model.hertz
        && an.contacts.len() == model.contacts.len()
    {
        match HertzSetup::resolve_at(h, &an, &|key| model.source.at("hertz", 0, key)) {
            Ok(setup) => hertz = Some(setup),
            Err(e) => problems.push(e),
        }
    }
    (an, hertz, problems)
}

/// A problem at `[output] folder` when it names an existing file, or a path through one (`run`
/// without `--output` would fail on it only after the analysis was set up).
fn folder_problem(model: &Model) -> Option<FemError> {
    let dir = model.output_dir();
    let existing = dir.ancestors().find(|a| a.exists())?;
    if existing.is_dir() {
        return None;
    }
    let what = if existing == dir {
        "exists and is not a folder".to_string()
    } else {
        format!(
            "cannot be created: {} is a file, not a folder",
            existing.display()
        )
    };
    Some(FemError::Invalid(vec![format!(
        "{}output.folder {}: {what}",
        model.source.at("output", 0, "folder"),
        dir.display()
    )]))
}

fn set_threads(threads: Option<usize>) -> Result<(), String> {
    let Some(n) = threads else { return Ok(()) };
    if n == 0 {
        return Err("--threads must be at least 1".into());
    }
    // More threads than cores only adds contention (1000 threads made a 0.06 s run take minutes).
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    let n = if n > cores {
        eprintln!("note: --threads {n}: this machine has {cores} cores; using {cores}");
        cores
    } else {
        n
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .map_err(|e| format!("cannot start {n} threads: {e}"))
}

/// `info`'s line of the verbose log; `previous` is the load factor the increment started from.
fn increment_line(info: &IncrementInfo<'_>, previous: f64) -> String {
    let searches = match info.line_searches {
        0 => String::new(),
        1 => " (1 line-search trial)".to_string(),
        n => format!(" ({n} line-search trials)"),
    };
    format!(
        "step {} '{}' inc {:>3}  t = {}  iters {:>2}{searches}  cutbacks {}  {}  rel. residuals [{}]",
        info.step + 1,
        info.step_name,
        info.increment,
        load_factor_text(info.load_factor, info.load_factor - previous, 4),
        info.iterations,
        info.cutbacks,
        info.method,
        residual_list(&info.relative_residuals())
    )
}

/// Relative residuals as the verbose log lists them, two digits each.
fn residual_list(relative: &[f64]) -> String {
    let rel: Vec<String> = relative.iter().map(|r| format!("{r:.1e}")).collect();
    rel.join(" ")
}

/// The verbose lines of a failed attempt: what it aimed at, its outcome and why, then its
/// relative residuals when it had any and the extra terms' note of each iteration.
fn attempt_lines(head: &str, outcome: &str, a: &driver::Attempt) -> Vec<String> {
    let mut lines = vec![format!("{head} {outcome}: {a}")];
    if !a.relative.is_empty() {
        lines.push(format!(
            "    rel. residuals [{}]",
            residual_list(&a.relative)
        ));
    }
    lines.extend(note_lines(&a.notes));
    lines
}

/// The verbose lines of the extra terms' notes, one per iteration.
fn note_lines(notes: &[String]) -> impl Iterator<Item = String> + '_ {
    notes
        .iter()
        .enumerate()
        .map(|(k, note)| format!("    iteration {k}: {note}"))
}

/// The verbose log of a converged increment that started at load factor `previous`: the attempts
/// cut back before it, its line, and the extra terms' note of each iteration.
fn verbose_lines(info: &IncrementInfo<'_>, previous: f64) -> Vec<String> {
    let mut lines: Vec<String> = info
        .attempts
        .iter()
        .flat_map(|a| {
            let outcome = a.label(false);
            let head = format!(
                "step {} '{}' attempt t = {}",
                info.step + 1,
                info.step_name,
                load_factor_text(a.target, a.target - previous, 4)
            );
            attempt_lines(&head, outcome, a)
        })
        .collect();
    lines.push(increment_line(info, previous));
    lines.extend(note_lines(info.notes));
    lines
}

/// The verbose log of the increment a run failed on: each attempt, what became of it (cut back,
/// or the last one failed) and why (none for other errors).
fn failed_attempts(an: &Analysis, e: &FemError) -> Vec<String> {
    let FemError::NotConverged {
        step,
        attempts,
        load_factor,
        ..
    } = e
    else {
        return Vec::new();
    };
    let number = an
        .steps
        .iter()
        .position(|s| s.name == *step)
        .map_or(0, |i| i + 1);
    attempts
        .iter()
        .enumerate()
        .flat_map(|(k, a)| {
            let t = load_factor_text(a.target, a.target - load_factor, 4);
            let outcome = a.label(k + 1 == attempts.len());
            attempt_lines(
                &format!("step {number} '{step}' attempt t = {t}"),
                outcome,
                a,
            )
        })
        .collect()
}

fn run(
    model_path: &Path,
    output: Option<PathBuf>,
    mesh_override: Option<PathBuf>,
    verbose: bool,
) -> Result<(), FemError> {
    let model = Model::load_with_mesh(model_path, mesh_override.as_deref())?;
    let mesh = model.read_mesh()?;
    mesh.check()?;
    let (an, hertz, mut problems) = resolve(&model, mesh);
    if output.is_none() {
        problems.extend(folder_problem(&model));
    }
    if let Some(e) = FemError::combine(problems) {
        return Err(e);
    }
    for note in an.notes() {
        say!("note: {note}");
    }
    let mut record = RunRecord::new(hertz);
    let dir = output.unwrap_or_else(|| model.output_dir());
    let stem = model_path
        .file_stem()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let mut writer = ResultWriter::new(&an, &dir, &stem)?;
    let pb = progress_bar(an.steps.len());
    for pair in &an.contacts {
        for line in &pair.report {
            say!("{line}");
        }
    }
    let mut contact = ContactTerms::new(&an);
    writer.extra_columns(contact.history().iter().map(|(name, _)| name.as_str()));
    // (step, load factor) of the last converged increment, for the verbose log.
    let mut last = (usize::MAX, 0.0);
    let summary = driver::run(&an, &mut contact, &mut |info| {
        writer.write(&an, info)?;
        record.record(&an, info);
        if an.output.history {
            record.write_tables_if_due(&dir)?;
        }
        pb.set_position((info.time * 1000.0).round() as u64);
        pb.set_message(format!("step {} t={:.3}", info.step + 1, info.load_factor));
        // The load factor this increment started from (0 at a step's first).
        let previous = if info.step == last.0 { last.1 } else { 0.0 };
        last = (info.step, info.load_factor);
        if verbose {
            for line in verbose_lines(info, previous) {
                if pb.is_hidden() {
                    say!("{line}");
                } else {
                    pb.println(line);
                }
            }
        }
        Ok(())
    });
    pb.finish_and_clear();
    if let Err(e) = &summary {
        record.record_failure(&an, e);
    }
    // What was left pending, whether the run succeeded or not: the tables' last rows, and on a
    // failure the last converged state if `every` skipped it. A run's own error comes first.
    let flushed = writer.finish(&an).and_then(|()| {
        if an.output.history {
            record.write_tables(&dir).map(|_| ())
        } else {
            Ok(())
        }
    });
    let summary = summary.and_then(|s| flushed.map(|()| s));
    if let (Err(e), true) = (&summary, verbose) {
        for line in failed_attempts(&an, e) {
            say!("{line}");
        }
    }
    report_end(&an, &record, &summary?, &dir)
}

/// A progress bar over the steps of a run, a thousand ticks each (hidden when not on a terminal).
fn progress_bar(steps: usize) -> ProgressBar {
    let pb = ProgressBar::new(1000 * steps as u64);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {pos:>5}/{len} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb
}

/// The end of a successful run: the contact and Hertz summaries, the plots (written now), and the
/// `done:` line with the run's counts and where its results are.
fn report_end(
    an: &Analysis,
    record: &RunRecord,
    summary: &driver::RunSummary,
    dir: &Path,
) -> Result<(), FemError> {
    for line in record
        .contact_summary()
        .into_iter()
        .chain(record.hertz_summary())
    {
        say!("{line}");
    }
    if an.output.plots {
        let plots = record.write_plots(dir)?;
        say!(
            "plots: {}",
            plots
                .iter()
                .map(|p| p.file_name().unwrap_or_default().to_string_lossy())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let switched = match summary.line_search_switches {
        0 => String::new(),
        1 => ", line search switched on in 1 step".to_string(),
        n => format!(", line search switched on in {n} steps"),
    };
    say!(
        "done: {} increments, {} Newton iterations, {} cutbacks{switched}; results in {}",
        summary.increments,
        summary.iterations,
        summary.cutbacks,
        dir.display()
    );
    Ok(())
}

fn export(
    model_path: &Path,
    output: Option<PathBuf>,
    mesh_override: Option<PathBuf>,
) -> Result<(), String> {
    let model =
        Model::load_with_mesh(model_path, mesh_override.as_deref()).map_err(|e| e.to_string())?;
    let mesh = model.read_mesh().map_err(|e| e.to_string())?;
    let an = Analysis::new(&model, mesh).map_err(|e| e.to_string())?;
    let title = format!(
        "{} (mesh {})",
        model_path.display(),
        model.mesh_path().display()
    );
    let deck = inp::write(&an, &title).map_err(|e| format!("{}: {e}", model_path.display()))?;
    let path = output.unwrap_or_else(|| model_path.with_extension("inp"));
    check_deck_path(&path, &[model_path, &model.mesh_path()])?;
    atomic::write_atomic(&path, deck.text.as_bytes()).map_err(|e| e.to_string())?;
    for note in &deck.notes {
        say!("note: {note}");
    }
    say!("wrote {}", path.display());
    Ok(())
}

/// A deck path must not be the model or its mesh, must end in `.inp` (as `ccx` expects) and, if it
/// exists, be a regular file (the deck is written by renaming a temporary
/// file over it, which would replace a symbolic link or a device rather than write to it).
fn check_deck_path(path: &Path, inputs: &[&Path]) -> Result<(), String> {
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if let Some(input) = inputs.iter().find(|i| same(path, i)) {
        return Err(format!(
            "{}: is an input of the model ({}); not replaced",
            path.display(),
            input.display()
        ));
    }
    if path.extension().and_then(|e| e.to_str()) != Some("inp") {
        return Err(format!(
            "{}: the deck's name must end in .inp (ccx reads JOB.inp)",
            path.display()
        ));
    }
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.file_type().is_file() => Err(format!(
            "{}: exists and is not a regular file; not replaced",
            path.display()
        )),
        _ => Ok(()),
    }
}

fn check(model_path: &Path, mesh_override: Option<PathBuf>) -> Result<(), FemError> {
    let model = Model::load_with_mesh(model_path, mesh_override.as_deref())?;
    let mesh = model.read_mesh()?;
    say!("model: {}", model_path.display());
    say!("mesh:  {}", model.mesh_path().display());
    say!("nodes: {}", mesh.nodes.len());
    for (kind, n) in mesh.count_kinds() {
        say!("elements {:<6} {n}", kind.name());
    }
    say!("groups:");
    for g in &mesh.groups {
        say!(
            "  {:<20} {}D  {:>8} elements {:>8} nodes",
            g.name,
            g.dim,
            g.elements.len(),
            g.nodes.len()
        );
    }
    let (an, _, mut problems) = resolve(&model, mesh);
    problems.extend(folder_problem(&model));
    let active = an.active_nodes.iter().filter(|&&a| a).count();
    say!(
        "bodies: {} elements, {} active nodes, {} DOFs",
        an.body.len(),
        active,
        3 * active
    );
    for pair in &an.contacts {
        let facets: usize = pair.passes.iter().map(|p| p.surface.len()).sum();
        let passes = if pair.is_self_contact() {
            "self-contact, facing facets only".to_string()
        } else {
            format!("{} pass(es)", pair.passes.len())
        };
        say!(
            "contact {}: {}, {} slave nodes, {} facets, {passes}, penalty {:.3e}, mean facet edge {:.3e}",
            pair.name,
            pair.method,
            pair.passes[0].slaves.len(),
            facets,
            pair.penalty,
            pair.facet_size
        );
        for line in &pair.report {
            say!("  {line}");
        }
    }
    for s in 0..an.steps.len() {
        let (mask, _) = driver::step_constraints(&an, s);
        let prescribed = mask.iter().filter(|&&m| m).count();
        say!(
            "step {} '{}': {} prescribed DOFs, {} free DOFs, nlgeom = {}, line_search = {}",
            s + 1,
            an.steps[s].name,
            prescribed,
            3 * active - prescribed,
            an.steps[s].nlgeom,
            an.steps[s].line_search
        );
        if problems.is_empty()
            && an.contacts.is_empty()
            && let Err(m) = rigid::check_supports(&an, &mask)
        {
            problems.push(FemError::Singular(format!(
                "step '{}': {m}",
                an.steps[s].name
            )));
        }
    }
    for note in an.notes() {
        say!("note: {note}");
    }
    if problems.is_empty() {
        say!("no problems found");
        Ok(())
    } else {
        let messages: Vec<String> = problems.iter().flat_map(FemError::messages).collect();
        say!("{} problem(s):", messages.len());
        for m in &messages {
            say!("  - {m}");
        }
        Err(FemError::combine(problems).expect("at least one problem"))
    }
}
