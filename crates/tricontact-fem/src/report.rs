//! Per-run records beside the VTU files: Newton residuals, contact force history and the Hertz
//! comparison, as CSV tables and (with `[output] plots = true`) PNG charts.
//!
//! Files (all atomic):
//! * `newton.csv` — `step,increment,load_factor,solve,iteration,relative_residual,outcome` for
//!   every attempt at an increment, iteration 0 of each Newton solve being its predictor (the
//!   residual it starts from; `solve` counts the augmented Lagrangian's successive solves of an
//!   attempt from 1, and is 1 otherwise): the attempts that failed (outcome `cut back: <why>`, or `failed: <why>` for one
//!   retried with the line search and for the last of a run that stopped) before the one that
//!   converged (`converged`);
//! * `hertz.csv` — one row per increment when the model has a `[hertz]` table (see
//!   [`crate::hertz`]; a cell is empty where its value is undefined: no fit with fewer than three
//!   closed nodes, no relative error without force), `hertz_profile.csv` — `r, p, p_hertz` of
//!   the last increment;
//! * `newton.png` (relative residual per iteration, log scale, the last eight converged
//!   increments),
//!   `contact_force.png` (normal force of each pair against time), `hertz_pressure.png` (nodal
//!   pressure against `r` with Hertz and the fitted profile) and `hertz_force_approach.png`
//!   (measured approach, approach minus the fitted linear term `c F`, and Hertz's `δ(F)`).
//!
//! Text fields of every CSV the program writes go through [`csv_field`] (RFC 4180 quoting).
//!
//! [`compare_newton`] overlays one increment of several result folders (`tricontact plot`).

use std::borrow::Cow;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::analysis::Analysis;
use crate::atomic::write_atomic;
use crate::driver::{Attempt, IncrementInfo};
use crate::error::{FemError, Result};
use crate::hertz::{HertzSample, HertzSetup, fit_approach};
use crate::plots::{Axes, Series, chart, check_png};
use crate::throttle::Throttle;

/// `newton.csv`: the residual of every Newton iteration.
const NEWTON_CSV: &str = "newton.csv";
/// The header of `newton.csv`.
const NEWTON_HEADER: &str = "step,increment,load_factor,solve,iteration,relative_residual,outcome";
/// The header `newton.csv` had until 2026-12-05 (converged increments only), still read.
const NEWTON_HEADER_V1: &str = "step,increment,iteration,relative_residual";
/// `hertz.csv`: the Hertz comparison per increment.
const HERTZ_CSV: &str = "hertz.csv";
/// `hertz_profile.csv`: the pressure profile of the last increment.
const HERTZ_PROFILE_CSV: &str = "hertz_profile.csv";
/// `newton.png`: the residual chart.
const NEWTON_PNG: &str = "newton.png";
/// `contact_force.png`: the contact force chart.
const CONTACT_FORCE_PNG: &str = "contact_force.png";
/// `hertz_pressure.png`: the pressure profile against Hertz.
const HERTZ_PRESSURE_PNG: &str = "hertz_pressure.png";
/// `hertz_force_approach.png`: force against approach.
const HERTZ_FORCE_APPROACH_PNG: &str = "hertz_force_approach.png";
/// Every file this module may write into a result folder (whichever a run writes depends on the
/// model), so that a new run can remove those of an earlier one.
pub const FILE_NAMES: [&str; 7] = [
    NEWTON_CSV,
    HERTZ_CSV,
    HERTZ_PROFILE_CSV,
    NEWTON_PNG,
    CONTACT_FORCE_PNG,
    HERTZ_PRESSURE_PNG,
    HERTZ_FORCE_APPROACH_PNG,
];

/// A CSV field as RFC 4180 writes it: in double quotes, inner quotes doubled, when it holds a
/// comma, a double quote, CR or LF; unchanged otherwise (numbers never need quotes).
#[must_use]
pub fn csv_field(s: &str) -> Cow<'_, str> {
    if s.contains([',', '"', '\r', '\n']) {
        Cow::Owned(format!("\"{}\"", s.replace('"', "\"\"")))
    } else {
        Cow::Borrowed(s)
    }
}

/// Residual history of one attempt at an increment.
#[derive(Clone, Debug, PartialEq)]
pub struct NewtonLog {
    /// Step index (0-based).
    pub step: usize,
    /// Increment within the step (1-based).
    pub increment: usize,
    /// The load factor the attempt aimed at (NaN when read from a file of the older form that
    /// did not give it).
    pub load_factor: f64,
    /// Relative residuals: predictor, then each iteration.
    pub relative: Vec<f64>,
    /// Where each Newton solve starts in `relative` (`[0]` for one solve).
    pub solve_starts: Vec<usize>,
    /// [`CONVERGED`], or how the attempt failed and what came after it.
    pub outcome: String,
}

/// The outcome of an attempt that converged.
pub const CONVERGED: &str = "converged";

impl NewtonLog {
    /// `true` for the attempt that converged.
    #[must_use]
    pub fn converged(&self) -> bool {
        self.outcome == CONVERGED
    }

    /// The solve (from 1) and the iteration within it (from 0) of residual `k`.
    #[must_use]
    pub fn solve_of(&self, k: usize) -> (usize, usize) {
        let solve = self.solve_starts.partition_point(|&s| s <= k).max(1);
        let start = self.solve_starts.get(solve - 1).copied().unwrap_or(0);
        (solve, k - start)
    }
}

/// The `newton.csv` rows of the failed `attempts` at increment `increment` of step `step`; the
/// last is marked `failed` when it ended the run (`stopped`).
fn attempt_logs(
    step: usize,
    increment: usize,
    attempts: &[Attempt],
    stopped: bool,
) -> Vec<NewtonLog> {
    attempts
        .iter()
        .enumerate()
        .map(|(k, a)| {
            let kind = a.label(stopped && k + 1 == attempts.len());
            NewtonLog {
                step,
                increment,
                load_factor: a.target,
                relative: a.relative.clone(),
                solve_starts: a.solve_starts.clone(),
                // One line per row: a line break in a reason would split it.
                outcome: format!("{kind}: {a}").replace(['\r', '\n'], " "),
            }
        })
        .collect()
}

/// What a run records for its tables and plots.
#[derive(Clone, Debug, Default)]
pub struct RunRecord {
    /// Residual histories.
    pub newton: Vec<NewtonLog>,
    /// `(time, [(pair column, normal force)])` per increment.
    pub forces: Vec<(f64, Vec<(String, f64)>)>,
    /// The Hertz comparison, when asked for.
    pub hertz: Option<(HertzSetup, Vec<HertzSample>)>,
    /// History columns of the extra terms at the last increment.
    pub last: Vec<(String, f64)>,
    /// When the tables were last written ([`RunRecord::write_tables_if_due`]).
    rewrites: Throttle,
}

impl RunRecord {
    /// An empty record; `hertz` enables the Hertz comparison.
    #[must_use]
    pub fn new(hertz: Option<HertzSetup>) -> Self {
        Self {
            hertz: hertz.map(|h| (h, Vec::new())),
            ..Self::default()
        }
    }

    /// Records a converged increment.
    pub fn record(&mut self, an: &Analysis, info: &IncrementInfo<'_>) {
        let (step, increment) = (info.step, info.increment);
        self.newton
            .extend(attempt_logs(step, increment, info.attempts, false));
        self.newton.push(NewtonLog {
            step,
            increment,
            load_factor: info.load_factor,
            relative: info.relative_residuals(),
            solve_starts: info.solve_starts.to_vec(),
            outcome: CONVERGED.to_string(),
        });
        let forces = info
            .history
            .iter()
            .filter(|(n, _)| n.ends_with("_normal_force"))
            .cloned()
            .collect();
        self.forces.push((info.time, forces));
        self.last = info.history.to_vec();
        if let Some((setup, samples)) = &mut self.hertz {
            samples.push(setup.measure(an, info));
        }
    }

    /// Records the attempts of the increment a run stopped on, when `e` is a step that did not
    /// converge (nothing otherwise).
    pub fn record_failure(&mut self, an: &Analysis, e: &FemError) {
        let FemError::NotConverged { step, attempts, .. } = e else {
            return;
        };
        let Some(s) = an.steps.iter().position(|st| st.name == *step) else {
            return;
        };
        let increment = self
            .newton
            .iter()
            .rev()
            .find(|l| l.step == s && l.converged())
            .map_or(1, |l| l.increment + 1);
        self.newton
            .extend(attempt_logs(s, increment, attempts, true));
    }

    /// [`RunRecord::write_tables`] when a rewrite is due ([`crate::throttle`]): after each
    /// increment, so that a running job's tables can be watched without rewriting them at every
    /// increment; write them once more when the run ends.
    ///
    /// # Errors
    /// File errors.
    pub fn write_tables_if_due(&mut self, dir: &Path) -> Result<()> {
        if self.rewrites.due() {
            let started = std::time::Instant::now();
            self.write_tables(dir)?;
            self.rewrites.wrote(started);
        }
        Ok(())
    }

    /// Writes `newton.csv` and, with a Hertz comparison, `hertz.csv` and `hertz_profile.csv`.
    ///
    /// # Errors
    /// File errors.
    pub fn write_tables(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let mut csv = format!("{NEWTON_HEADER}\n");
        for log in &self.newton {
            let outcome = csv_field(&log.outcome);
            for (k, r) in log.relative.iter().enumerate() {
                let (solve, iteration) = log.solve_of(k);
                let _ = writeln!(
                    csv,
                    "{},{},{},{solve},{iteration},{r:e},{outcome}",
                    log.step + 1,
                    log.increment,
                    log.load_factor
                );
            }
        }
        let mut written = vec![dir.join(NEWTON_CSV)];
        write_atomic(&written[0], csv.as_bytes())?;
        if let Some((setup, samples)) = &self.hertz {
            let path = dir.join(HERTZ_CSV);
            write_atomic(&path, hertz_table(setup, samples).as_bytes())?;
            written.push(path);
            if let Some(last) = samples.last() {
                let mut csv = String::from("r,p,p_hertz\n");
                for &(r, p) in &last.profile {
                    let ph = setup.theory.pressure(last.force, r);
                    let _ = writeln!(csv, "{r:e},{p:e},{ph:e}");
                }
                let path = dir.join(HERTZ_PROFILE_CSV);
                write_atomic(&path, csv.as_bytes())?;
                written.push(path);
            }
        }
        Ok(written)
    }

    /// One line per contact pair at the last increment: normal force, closed nodes, pressure
    /// range and largest penetration.
    #[must_use]
    pub fn contact_summary(&self) -> Vec<String> {
        let get = |name: &str| {
            self.last
                .iter()
                .find(|(n, _)| n == name)
                .map_or(f64::NAN, |(_, v)| *v)
        };
        self.last
            .iter()
            .filter_map(|(n, _)| n.strip_suffix("_normal_force"))
            .map(|pair| {
                let closed = get(&format!("{pair}_active"));
                // Slave nodes of a node group have no area, hence no pressure.
                let pressure = if closed > 0.0 && get(&format!("{pair}_area")) == 0.0 {
                    "pressure not available (a node-group slave has no areas)".to_string()
                } else {
                    format!(
                        "pressure {:.6e} … {:.6e}",
                        get(&format!("{pair}_min_pressure")),
                        get(&format!("{pair}_max_pressure"))
                    )
                };
                format!(
                    "contact {pair}: normal force {:.6e}, {closed} closed nodes, {pressure}, largest penetration {:.3e}",
                    get(&format!("{pair}_normal_force")),
                    get(&format!("{pair}_max_penetration")),
                )
            })
            .collect()
    }

    /// Lines summarising the Hertz comparison of the last increment and the approach fit.
    #[must_use]
    pub fn hertz_summary(&self) -> Vec<String> {
        let Some((setup, samples)) = &self.hertz else {
            return Vec::new();
        };
        let Some(last) = samples.last() else {
            return Vec::new();
        };
        if last.force.is_nan() || last.force <= 0.0 {
            return vec![format!(
                "hertz: no contact force at the last increment ({} closed nodes)",
                last.profile.len()
            )];
        }
        let e = last.errors(&setup.theory);
        let mut lines = match last.fit {
            Some((fa, fp)) => vec![
                format!(
                    "hertz: force {:.6e}, {} closed nodes; contact radius fit {fa:.5e} vs {:.5e} ({:+.2} %)",
                    last.force,
                    last.profile.len(),
                    e.radius,
                    100.0 * e.fit_radius
                ),
                format!(
                    "hertz: peak pressure fit {fp:.5e} vs {:.5e} ({:+.2} %), largest nodal {:.5e} ({:+.2} %)",
                    e.peak,
                    100.0 * e.fit_peak,
                    last.max_pressure,
                    100.0 * e.max_pressure
                ),
            ],
            None => vec![format!(
                "hertz: force {:.6e}, {} closed nodes: too few (or a rising profile) to fit; Hertz radius {:.5e}, peak pressure {:.5e}, largest nodal {:.5e}",
                last.force,
                last.profile.len(),
                e.radius,
                e.peak,
                last.max_pressure
            )],
        };
        if let Some((k, c)) = approach_fit(samples) {
            let kh = setup.theory.approach_coefficient();
            lines.push(format!(
                "hertz: approach = k F^(2/3) + c F with k {k:.5e} vs Hertz {kh:.5e} ({:+.2} %), linear term c {c:.4e}",
                100.0 * (k / kh - 1.0)
            ));
        }
        lines
    }

    /// Writes the PNG charts.
    ///
    /// # Errors
    /// Drawing or file errors.
    pub fn write_plots(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        let path = dir.join(NEWTON_PNG);
        let converged: Vec<&NewtonLog> = self.newton.iter().filter(|l| l.converged()).collect();
        let start = converged.len().saturating_sub(8);
        let series: Vec<Series> = converged[start..]
            .iter()
            .map(|l| newton_series(l))
            .collect();
        chart(&path, &newton_axes(), &series)?;
        written.push(path);
        if self.forces.iter().any(|(_, f)| !f.is_empty()) {
            let path = dir.join(CONTACT_FORCE_PNG);
            chart(&path, &force_axes(), &self.force_series())?;
            written.push(path);
        }
        if let Some((setup, samples)) = &self.hertz {
            written.extend(hertz_plots(dir, setup, samples)?);
        }
        Ok(written)
    }

    fn force_series(&self) -> Vec<Series> {
        let names: Vec<String> = self
            .forces
            .first()
            .map(|(_, f)| f.iter().map(|(n, _)| n.clone()).collect())
            .unwrap_or_default();
        names
            .iter()
            .enumerate()
            .map(|(k, name)| {
                let pts = self
                    .forces
                    .iter()
                    .filter_map(|(t, f)| f.get(k).map(|v| (*t, v.1)))
                    .collect();
                Series::line(name.trim_end_matches("_normal_force"), pts)
            })
            .collect()
    }
}

/// The axes of a Newton-convergence chart (relative residual per iteration, log scale).
fn newton_axes() -> Axes<'static> {
    Axes {
        title: "Newton convergence",
        x: "iteration",
        y: "relative residual",
        log_y: true,
        legend_low: false,
    }
}

fn force_axes() -> Axes<'static> {
    Axes {
        title: "Contact normal force",
        x: "time (step + load factor)",
        y: "normal force",
        log_y: false,
        legend_low: true,
    }
}

fn newton_series(log: &NewtonLog) -> Series {
    let pts = log
        .relative
        .iter()
        .enumerate()
        .map(|(k, &r)| (k as f64, r))
        .collect();
    Series::line(format!("step {} inc {}", log.step + 1, log.increment), pts)
}

fn approach_fit(samples: &[HertzSample]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = samples.iter().map(|s| (s.force, s.approach)).collect();
    fit_approach(&pts)
}

/// A CSV cell: the value, or empty where it is undefined (no fit, no force).
fn cell(v: f64) -> String {
    if v.is_finite() {
        format!("{v:e}")
    } else {
        String::new()
    }
}

fn hertz_table(setup: &HertzSetup, samples: &[HertzSample]) -> String {
    let mut csv = String::from(
        "step,increment,iterations,force,approach,closed_nodes,hertz_radius,fit_radius,radius_error,hertz_p0,fit_p0,p0_error,max_pressure,max_pressure_error\n",
    );
    for s in samples {
        let e = s.errors(&setup.theory);
        let (fa, fp) = s.fit.unwrap_or((f64::NAN, f64::NAN));
        let cells = [
            s.force,
            s.approach,
            e.radius,
            fa,
            e.fit_radius,
            e.peak,
            fp,
            e.fit_peak,
            s.max_pressure,
            e.max_pressure,
        ]
        .map(cell);
        let [force, approach, rest @ ..] = &cells;
        let _ = writeln!(
            csv,
            "{},{},{},{force},{approach},{},{}",
            s.step + 1,
            s.increment,
            s.iterations,
            s.profile.len(),
            rest.join(",")
        );
    }
    csv
}

fn hertz_plots(dir: &Path, setup: &HertzSetup, samples: &[HertzSample]) -> Result<Vec<PathBuf>> {
    let Some(last) = samples.last() else {
        return Ok(Vec::new());
    };
    let theory = &setup.theory;
    let a = theory.contact_radius(last.force);
    let r_max = last.profile.last().map_or(a, |p| p.0).max(a) * 1.05;
    let curve = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..=200)
            .map(|i| {
                let r = r_max * f64::from(i) / 200.0;
                (r, f(r))
            })
            .collect()
    };
    let mut series = vec![
        Series::points("nodal pressure", last.profile.clone()),
        Series::line(
            format!("Hertz, F = {:.4e}", last.force),
            curve(&|r| theory.pressure(last.force, r)),
        ),
    ];
    if let Some((fa, fp)) = last.fit {
        series.push(Series::line(
            "least-squares Hertz profile",
            curve(&|r| fp * (1.0 - (r / fa).powi(2)).max(0.0).sqrt()),
        ));
    }
    let p_path = dir.join(HERTZ_PRESSURE_PNG);
    let axes = Axes {
        title: "Contact pressure against Hertz",
        x: "distance from the axis r",
        y: "pressure p",
        log_y: false,
        legend_low: false,
    };
    chart(&p_path, &axes, &series)?;
    let f_max = samples.iter().map(|s| s.force).fold(0.0, f64::max);
    let mut series = vec![
        Series::points(
            "approach of the loaded face",
            samples.iter().map(|s| (s.force, s.approach)).collect(),
        ),
        Series::line(
            "Hertz δ(F)",
            (0..=100)
                .map(|i| {
                    let f = f_max * f64::from(i) / 100.0;
                    (f, theory.approach(f))
                })
                .collect(),
        ),
    ];
    if let Some((_, c)) = approach_fit(samples) {
        series.insert(
            1,
            Series::points(
                "minus the fitted linear term c F",
                samples
                    .iter()
                    .map(|s| (s.force, s.approach - c * s.force))
                    .collect(),
            ),
        );
    }
    let d_path = dir.join(HERTZ_FORCE_APPROACH_PNG);
    let axes = Axes {
        title: "Force against approach",
        x: "total force F",
        y: "approach",
        log_y: false,
        legend_low: true,
    };
    chart(&d_path, &axes, &series)?;
    Ok(vec![p_path, d_path])
}

/// Reads `newton.csv` of a result folder (also in its older form, converged increments only
/// without load factors).
///
/// # Errors
/// Missing or malformed file (the message names file and line).
pub fn read_newton(dir: &Path) -> Result<Vec<NewtonLog>> {
    let path = dir.join(NEWTON_CSV);
    let text = std::fs::read_to_string(&path).map_err(|e| FemError::io(&path, e))?;
    let mut logs: Vec<NewtonLog> = Vec::new();
    let older = match text
        .lines()
        .next()
        .map(|l| l.trim_start_matches('\u{feff}').trim())
    {
        None => false,
        Some(NEWTON_HEADER) => false,
        Some(NEWTON_HEADER_V1) => true,
        Some(first) => {
            return Err(FemError::Output(format!(
                "{}:1: expected the header '{NEWTON_HEADER}', found '{first}'",
                path.display()
            )));
        }
    };
    for (n, line) in text.lines().enumerate().skip(1) {
        if line.trim().is_empty() {
            continue;
        }
        let bad = || {
            FemError::Output(format!(
                "{}:{}: malformed row '{line}'",
                path.display(),
                n + 1
            ))
        };
        let row = if older {
            newton_row_v1(line)
        } else {
            newton_row(line)
        }
        .ok_or_else(bad)?;
        let (step, increment, load_factor, solve, iteration, r, outcome) = row;
        // Iterations count 0, 1, … within a solve, solves 1, 2, … within an attempt: a row out of
        // sequence is not ours.
        let new_attempt = solve == 1 && iteration == 0;
        match logs.last_mut() {
            Some(l)
                if !new_attempt
                    && l.step + 1 == step
                    && l.increment == increment
                    && l.outcome == outcome =>
            {
                let (last_solve, last_iteration) = l.solve_of(l.relative.len() - 1);
                if iteration == 0 && solve == last_solve + 1 {
                    l.solve_starts.push(l.relative.len());
                } else if solve != last_solve || iteration != last_iteration + 1 {
                    return Err(bad());
                }
                l.relative.push(r);
            }
            _ if !new_attempt => return Err(bad()),
            _ => logs.push(NewtonLog {
                step: step.checked_sub(1).ok_or_else(bad)?,
                increment,
                load_factor,
                relative: vec![r],
                solve_starts: vec![0],
                outcome,
            }),
        }
    }
    Ok(logs)
}

/// A row of `newton.csv`: step and increment (1-based), load factor, solve (from 1),
/// iteration, relative residual and outcome (the last field, in double quotes when it holds a
/// comma or a quote).
type NewtonRow = (usize, usize, f64, usize, usize, f64, String);

/// A row of the present form, `None` when malformed.
fn newton_row(line: &str) -> Option<NewtonRow> {
    let mut cols = line.splitn(7, ',');
    let mut next = || cols.next();
    let (step, inc, t, solve, iteration, r) =
        (next()?, next()?, next()?, next()?, next()?, next()?);
    let outcome = unquote(next()?)?;
    Some((
        step.parse().ok()?,
        inc.parse().ok().filter(|&i| i > 0)?,
        t.parse().ok()?,
        solve.parse().ok().filter(|&s| s > 0)?,
        iteration.parse().ok()?,
        r.parse().ok()?,
        outcome,
    ))
}

/// A row of the older form (`step,increment,iteration,relative_residual`, converged increments
/// only), `None` when malformed.
fn newton_row_v1(line: &str) -> Option<NewtonRow> {
    let cols: Vec<&str> = line.split(',').collect();
    let [step, inc, iteration, r] = cols.as_slice() else {
        return None;
    };
    Some((
        step.parse().ok()?,
        inc.parse().ok().filter(|&i| i > 0)?,
        f64::NAN,
        1,
        iteration.parse().ok()?,
        r.parse().ok()?,
        CONVERGED.to_string(),
    ))
}

/// The text of a CSV field as [`csv_field`] writes it; `None` for a quote out of place.
fn unquote(field: &str) -> Option<String> {
    match field.strip_prefix('"') {
        None => (!field.contains('"')).then(|| field.to_string()),
        Some(inner) => {
            let inner = inner.strip_suffix('"')?;
            let text = inner.replace("\"\"", "\"");
            (text.matches('"').count() * 2 == inner.matches('"').count()).then_some(text)
        }
    }
}

/// The residual series of one increment (`pick`, 1-based; the last one when `None`) of the
/// result folder `dir`, labelled by folder name.
///
/// # Errors
/// An unreadable `newton.csv`, a missing increment, or one with nothing to plot.
fn folder_series(dir: &Path, pick: Option<(usize, usize)>) -> Result<Series> {
    let logs = read_newton(dir)?;
    let mut converged = logs.iter().filter(|l| l.converged());
    let log = match pick {
        Some((s, i)) => converged.find(|l| l.step + 1 == s && l.increment == i),
        None => converged.max_by_key(|l| (l.step, l.increment)),
    }
    .ok_or_else(|| {
        // Failed attempts are not plotted; say so where the file has them.
        let failed = logs
            .iter()
            .filter(|l| pick.is_none_or(|(s, i)| l.step + 1 == s && l.increment == i))
            .count();
        let which = pick.map_or(String::new(), |(s, i)| format!(" {i} of step {s}"));
        let attempts = match failed {
            0 => String::new(),
            n => format!(" (only {n} failed attempt(s), which are not plotted)"),
        };
        FemError::Output(format!(
            "{}: no converged increment{which} in newton.csv{attempts}",
            dir.display()
        ))
    })?;
    let mut series = newton_series(log);
    if !series.is_drawn(newton_axes().log_y) {
        return Err(FemError::Output(format!(
            "{}: increment {} of step {} has no finite positive residual: nothing to plot",
            dir.join(NEWTON_CSV).display(),
            log.increment,
            log.step + 1
        )));
    }
    let name = dir.file_name().map_or_else(
        || dir.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    series.label = format!("{name} (step {} inc {})", log.step + 1, log.increment);
    Ok(series)
}

/// Overlays the residual history of one increment (`step`, `increment`, 1-based; the last
/// increment of the run when `None`) of each result folder, labelled by folder name.
///
/// # Errors
/// An output name not ending in `.png`, unreadable folders, a missing increment or one with
/// nothing to plot, drawing or file errors.
pub fn compare_newton(dirs: &[PathBuf], pick: Option<(usize, usize)>, out: &Path) -> Result<()> {
    check_png(out)?;
    let series = dirs
        .iter()
        .map(|dir| folder_series(dir, pick))
        .collect::<Result<Vec<_>>>()?;
    chart(out, &newton_axes(), &series)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_node_group_slave_reports_no_pressure() {
        let mut record = RunRecord::new(None);
        let columns = |area: f64| {
            [
                ("normal_force", 10.0),
                ("active", 4.0),
                ("max_penetration", 0.0),
                ("area", area),
                ("min_pressure", 2.0),
                ("max_pressure", 3.0),
            ]
            .map(|(k, v)| (format!("s-m_{k}"), v))
            .to_vec()
        };
        record.last = columns(0.0);
        let line = &record.contact_summary()[0];
        assert!(
            line.contains("4 closed nodes, pressure not available"),
            "{line}"
        );
        record.last = columns(1.0);
        let line = &record.contact_summary()[0];
        assert!(line.contains("pressure 2.000000e0 … 3.000000e0"), "{line}");
    }
    use crate::hertz::Hertz;

    fn record(samples: Vec<HertzSample>) -> RunRecord {
        let setup = HertzSetup {
            theory: Hertz {
                radius: 20.0,
                modulus: 2.0e5,
            },
            force_column: "a-b_normal_force".into(),
            centre: [0.0; 3],
            axis: [0.0, 0.0, 1.0],
            symmetry: 4.0,
            loaded: Vec::new(),
            slaves: Vec::new(),
        };
        RunRecord {
            hertz: Some((setup, samples)),
            ..RunRecord::default()
        }
    }

    fn sample(force: f64, profile: Vec<(f64, f64)>) -> HertzSample {
        HertzSample {
            step: 0,
            increment: 1,
            iterations: 2,
            force,
            approach: 0.01,
            fit: crate::hertz::fit_profile(&profile),
            max_pressure: profile.iter().map(|p| p.1).fold(0.0, f64::max),
            profile,
        }
    }

    #[test]
    fn undefined_values_are_said_and_left_empty_not_nan() {
        let rec = record(vec![sample(0.0, Vec::new())]);
        let lines = rec.hertz_summary();
        assert_eq!(lines.len(), 1);
        assert!(lines[0].contains("no contact force"), "{lines:?}");
        let table = hertz_table(
            &rec.hertz.as_ref().expect("hertz").0,
            &rec.hertz.as_ref().expect("hertz").1,
        );
        assert!(
            !table.to_lowercase().contains("nan") && !table.contains("inf"),
            "{table}"
        );
        // Force but two nodes: no fit, the summary says so.
        let rec = record(vec![sample(100.0, vec![(0.0, 50.0), (0.1, 40.0)])]);
        let lines = rec.hertz_summary();
        assert!(lines[0].contains("too few"), "{lines:?}");
        assert!(!lines.concat().to_lowercase().contains("nan"));
    }

    #[test]
    fn csv_fields_are_quoted_only_when_needed() {
        assert_eq!(csv_field("clamp_Rx"), "clamp_Rx");
        assert!(matches!(csv_field("1.5e-3"), Cow::Borrowed(_)));
        assert_eq!(csv_field("clamp,left_Rx"), "\"clamp,left_Rx\"");
        assert_eq!(csv_field("a \"b\""), "\"a \"\"b\"\"\"");
        assert_eq!(csv_field("a\r\nb"), "\"a\r\nb\"");
        assert_eq!(csv_field(""), "");
    }

    /// Failed attempts are labelled by what followed them (the last of a stopped run `failed`)
    /// and their outcome is one line, whatever their reason holds.
    #[test]
    fn attempts_are_labelled_and_kept_on_one_line() {
        use crate::driver::Retry;
        let attempt = |retry, reason: &str| Attempt {
            target: 0.5,
            reason: reason.to_string(),
            retry,
            relative: vec![1.0, 2.0],
            solve_starts: vec![0],
            notes: Vec::new(),
        };
        let attempts = [
            attempt(Retry::LineSearch, "element 3 inverted"),
            attempt(Retry::CutBack, "no convergence\nin 20 iterations\r"),
            attempt(Retry::CutBack, "element 4 inverted"),
        ];
        let outcomes = |stopped| -> Vec<String> {
            attempt_logs(1, 2, &attempts, stopped)
                .into_iter()
                .map(|l| l.outcome)
                .collect()
        };
        let running = outcomes(false);
        assert!(
            running[0].starts_with("failed: element 3 inverted; retried"),
            "{running:?}"
        );
        assert_eq!(running[1], "cut back: no convergence in 20 iterations ");
        assert_eq!(running[2], "cut back: element 4 inverted");
        assert_eq!(outcomes(true)[2], "failed: element 4 inverted");
    }

    /// `newton.csv` round trips: a converged increment after two failed attempts (an outcome
    /// with a comma and quotes, so quoted), another step of three solves (the augmented
    /// Lagrangian's), its iterations counted within each; the older form (converged increments
    /// only, no load factor) is still read; a malformed row, a row out of sequence or a stray
    /// quote is named by line.
    #[test]
    fn newton_table_round_trips() {
        let dir = std::env::temp_dir().join(format!("tricontact-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let log = |step, increment, load_factor, relative: &[f64], outcome: &str| NewtonLog {
            step,
            increment,
            load_factor,
            relative: relative.to_vec(),
            solve_starts: vec![0],
            outcome: outcome.to_string(),
        };
        let mut uzawa = log(
            1,
            1,
            1.0,
            &[1.0, 2e-12, 1.0, 3e-3, 4e-11, 0.5, 1e-13],
            CONVERGED,
        );
        uzawa.solve_starts = vec![0, 2, 5];
        let rec = RunRecord {
            newton: vec![
                log(0, 1, 0.5, &[1.0, 3.0, 7.5], "cut back: element 9 inverted"),
                log(0, 1, 0.25, &[1.0, 2.0], "failed: a, \"b\"; retried"),
                log(0, 1, 0.25, &[1.0, 1e-3, 1e-9], CONVERGED),
                uzawa,
            ],
            ..RunRecord::default()
        };
        rec.write_tables(&dir).expect("tables");
        let text = std::fs::read_to_string(dir.join("newton.csv")).expect("read");
        assert!(
            text.contains(",\"failed: a, \"\"b\"\"; retried\"\n"),
            "{text}"
        );
        assert!(
            text.ends_with("\n2,1,1,3,0,5e-1,converged\n2,1,1,3,1,1e-13,converged\n"),
            "{text}"
        );
        assert_eq!(read_newton(&dir).expect("read"), rec.newton);
        // A run's last converged increment is the one plotted.
        let series = folder_series(&dir, None).expect("series");
        assert!(series.label.ends_with("(step 2 inc 1)"), "{}", series.label);
        assert!(folder_series(&dir, Some((1, 1))).is_ok());
        // A run that stopped before any increment converged: its attempts are named, not drawn.
        let stopped = RunRecord {
            newton: rec.newton[..2].to_vec(),
            ..RunRecord::default()
        };
        stopped.write_tables(&dir).expect("tables");
        let e = folder_series(&dir, None)
            .expect_err("nothing converged")
            .to_string();
        assert!(
            e.ends_with("no converged increment in newton.csv (only 2 failed attempt(s), which are not plotted)"),
            "{e}"
        );
        let e = folder_series(&dir, Some((1, 2)))
            .expect_err("no such increment")
            .to_string();
        assert!(
            e.ends_with("no converged increment 2 of step 1 in newton.csv"),
            "{e}"
        );
        std::fs::write(
            dir.join("newton.csv"),
            "step,increment,iteration,relative_residual\n1,1,0,1\n1,1,1,1e-9\n",
        )
        .expect("write");
        let older = read_newton(&dir).expect("older form");
        assert_eq!(older.len(), 1);
        assert!(older[0].converged() && older[0].load_factor.is_nan());
        assert_eq!(older[0].relative, [1.0, 1e-9]);
        for (rows, line) in [
            ("step,increment,iteration,relative_residual\n1,x,0,1\n", 2),
            (
                &format!("{NEWTON_HEADER}\n1,1,0.5,1,0,1,converged\n1,1,0.5,1,1,2,a\"b\n"),
                3,
            ),
            (
                &format!("{NEWTON_HEADER}\n1,1,0.5,1,0,1,converged\n1,1,0.5,1,2,2,converged\n"),
                3,
            ),
            (
                // A second solve starts at its iteration 0, not 1.
                &format!("{NEWTON_HEADER}\n1,1,0.5,1,0,1,converged\n1,1,0.5,2,1,2,converged\n"),
                3,
            ),
            (&format!("{NEWTON_HEADER}\n1,1,0.5,0,0,1,converged\n"), 2),
        ] {
            std::fs::write(dir.join("newton.csv"), rows).expect("write");
            let e = read_newton(&dir).expect_err("malformed").to_string();
            assert!(e.contains(&format!("newton.csv:{line}")), "{e}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
