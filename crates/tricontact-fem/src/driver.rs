//! Steps and load increments with automatic cutback.
//!
//! Within step `s` the load factor `t` runs from 0 to 1. A load's amplitude
//! goes linearly from its value at the end of the previous step (1 if it was
//! active there, else 0) to 1 (active in `s`) or 0 (inactive). A
//! constrained DOF goes linearly from its displacement at the start of the
//! step to its target (0 for `fix`), reached at `t = 1`. DOFs of inactive
//! boundaries are free; the reaction a DOF carried when it is released is
//! applied as a force ramped from full to zero over the step.
//!
//! Increment control: start with `Δt = 1/increments`; on a [`Failure`] the
//! state is restored to the last converged increment and `Δt` is halved (at
//! most `max_cutbacks` times in a row, and never below `Δt₀/2^max_cutbacks`);
//! after two converged increments in a row `Δt` doubles back, up to its
//! initial value. State (`u` and the state
//! of the [`ExtraTerms`]) is committed only at converged increments and
//! restored on a cutback. When the extra terms ask for another solve after
//! Newton converged (an Uzawa update), the increment is solved again from the
//! converged state, at most [`MAX_OUTER`] times.
//!
//! Starting point ([`Extrapolation`]): with `linear` (the default), Newton
//! starts increment `n + 1` of a step from `u_n + (Δt_{n+1}/Δt_n)(u_n − u_{n−1})`,
//! all unknowns (multipliers too), so that a motion that carries on — a
//! slider moving on, a load growing — begins where the last increment points.
//! The first increment of a step and the retry after a cutback start from
//! `u_n`, as with `none`.
//!
//! Line search (`[[step]] line_search`): `true` and `false` hold for the whole step. With
//! `"auto"` (the default) the step starts without it; the first attempt that fails on an
//! inverted element where the line search applies (the residual is an energy gradient) is
//! retried at the same size with the line search, which stays on for the rest of the step. That
//! attempt is not a cutback ([`Retry::LineSearch`]); a line search costs
//! iterations where Newton recovers from an overshoot by itself, which is why it does not start on.

use crate::analysis::{Analysis, Load, Step};
use crate::assembly::{DofMap, ExtraTerms, Pattern, PointField, node_adjacency};
use crate::error::{FemError, Result};
use crate::linsolve::LinearSolver;
use crate::model::{Extrapolation, LineSearchMode};
use crate::newton::{
    Converged, Failed, Failure, IncrementProblem, relative_residuals, solve_increment,
};
use crate::ordering::equation_order;
use crate::rigid::check_supports;

/// What a converged increment reports to the observer.
#[derive(Debug)]
pub struct IncrementInfo<'a> {
    /// Step index (0-based).
    pub step: usize,
    /// Step name.
    pub step_name: &'a str,
    /// Increment number within the step (1-based).
    pub increment: usize,
    /// Load factor within the step, 0..=1.
    pub load_factor: f64,
    /// Total time: step index + load factor.
    pub time: f64,
    /// Newton iterations (linear solves).
    pub iterations: usize,
    /// Line-search trials ([`crate::line_search`]): assemblies beyond one per iteration.
    pub line_searches: usize,
    /// Residual norms (predictor, then each iteration).
    pub residuals: &'a [f64],
    /// Where each Newton solve starts in `residuals` (`[0]` for one; the augmented Lagrangian's
    /// successive solves follow each other).
    pub solve_starts: &'a [usize],
    /// Reference norm of the relative residual test.
    pub reference: f64,
    /// Cutbacks taken before this increment converged.
    pub cutbacks: usize,
    /// Displacements over global DOFs (`3a + i`, then extra unknowns).
    pub u: &'a [f64],
    /// Reaction forces at prescribed DOFs (0 elsewhere), global DOFs.
    pub reactions: &'a [f64],
    /// Finite strain.
    pub nlgeom: bool,
    /// Factorization used last.
    pub method: &'a str,
    /// Notes of the extra terms per Newton iteration (e.g. contact active set).
    pub notes: &'a [String],
    /// Extra point fields at the committed state (see
    /// [`ExtraTerms::point_fields`]).
    pub point_fields: &'a [PointField],
    /// Extra history columns at the committed state.
    pub history: &'a [(String, f64)],
    /// The attempts that failed before this increment converged.
    pub attempts: &'a [Attempt],
}

/// One failed attempt at an increment: the load factor it aimed at, why it failed, and how it was
/// retried.
#[derive(Debug, Clone, PartialEq)]
pub struct Attempt {
    /// The load factor the attempt aimed at.
    pub target: f64,
    /// Why it failed.
    pub reason: String,
    /// What came after it.
    pub retry: Retry,
    /// Its relative residuals (residual norms divided by the reference norm of the relative
    /// test, as [`IncrementInfo::relative_residuals`]): the predictor's, then each iteration's
    /// (with the augmented Lagrangian, the solves of successive updates after each other); empty
    /// when it failed at its first assembly.
    pub relative: Vec<f64>,
    /// Where each Newton solve starts in `relative` (see [`IncrementInfo::solve_starts`]).
    pub solve_starts: Vec<usize>,
    /// The extra terms' note of each of its iterations (see [`IncrementInfo::notes`]).
    pub notes: Vec<String>,
}

/// How a failed attempt was followed up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Retry {
    /// A smaller increment (a cutback), or none when the cutbacks ran out.
    CutBack,
    /// The same increment with the line search, on for the rest of the step
    /// (`line_search = "auto"`); not a cutback.
    LineSearch,
}

impl Attempt {
    /// What became of the attempt, as the verbose log and `newton.csv` name it: `cut back` when a
    /// smaller increment followed, `failed` when it was retried with the line search or it
    /// ended the run (`ended_run`).
    #[must_use]
    pub fn label(&self, ended_run: bool) -> &'static str {
        match self.retry {
            _ if ended_run => "failed",
            Retry::CutBack => "cut back",
            Retry::LineSearch => "failed",
        }
    }
}

impl std::fmt::Display for Attempt {
    /// The reason, followed by [`LINE_SEARCH_SWITCH`] for an attempt after which the line search
    /// came on.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.retry {
            Retry::CutBack => write!(f, "{}", self.reason),
            Retry::LineSearch => write!(f, "{}; {LINE_SEARCH_SWITCH}", self.reason),
        }
    }
}

impl IncrementInfo<'_> {
    /// The residual norms divided by the reference norm of the convergence test (the norms
    /// themselves when the reference is zero).
    #[must_use]
    pub fn relative_residuals(&self) -> Vec<f64> {
        relative_residuals(self.residuals, self.reference)
    }
}

/// Totals of a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunSummary {
    /// Converged increments.
    pub increments: usize,
    /// Newton iterations.
    pub iterations: usize,
    /// Cutbacks.
    pub cutbacks: usize,
    /// Steps in which `line_search = "auto"` switched the line search on.
    pub line_search_switches: usize,
    /// Final displacements.
    pub u: Vec<f64>,
}

/// Increment-size control of one step (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct IncrementControl {
    /// Initial (and largest) increment.
    pub dt0: f64,
    /// Current increment.
    pub dt: f64,
    /// Converged increments in a row since the last failure or growth.
    pub streak: usize,
    /// Cutbacks of the increment being attempted.
    pub cutbacks_here: usize,
    /// Allowed cutbacks per increment.
    pub max_cutbacks: usize,
}

impl IncrementControl {
    /// `increments` equal increments initially.
    #[must_use]
    pub fn new(increments: usize, max_cutbacks: usize) -> Self {
        let dt0 = 1.0 / increments.max(1) as f64;
        Self {
            dt0,
            dt: dt0,
            streak: 0,
            cutbacks_here: 0,
            max_cutbacks,
        }
    }

    /// Load factor at the end of the next increment from `t` (snaps to 1).
    #[must_use]
    pub fn target(&self, t: f64) -> f64 {
        if t + self.dt > 1.0 - 1e-9 {
            1.0
        } else {
            t + self.dt
        }
    }

    /// Records a converged increment; doubles `dt` (up to `dt0`) after two
    /// in a row.
    pub fn converged(&mut self) {
        self.cutbacks_here = 0;
        self.streak += 1;
        if self.streak >= 2 && self.dt < self.dt0 {
            self.dt = (2.0 * self.dt).min(self.dt0);
            self.streak = 0;
        }
    }

    /// Records a failed attempt: halves `dt`; `false` when the cutbacks of
    /// this increment are exhausted or `dt` would fall below the smallest increment,
    /// `dt0 / 2^max_cutbacks` (a step that keeps failing after converged half-increments
    /// otherwise creeps on with ever smaller ones).
    #[must_use]
    pub fn failed(&mut self) -> bool {
        self.cutbacks_here += 1;
        self.streak = 0;
        self.dt /= 2.0;
        self.cutbacks_here <= self.max_cutbacks && self.dt >= self.smallest()
    }

    /// The smallest increment allowed, `dt0 / 2^max_cutbacks`.
    #[must_use]
    pub fn smallest(&self) -> f64 {
        let halvings = i32::try_from(self.max_cutbacks).unwrap_or(i32::MAX);
        self.dt0 * 0.5f64.powi(halvings)
    }

    /// Why [`IncrementControl::failed`] gave up, for the error message.
    #[must_use]
    pub fn exhausted(&self) -> String {
        let n = self.max_cutbacks;
        if self.cutbacks_here > n {
            format!("after {n} cutback{}", if n == 1 { "" } else { "s" })
        } else {
            let k = self.cutbacks_here - 1;
            format!(
                "after {k} cutback{} of this increment, which is already the smallest \
                 max_cutbacks = {n} allows: 1/2^{n} of the initial one",
                if k == 1 { "" } else { "s" }
            )
        }
    }
}

/// Prescribed mask and targets of a step.
#[must_use]
pub fn step_constraints(an: &Analysis, s: usize) -> (Vec<bool>, Vec<(usize, f64)>) {
    let mut mask = vec![false; an.num_nodal_dofs()];
    let mut targets = Vec::new();
    for b in an.boundaries.iter().filter(|b| b.active[s]) {
        for &a in &b.nodes {
            for (i, v) in b.values.iter().enumerate() {
                if let Some(v) = v {
                    let dof = 3 * a + i;
                    if !mask[dof] {
                        mask[dof] = true;
                        targets.push((dof, *v));
                    }
                }
            }
        }
    }
    targets.sort_by_key(|t| t.0);
    (mask, targets)
}

/// Amplitude of load `l` in step `s` at load factor `t` (see module doc).
#[must_use]
pub fn amplitude(l: &Load, s: usize, t: f64) -> f64 {
    let prev = if s > 0 && l.active[s - 1] { 1.0 } else { 0.0 };
    let target = if l.active[s] { 1.0 } else { 0.0 };
    prev + t * (target - prev)
}

/// Follower pressures acting in step `s` at `t`: `(load index, p × amplitude)`.
#[must_use]
pub fn follower_pressures(an: &Analysis, s: usize, t: f64) -> Vec<(usize, f64)> {
    if !an.steps[s].nlgeom {
        return Vec::new();
    }
    an.loads
        .iter()
        .enumerate()
        .filter_map(|(i, l)| {
            let (p, _) = l.follower.as_ref()?;
            let amp = amplitude(l, s, t);
            (amp != 0.0).then_some((i, p * amp))
        })
        .collect()
}

/// External dead-load vector (global DOFs) in step `s` at load factor `t`
/// (follower pressures of `nlgeom` steps excluded: see [`follower_pressures`]).
#[must_use]
pub fn external_forces(an: &Analysis, n_dofs: usize, s: usize, t: f64) -> Vec<f64> {
    let mut f = vec![0.0; n_dofs];
    for l in &an.loads {
        if l.follower.is_some() && an.steps[s].nlgeom {
            continue;
        }
        let amp = amplitude(l, s, t);
        if amp == 0.0 {
            continue;
        }
        for (a, v) in &l.forces {
            for i in 0..3 {
                f[3 * a + i] += amp * v[i];
            }
        }
    }
    f
}

/// Added to a singular-tangent failure of a model with multipliers when [`ExtraTerms::singular_cause`]
/// names no node: their usual cause.
const MULTIPLIER_HINT: &str = "; with Lagrange multipliers this usually means slave nodes are prescribed along the contact normal, so their constraints act on the master nodes alone and repeat each other: free those components or use method = \"penalty\"";

/// Appended to the reason a step fails on an inverted element when its line search is off and
/// would apply (the residual is an energy gradient: no multipliers, no follower pressure).
const LINE_SEARCH_HINT: &str = "; line_search = true (or \"auto\", the default) in this [[step]] may get through: it shortens a Newton correction that inverts an element";

/// Appended to the reason of an attempt after which `line_search = "auto"` switched the line
/// search on, when it is shown ([`Attempt`]'s `Display`).
pub const LINE_SEARCH_SWITCH: &str =
    "retried at the same size with the line search, on for the rest of the step";

/// Most solves of one increment asked for by [`ExtraTerms::after_converged`].
pub const MAX_OUTER: usize = 50;

/// Runs all steps; `observer` sees each converged increment.
///
/// # Errors
/// Singular model, non-convergence after all cutbacks, observer errors.
pub fn run(
    an: &Analysis,
    extra: &mut dyn ExtraTerms,
    observer: &mut dyn FnMut(&IncrementInfo<'_>) -> Result<()>,
) -> Result<RunSummary> {
    let n_dofs = an.num_nodal_dofs() + extra.num_extra();
    let mut carried = Carried {
        summary: RunSummary {
            u: vec![0.0; n_dofs],
            ..RunSummary::default()
        },
        mask: Vec::new(),
        reactions: vec![0.0; n_dofs],
        force_scale: 0.0,
    };
    for s in 0..an.steps.len() {
        run_step(an, s, extra, &mut carried, observer)?;
    }
    Ok(carried.summary)
}

/// What one step hands to the next.
struct Carried {
    /// The run's totals so far, with the committed state `u`.
    summary: RunSummary,
    /// The constrained DOFs of the last step (empty before the first).
    mask: Vec<bool>,
    /// The reactions of the last converged increment, global DOFs.
    reactions: Vec<f64>,
    /// The force scale `q̄` of the last step (see `newton`): the first increment of a step uses it.
    force_scale: f64,
}

/// What a step fixes before its first increment: its constraints (the prescribed mask and the
/// targets of the prescribed DOFs), equation numbering, matrix pattern and linear solver (with
/// its equation order), the displacements it starts from, and the reactions of the DOFs it
/// releases (ramped down to zero over the step).
struct StepSystem {
    mask: Vec<bool>,
    targets: Vec<(usize, f64)>,
    dm: DofMap,
    pat: Pattern,
    solver: LinearSolver,
    u_step: Vec<f64>,
    released: Vec<(usize, f64)>,
}

impl StepSystem {
    /// The system of step `s` from the committed state in `carried`.
    ///
    /// # Errors
    /// A body with too few supports (when the extra terms cannot hold bodies).
    fn new(an: &Analysis, s: usize, extra: &dyn ExtraTerms, carried: &Carried) -> Result<Self> {
        let step = &an.steps[s];
        let (mask, targets) = step_constraints(an, s);
        if !extra.supports_bodies() {
            check_supports(an, &mask)
                .map_err(|m| FemError::Singular(format!("step '{}': {m}", step.name)))?;
        }
        let dm = DofMap::new(&an.active_nodes, &mask, extra.num_extra());
        let adj = node_adjacency(an);
        let pat = Pattern::from_adjacency(&adj, an, &dm);
        let extras = (extra.extra_nodes(), extra.extra_late());
        let order = equation_order(&an.mesh.nodes, &adj, &dm, (&extras.0, &extras.1));
        let released = (0..an.num_nodal_dofs())
            .filter(|&d| carried.mask.get(d).copied().unwrap_or(false) && !mask[d])
            .map(|d| (d, carried.reactions[d]))
            .collect();
        Ok(Self {
            mask,
            targets,
            dm,
            pat,
            solver: LinearSolver::new().with_order(order),
            u_step: carried.summary.u.clone(),
            released,
        })
    }

    /// The loads at load factor `t` of step `s`: external forces (with the released reactions'
    /// remainder), prescribed values and follower pressures.
    fn loads(&self, an: &Analysis, s: usize, t: f64) -> Loads {
        let mut fext = external_forces(an, self.u_step.len(), s, t);
        for &(d, r) in &self.released {
            fext[d] += (1.0 - t) * r;
        }
        let u = &self.u_step;
        let prescribed = self
            .targets
            .iter()
            .map(|&(dof, v)| (dof, u[dof] + t * (v - u[dof])))
            .collect();
        Loads {
            fext,
            prescribed,
            follower: follower_pressures(an, s, t),
        }
    }
}

/// The loads of one increment (see [`StepSystem::loads`]).
struct Loads {
    fext: Vec<f64>,
    prescribed: Vec<(usize, f64)>,
    follower: Vec<(usize, f64)>,
}

/// Runs step `s` from the committed state in `carried`, increment by increment with cutbacks.
fn run_step(
    an: &Analysis,
    s: usize,
    extra: &mut dyn ExtraTerms,
    carried: &mut Carried,
    observer: &mut dyn FnMut(&IncrementInfo<'_>) -> Result<()>,
) -> Result<()> {
    let step = &an.steps[s];
    let mut system = StepSystem::new(an, s, extra, carried)?;
    let mut control = IncrementControl::new(step.increments, step.max_cutbacks);
    let mut t = 0.0;
    let mut increment = 0;
    let mut attempts: Vec<Attempt> = Vec::new();
    // The last converged increment of this step: `u_n − u_{n−1}` and its `Δt`.
    let mut last: Option<(Vec<f64>, f64)> = None;
    // `∫ r_ref dt` over the step's converged increments, for the force scale `q̄`.
    let mut reference_integral = 0.0;
    // Where the residual is an energy gradient: `line_search = "auto"` switches it on below.
    let mut line_search = step.line_search == LineSearchMode::On;
    while t < 1.0 - 1e-12 {
        let t_new = control.target(t);
        let loads = system.loads(an, s, t_new);
        let problem = IncrementProblem {
            an,
            dm: &system.dm,
            pat: &system.pat,
            step,
            fext: &loads.fext,
            prescribed: &loads.prescribed,
            follower: &loads.follower,
            force_scale: if t > 0.0 {
                reference_integral / t
            } else {
                carried.force_scale
            },
            line_search,
        };
        let u = &carried.summary.u;
        let start = match (&last, step.extrapolation, attempts.is_empty()) {
            (Some((du, dt)), Extrapolation::Linear, true) => extrapolated(u, du, (t_new - t) / dt),
            _ => u.clone(),
        };
        match solve_with_outer(&problem, extra, u, &start, &mut system.solver) {
            Ok(c) => {
                extra.commit();
                let du = c.u.iter().zip(u).map(|(a, b)| a - b).collect();
                last = Some((du, t_new - t));
                reference_integral += c.trace.reference * (t_new - t);
                t = t_new;
                increment += 1;
                let at = Reached {
                    s,
                    increment,
                    t,
                    cutbacks: control.cutbacks_here,
                };
                commit(
                    an,
                    at,
                    c,
                    (&system.targets, &attempts),
                    extra,
                    carried,
                    observer,
                )?;
                attempts.clear();
                control.converged();
            }
            Err(failed) if switches_line_search(&problem, &failed.failure, extra) => {
                // Retried at the same size, with the line search from now on.
                extra.restore();
                line_search = true;
                carried.summary.line_search_switches += 1;
                attempts.push(Attempt {
                    target: t_new,
                    reason: failed.failure.to_string(),
                    retry: Retry::LineSearch,
                    relative: failed.trace.relative(),
                    solve_starts: failed.trace.solve_starts,
                    notes: failed.trace.notes,
                });
            }
            Err(failed) => {
                carried.summary.cutbacks += 1;
                cut_back(
                    &problem,
                    (t, t_new),
                    failed,
                    extra,
                    &mut control,
                    &mut attempts,
                )?;
            }
        }
    }
    carried.mask = system.mask;
    carried.force_scale = reference_integral / t;
    Ok(())
}

/// Where a converged increment ends: step `s`, its increment number in the step, load factor `t`
/// and the cutbacks it took.
#[derive(Clone, Copy)]
struct Reached {
    s: usize,
    increment: usize,
    t: f64,
    cutbacks: usize,
}

/// Commits the converged increment `c` into `carried` (displacements, counts, the reactions at
/// the prescribed DOFs `targets`) and shows it to `observer` with the `attempts` before it.
///
/// # Errors
/// The observer's.
fn commit(
    an: &Analysis,
    at: Reached,
    c: Converged,
    (targets, attempts): (&[(usize, f64)], &[Attempt]),
    extra: &mut dyn ExtraTerms,
    carried: &mut Carried,
    observer: &mut dyn FnMut(&IncrementInfo<'_>) -> Result<()>,
) -> Result<()> {
    let step = &an.steps[at.s];
    let summary = &mut carried.summary;
    summary.increments += 1;
    summary.iterations += c.iterations;
    carried.reactions.fill(0.0);
    for &(dof, _) in targets {
        carried.reactions[dof] = c.residual[dof];
    }
    summary.u = c.u;
    let point_fields = extra.point_fields();
    let history = extra.history();
    observer(&IncrementInfo {
        step: at.s,
        step_name: &step.name,
        increment: at.increment,
        load_factor: at.t,
        time: at.s as f64 + at.t,
        iterations: c.iterations,
        line_searches: c.line_searches,
        residuals: &c.trace.residuals,
        solve_starts: &c.trace.solve_starts,
        reference: c.trace.reference,
        cutbacks: at.cutbacks,
        u: &summary.u,
        reactions: &carried.reactions,
        nlgeom: step.nlgeom,
        method: c.method,
        notes: &c.trace.notes,
        point_fields: &point_fields,
        history: &history,
        attempts,
    })
}

/// After the attempt at `t_new` from `t` failed: restores the extra terms' state and records the
/// attempt for a retry with a smaller increment.
///
/// # Errors
/// A singular tangent of a small-strain step (a smaller increment cannot help), or the step's
/// cutbacks used up.
fn cut_back(
    problem: &IncrementProblem<'_>,
    (t, t_new): (f64, f64),
    failed: Failed,
    extra: &mut dyn ExtraTerms,
    control: &mut IncrementControl,
    attempts: &mut Vec<Attempt>,
) -> Result<()> {
    let step = problem.step;
    let relative = failed.trace.relative();
    let Failed { failure, trace } = failed;
    let (notes, solve_starts) = (trace.notes, trace.solve_starts);
    let hint = failure_hint(&failure, extra, problem.dm);
    extra.restore();
    if let (Failure::Singular(m), false) = (&failure, step.nlgeom) {
        let gap = open_gap_hint(problem, t);
        return Err(FemError::Singular(format!(
            "step '{}': {m}{hint}{gap}",
            step.name
        )));
    }
    attempts.push(Attempt {
        target: t_new,
        reason: failure.to_string(),
        retry: Retry::CutBack,
        relative,
        solve_starts,
        notes,
    });
    if control.failed() {
        return Ok(());
    }
    let search_hint = line_search_hint(&failure, step, problem.line_search_applies(extra));
    let gap = open_gap_hint(problem, t);
    Err(FemError::NotConverged {
        step: step.name.clone(),
        load_factor: t,
        target: t_new,
        reason: format!("{failure}{hint}{search_hint}{gap}"),
        exhausted: control.exhausted(),
        attempts: std::mem::take(attempts),
    })
}

/// What to add to the reason of a first step that fails before its first increment converged
/// (at load factor `t = 0`): the body parts only contact across a gap holds, if any
/// ([`Analysis::open_gap_support`]).
fn open_gap_hint(problem: &IncrementProblem<'_>, t: f64) -> String {
    let first = problem
        .an
        .steps
        .first()
        .is_some_and(|s| std::ptr::eq(s, problem.step));
    if first && t == 0.0 {
        problem
            .an
            .open_gap_support()
            .iter()
            .map(crate::analysis::OpenGap::hint)
            .collect()
    } else {
        String::new()
    }
}

/// What to add to a failure's reason: for a singular tangent with extra unknowns
/// (multipliers), the cause the extra terms name, else their usual cause ([`MULTIPLIER_HINT`]).
fn failure_hint(failure: &Failure, extra: &dyn ExtraTerms, dm: &DofMap) -> String {
    match (failure, extra.num_extra() > 0) {
        (Failure::Singular(_), true) => extra
            .singular_cause(dm)
            .map_or_else(|| MULTIPLIER_HINT.to_string(), |c| format!("; {c}")),
        _ => String::new(),
    }
}

/// Whether `line_search = "auto"` switches the line search on after `failure`: an inverted element,
/// in a step where it applies (the residual is an energy gradient) and is still off.
fn switches_line_search(
    problem: &IncrementProblem<'_>,
    failure: &Failure,
    extra: &dyn ExtraTerms,
) -> bool {
    problem.step.line_search == LineSearchMode::Auto
        && !problem.line_search
        && matches!(failure, Failure::Inverted(_))
        && problem.line_search_applies(extra)
}

/// [`LINE_SEARCH_HINT`] for a step that fails on an inverted element where the line search
/// would apply (`searchable`: the residual is an energy gradient) and is off.
fn line_search_hint(failure: &Failure, step: &Step, searchable: bool) -> &'static str {
    if matches!(failure, Failure::Inverted(_))
        && searchable
        && step.line_search == LineSearchMode::Off
    {
        LINE_SEARCH_HINT
    } else {
        ""
    }
}

/// `u + ratio · du`: the start of an increment extrapolated from the last one.
fn extrapolated(u: &[f64], du: &[f64], ratio: f64) -> Vec<f64> {
    u.iter().zip(du).map(|(a, d)| a + ratio * d).collect()
}

/// One increment from the committed `u0`, Newton starting at `start`, repeated
/// from the converged state while the extra terms ask for it (outer loop).
/// Residual histories and iteration counts of the solves are concatenated (those of a failure too).
fn solve_with_outer(
    problem: &IncrementProblem<'_>,
    extra: &mut dyn ExtraTerms,
    u0: &[f64],
    start: &[f64],
    solver: &mut LinearSolver,
) -> std::result::Result<Converged, Failed> {
    // A failure of the extra terms themselves, after the solves `c` (none before the first).
    let failed = |failure: String, c: Option<&Converged>| Failed {
        failure: Failure::Diverged(failure),
        trace: c.map(|c| c.trace.clone()).unwrap_or_default(),
    };
    extra.begin_increment(u0).map_err(|e| failed(e, None))?;
    let mut c = solve_increment(problem, extra, u0, start, solver)?;
    let mut outer = 0;
    while !extra
        .after_converged(&c.u)
        .map_err(|e| failed(e, Some(&c)))?
    {
        outer += 1;
        if outer > MAX_OUTER {
            let why = extra
                .outer_note()
                .map_or_else(String::new, |n| format!(": {n}"));
            return Err(failed(
                format!("outer (Uzawa) loop not converged in {MAX_OUTER} solves{why}"),
                Some(&c),
            ));
        }
        // The solves of the increment follow each other in its record, failed or not.
        let next = match solve_increment(problem, extra, u0, &c.u, solver) {
            Ok(next) => next,
            Err(f) => {
                c.trace.append(f.trace);
                return Err(Failed {
                    failure: f.failure,
                    trace: c.trace,
                });
            }
        };
        let mut trace = c.trace;
        trace.append(next.trace);
        c = Converged {
            trace,
            iterations: c.iterations + next.iterations,
            line_searches: c.line_searches + next.line_searches,
            ..next
        };
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_on_failure_and_grows_back_after_two_successes() {
        let mut c = IncrementControl::new(4, 2);
        assert!((c.target(0.0) - 0.25).abs() < 1e-15);
        assert!(c.failed());
        assert!(c.failed());
        assert!((c.dt - 0.0625).abs() < 1e-15);
        assert!(!c.failed(), "third cutback exceeds max_cutbacks = 2");
        assert_eq!(c.exhausted(), "after 2 cutbacks");
        // Converged half-increments do not let the increment shrink below dt0 / 2^2.
        let mut c = IncrementControl::new(4, 2);
        assert!(c.failed() && c.failed());
        c.converged();
        assert!(
            !c.failed(),
            "1/16 is below the smallest increment, 1/4 / 2^2"
        );
        assert_eq!(
            c.exhausted(),
            "after 0 cutbacks of this increment, which is already the smallest max_cutbacks = 2 \
             allows: 1/2^2 of the initial one"
        );
        let mut c = IncrementControl::new(4, 2);
        assert!(c.failed() && c.failed());
        c.converged();
        assert!((c.dt - 0.0625).abs() < 1e-15, "one success: no growth");
        c.converged();
        assert!((c.dt - 0.125).abs() < 1e-15);
        c.converged();
        c.converged();
        assert!((c.dt - 0.25).abs() < 1e-15);
        c.converged();
        c.converged();
        assert!(
            (c.dt - 0.25).abs() < 1e-15,
            "never beyond the initial increment"
        );
        assert!(
            (c.target(0.9) - 1.0).abs() < 1e-15,
            "snaps to the end of the step"
        );
    }
}
