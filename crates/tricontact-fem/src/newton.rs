//! Newton–Raphson solution of one load increment.
//!
//! Small-strain steps are linear unless the extra terms say otherwise
//! ([`ExtraTerms::nonlinear`], e.g. contact) or follower loads act.
//!
//! Unknowns: free DOFs (and extra unknowns); prescribed DOFs move from their
//! committed values to the increment's targets `u_p`. Iteration 0 is the
//! linearised predictor `K_ff Δu_f = −(r_f + K_fp Δu_p)` assembled at the
//! committed state; then `K_ff δu = −r_f(u)` until convergence. In
//! small-strain steps (constant tangent) the factorization is computed once
//! per step and reused by every iteration and increment.
//!
//! Convergence (both must hold), with `r_ref = max(‖r⁰‖, ‖f_ext,f‖, ‖R‖, φ q̄)`
//! (`R` the reactions, `q̄` the step's force scale below) and `Δu = u − u_committed`:
//! * `‖r_f‖ ≤ tol_r · r_ref`;
//! * `‖δu_last‖ · min(1, ‖r_f^k‖/‖r_f^{k−1}‖) ≤ tol_u · max(‖Δu‖, 10⁻³‖u‖)`
//!   — the last correction scaled by the observed contraction, an estimate
//!   of the next one (so a linear problem converges after one solve); the
//!   floor `10⁻³‖u‖` keeps increments that change nothing from stalling.
//!
//! The force scale `q̄` is the time average of `r_ref` over the step's converged increments (the
//! previous step's, for a step's first increment; none for the first step's), and `φ` is
//! [`SCALE_FRACTION`] (10⁻²). It matters only where an increment has no force of its own: a body
//! that only translates, or one that has just left contact, carries no load and no reaction, and
//! an increment extrapolated from the last one starts exactly at its answer, so `r⁰` and every
//! residual are round-off (10⁻¹² where the step's forces were 10³); the relative test then
//! compared round-off with round-off and failed every such increment. Elsewhere `r_ref` is far
//! above `φ q̄` and the test is unchanged.
//!
//! Norms are weighted so that every entry is a force (residuals) or a length (corrections): an
//! extra unknown's equation counts `κ` times its residual and `1/κ` times its correction, `κ`
//! from [`ExtraTerms::residual_scales`] (for a contact multiplier the pair's penalty factor `α`:
//! `αP` is a force, `δλ/α` a length). The linear system is solved in the same scaled variables
//! (rows and columns of the extra unknowns times `κ`), so that its blocks share one scale. Norms
//! are computed without overflow or underflow of the squares.
//!
//! With the line search on ([`IncrementProblem::line_search`]: `[[step]] line_search = true`, or
//! `"auto"` once an element inverted, see [`crate::driver`]), each correction after the predictor
//! of a potential problem (no multipliers, no follower pressure) may be shortened by
//! [`crate::line_search`] before the next iteration.
//!
//! Failure (triggers a cutback in [`crate::driver`]): no convergence within
//! `max_iterations`, a non-finite or exploding residual (> 1e6 `r_ref`), an
//! inverted element, or a singular tangent.

use crate::analysis::{Analysis, Step};
use crate::assembly::{Assembled, AssemblyError, DofMap, ExtraTerms, NO_EQ, Pattern, assemble};
use crate::follower;
use crate::line_search::LineSearch;
use crate::linsolve::{LinearSolver, Structure};

/// A converged increment.
#[derive(Clone, Debug)]
pub struct Converged {
    /// Displacements (and extra unknowns), global DOFs.
    pub u: Vec<f64>,
    /// `r = f_int − f_ext (+ extra)` over all global DOFs at `u`.
    pub residual: Vec<f64>,
    /// What its iterations went through.
    pub trace: Trace,
    /// Linear solves performed.
    pub iterations: usize,
    /// Last factorization method.
    pub method: &'static str,
    /// Line-search trials (assemblies beyond one per iteration).
    pub line_searches: usize,
}

/// A solve that failed: why, and what its iterations went through, for the record of the
/// attempt.
#[derive(Clone, Debug, PartialEq)]
pub struct Failed {
    /// Why.
    pub failure: Failure,
    /// Its iterations (no residual when it failed at its first assembly).
    pub trace: Trace,
}

/// What the iterations of an increment's Newton solves went through, converged or not.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    /// Weighted residual norms over free equations: each solve's predictor, then each of its
    /// iterations.
    pub residuals: Vec<f64>,
    /// Where each solve starts in `residuals` (`[0]` for one solve; the augmented Lagrangian's
    /// successive solves follow each other).
    pub solve_starts: Vec<usize>,
    /// Reference norm of the relative test (the largest of the solves').
    pub reference: f64,
    /// Notes of the extra terms per assembly (see [`ExtraTerms::iteration_note`]), empty if it
    /// has none.
    pub notes: Vec<String>,
}

impl Default for Trace {
    /// One solve, nothing recorded yet.
    fn default() -> Self {
        Self {
            residuals: Vec::new(),
            solve_starts: vec![0],
            reference: 0.0,
            notes: Vec::new(),
        }
    }
}

impl Trace {
    /// The residual norms relative to the reference ([`relative_residuals`]).
    #[must_use]
    pub fn relative(&self) -> Vec<f64> {
        relative_residuals(&self.residuals, self.reference)
    }

    /// Appends the record of the solves that followed these (`later`): its residuals and notes
    /// after these, its solves numbered on, the larger reference.
    pub fn append(&mut self, later: Trace) {
        let offset = self.residuals.len();
        self.solve_starts
            .extend(later.solve_starts.iter().map(|s| s + offset));
        self.residuals.extend(later.residuals);
        self.notes.extend(later.notes);
        self.reference = self.reference.max(later.reference);
    }
}

/// Residual norms divided by the reference norm of the convergence test (the norms themselves when
/// the reference is zero).
#[must_use]
pub fn relative_residuals(residuals: &[f64], reference: f64) -> Vec<f64> {
    let scale = if reference > 0.0 { reference } else { 1.0 };
    residuals.iter().map(|r| r / scale).collect()
}

/// Why an increment failed.
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// Not converged or diverging.
    Diverged(String),
    /// Body element (Gmsh tag) with `det F ≤ 0`.
    Inverted(u64),
    /// Singular tangent.
    Singular(String),
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Diverged(s) => write!(f, "{s}"),
            Self::Inverted(t) => write!(f, "element {t} inverted (det F ≤ 0)"),
            Self::Singular(s) => write!(f, "singular tangent: {s}"),
        }
    }
}

/// The fraction `φ` of the step's force scale `q̄` below which the reference of the residual test
/// does not fall (see the module documentation).
pub const SCALE_FRACTION: f64 = 1e-2;

/// Relative residual or correction below which an unmet tolerance is taken to ask for more than
/// double precision gives: round-off in the assembled forces is about 10⁻¹⁶ of their terms, times
/// the conditioning of the model.
const ROUND_OFF: f64 = 1e-11;

/// Why an increment stalled with its `quantity` (`"residual"` or `"displacement"`) at the relative
/// value `value`, below [`ROUND_OFF`].
fn round_off_hint(quantity: &str, value: f64) -> String {
    format!(
        "; the {quantity} test stalled at round-off ({value:.1e}): `{quantity}_tolerance` asks for \
         more than double precision gives here — use 1e-10 or more"
    )
}

/// Euclidean norm, without overflow or underflow of the squares: entries of 10⁻¹⁷⁰ (or 10¹⁶⁰)
/// would otherwise give a norm of 0 (or ∞) and a wrong convergence decision.
fn norm(v: impl Iterator<Item = f64> + Clone) -> f64 {
    let sum: f64 = v.clone().map(|x| x * x).sum();
    if sum.is_normal() && sum < 1e300 && sum > 1e-300 {
        return sum.sqrt();
    }
    let scale = v.clone().fold(0.0f64, |m, x| m.max(x.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return if sum.is_nan() { f64::NAN } else { scale };
    }
    scale * v.map(|x| (x / scale).powi(2)).sum::<f64>().sqrt()
}

/// Norm of `v` weighted entry by entry by `w`.
fn weighted(v: &[f64], w: &[f64]) -> f64 {
    norm(v.iter().zip(w).map(|(a, b)| a * b))
}

/// Norm of `v` divided entry by entry by `w`.
fn divided(v: &[f64], w: &[f64]) -> f64 {
    norm(v.iter().zip(w).map(|(a, b)| a / b))
}

/// Weights of the convergence norms ([`ExtraTerms::residual_scales`]): per equation for residuals
/// (corrections are divided by them), per global DOF for displacements. The residual weights also
/// scale the linear system symmetrically (rows and columns of the extra unknowns).
struct Weights {
    residual: Vec<f64>,
    dof: Vec<f64>,
}

impl Weights {
    fn new(dm: &DofMap, scales: &[f64]) -> Self {
        let mut w = Self {
            residual: vec![1.0; dm.n_eq],
            dof: vec![1.0; dm.eq.len()],
        };
        for (k, &kappa) in scales.iter().enumerate() {
            let dof = dm.n_nodal + k;
            if dof < dm.eq.len() && kappa > 0.0 && kappa.is_finite() {
                w.dof[dof] = 1.0 / kappa;
                if dm.eq[dof] != NO_EQ {
                    w.residual[dm.eq[dof]] = kappa;
                }
            }
        }
        w
    }
}

/// Inputs fixed during an increment.
pub struct IncrementProblem<'a> {
    /// Analysis.
    pub an: &'a Analysis,
    /// Equation numbering.
    pub dm: &'a DofMap,
    /// Sparsity pattern.
    pub pat: &'a Pattern,
    /// Step controls.
    pub step: &'a Step,
    /// External forces over global DOFs at the increment's end.
    pub fext: &'a [f64],
    /// Prescribed DOFs and their values at the increment's end.
    pub prescribed: &'a [(usize, f64)],
    /// Follower pressures `(load index, pressure)` at the increment's end.
    pub follower: &'a [(usize, f64)],
    /// The force scale of the step so far, `q̄` (see the module documentation; zero for none).
    pub force_scale: f64,
    /// Line search along the corrections, where the residual is an energy gradient.
    pub line_search: bool,
}

/// The structure of an increment's tangent: unsymmetric with follower pressure or unsymmetric
/// terms, indefinite with multipliers. Where it is [`Structure::SymmetricDefinite`] the residual
/// is an energy gradient, and `[[step]] line_search` applies.
pub(crate) fn structure(extra: &dyn ExtraTerms, follower: &[(usize, f64)]) -> Structure {
    match (extra.symmetric() && follower.is_empty(), extra.definite()) {
        (false, _) => Structure::Unsymmetric,
        (true, true) => Structure::SymmetricDefinite,
        (true, false) => Structure::SymmetricIndefinite,
    }
}

impl IncrementProblem<'_> {
    /// Whether a line search applies to this increment: its residual is an energy gradient (the
    /// tangent's [`structure`] is symmetric definite: no multipliers, no follower pressure).
    pub(crate) fn line_search_applies(&self, extra: &dyn ExtraTerms) -> bool {
        structure(extra, self.follower) == Structure::SymmetricDefinite
    }
}

/// Solves one increment from the committed `u0`, iterating from `start` (`u0`, or the converged
/// state of a previous solve of the same increment in an outer loop); the correction test measures
/// `Δu` from `u0`.
///
/// # Errors
/// [`Failed`]: the [`Failure`] with the residuals of the iterations before it; the caller keeps
/// its committed state.
pub fn solve_increment(
    p: &IncrementProblem<'_>,
    extra: &mut dyn ExtraTerms,
    u0: &[f64],
    start: &[f64],
    solver: &mut LinearSolver,
) -> Result<Converged, Failed> {
    let mut it = Iterate::new(start, 0.0);
    match iterate(p, extra, (u0, start), solver, &mut it) {
        Ok(r) => Ok(it.converged(r)),
        Err(failure) => Err(Failed {
            failure,
            trace: it.take_trace(),
        }),
    }
}

/// The iterations of [`solve_increment`] on `it`, started at `start`; returns the full residual
/// at the converged `it.u`.
fn iterate(
    p: &IncrementProblem<'_>,
    extra: &mut dyn ExtraTerms,
    (u0, start): (&[f64], &[f64]),
    solver: &mut LinearSolver,
    it: &mut Iterate,
) -> Result<Vec<f64>, Failure> {
    let (an, dm) = (p.an, p.dm);
    let structure = structure(extra, p.follower);
    let weights = Weights::new(dm, &extra.residual_scales());
    let fext_norm = norm(
        (0..dm.eq.len())
            .filter(|&d| dm.eq[d] != NO_EQ)
            .map(|d| p.fext[d]),
    );
    it.reference = fext_norm.max(SCALE_FRACTION * p.force_scale);
    // Line search where the residual is an energy gradient: the correction being applied.
    let searching = p.line_search && p.line_search_applies(extra);
    // Small strain without extra or follower terms: the tangent is constant,
    // so the prescribed values are applied directly (the residual then
    // contains `K_fp Δu_p` exactly) and one factorization serves the step.
    // Otherwise the predictor adds `K_fp Δu_p` with the prescribed increments `dup`.
    let constant_tangent = !p.step.nlgeom && !extra.nonlinear() && p.follower.is_empty();
    let mut dup = vec![0.0; start.len()];
    for &(dof, v) in p.prescribed {
        if constant_tangent {
            it.u[dof] = v;
        } else {
            dup[dof] = v - start[dof];
        }
    }
    loop {
        let need_tangent = !(constant_tangent && solver.cached.is_some());
        let predictor_terms = (it.predictor && !constant_tangent).then_some(dup.as_slice());
        let assembled = assemble(
            an,
            dm,
            p.pat,
            &it.u,
            p.step.nlgeom,
            need_tangent,
            predictor_terms,
            extra,
        );
        let mut asm = match assembled {
            Ok(asm) => asm,
            // A line search halves a correction that inverts an element.
            Err(AssemblyError::Inverted(_)) if it.search_step(dm, None) => continue,
            Err(AssemblyError::Inverted(e)) => {
                return Err(Failure::Inverted(an.mesh.elements[an.body[e].element].tag));
            }
            Err(AssemblyError::Extra(m)) => return Err(Failure::Diverged(m)),
        };
        add_follower_terms(p, &it.u, &mut asm);
        let Residual {
            r,
            mut rhs,
            norm: rnorm,
            reactions,
        } = residual(p, &asm, &weights);
        if it.predictor {
            for (b, q) in rhs.iter_mut().zip(&asm.predictor) {
                *b += q;
            }
        }
        let current = weighted(&rhs, &weights.residual);
        if it.search_step(dm, Some(&rhs)) {
            continue;
        }
        it.search = None;
        if !current.is_finite() {
            return Err(Failure::Diverged("non-finite residual".into()));
        }
        if let Some(n) = extra.iteration_note() {
            it.notes.push(n);
        }
        it.residuals.push(current);
        it.reference = it.reference.max(reactions).max(it.residuals[0]);
        let done = if it.predictor {
            current == 0.0 && dup.iter().all(|&d| d == 0.0)
        } else {
            it.converged_at(p.step, u0, &weights.dof, rnorm)?
        };
        if done {
            return Ok(r);
        }
        if need_tangent {
            factor_tangent(p.pat, &mut asm, &weights, structure, solver)?;
        }
        let solved = correction(solver, &rhs, &weights);
        if !constant_tangent && let Some(f) = solver.cached.take() {
            solver.recycle(f);
        }
        let (du, method) = solved?;
        it.method = method;
        it.apply(p, du, &rhs, &weights, searching);
    }
}

/// The state of an increment's iterations.
struct Iterate {
    /// The present iterate (global DOFs and extra unknowns).
    u: Vec<f64>,
    /// Weighted residual norms: the predictor's, then each iteration's.
    residuals: Vec<f64>,
    /// `r_ref` of the relative residual test (module documentation).
    reference: f64,
    /// Weighted norm of the last correction as applied.
    du_norm: f64,
    /// Weighted norm of the last correction in full (a line search applies a fraction of it).
    full_norm: f64,
    /// The last factorization's method.
    method: &'static str,
    /// Linear solves so far.
    iterations: usize,
    /// `true` until the predictor's correction is applied.
    predictor: bool,
    /// The extra terms' notes, one per iteration that has one.
    notes: Vec<String>,
    /// The line search along the last correction, while it runs.
    search: Option<LineSearch>,
    /// Line-search trials so far.
    line_searches: usize,
}

impl Iterate {
    fn new(start: &[f64], reference: f64) -> Self {
        Self {
            u: start.to_vec(),
            residuals: Vec::new(),
            reference,
            du_norm: 0.0,
            full_norm: 0.0,
            method: "none",
            iterations: 0,
            predictor: true,
            notes: Vec::new(),
            search: None,
            line_searches: 0,
        }
    }

    /// Moves `u` to the line search's next trial, if one runs and asks for one (`rhs`, the
    /// residual's right-hand side at `u`, gives the slope; `None` where `u` inverted an element).
    fn search_step(&mut self, dm: &DofMap, rhs: Option<&[f64]>) -> bool {
        let Some(ls) = self.search.as_mut() else {
            return false;
        };
        let slope = rhs.map(|r| ls.slope(r)).filter(|g| g.is_finite());
        let Some(s) = ls.next(slope) else {
            return false;
        };
        self.du_norm = ls.move_to(s, &mut self.u, dm) * self.full_norm;
        self.line_searches += 1;
        true
    }

    /// Whether an iteration after the predictor, its free residual's weighted norm `rnorm`, meets
    /// both tests of the module documentation.
    ///
    /// # Errors
    /// A residual above 10⁶ `r_ref`, or no iterations left.
    fn converged_at(
        &self,
        step: &Step,
        u0: &[f64],
        dof_weights: &[f64],
        rnorm: f64,
    ) -> Result<bool, Failure> {
        let prev = self.residuals[self.residuals.len() - 2];
        let ratio = if prev > 0.0 {
            (rnorm / prev).min(1.0)
        } else {
            0.0
        };
        let du_total = norm(
            self.u
                .iter()
                .zip(u0)
                .zip(dof_weights)
                .map(|((a, b), w)| (a - b) * w),
        )
        .max(1e-3 * weighted(&self.u, dof_weights));
        let reference = self.reference;
        let residual_met = rnorm <= step.residual_tolerance * reference;
        if residual_met && self.du_norm * ratio <= step.displacement_tolerance * du_total {
            return Ok(true);
        }
        if rnorm > 1e6 * reference {
            return Err(Failure::Diverged(format!(
                "residual grew to {rnorm:.3e} (reference {reference:.3e})"
            )));
        }
        if self.iterations >= step.max_iterations {
            return Err(not_converged(
                step,
                self.iterations,
                residual_met,
                rnorm / reference,
                self.du_norm * ratio / du_total,
            ));
        }
        Ok(false)
    }

    /// Adds the correction `du` (free equations) to `u`; after the predictor, sets the prescribed
    /// values and, with `searching`, starts a line search along `du`.
    fn apply(
        &mut self,
        p: &IncrementProblem<'_>,
        du: Vec<f64>,
        rhs: &[f64],
        weights: &Weights,
        searching: bool,
    ) {
        for (dof, &e) in p.dm.eq.iter().enumerate() {
            if e != NO_EQ {
                self.u[dof] += du[e];
            }
        }
        self.full_norm = divided(&du, &weights.residual);
        self.du_norm = self.full_norm;
        if self.predictor {
            for &(dof, v) in p.prescribed {
                self.u[dof] = v;
            }
            self.predictor = false;
        } else if searching {
            self.search = Some(LineSearch::new(du, rhs));
        }
        self.iterations += 1;
    }

    /// The record of the iterations so far (taken out of `self`).
    fn take_trace(&mut self) -> Trace {
        Trace {
            residuals: std::mem::take(&mut self.residuals),
            solve_starts: vec![0],
            reference: self.reference,
            notes: std::mem::take(&mut self.notes),
        }
    }

    /// The converged increment, with `residual` the full residual at `u`.
    fn converged(mut self, residual: Vec<f64>) -> Converged {
        Converged {
            trace: self.take_trace(),
            u: self.u,
            residual,
            iterations: self.iterations,
            method: self.method,
            line_searches: self.line_searches,
        }
    }
}

/// An assembly's residual: `r = f_int − f_ext (+ extra)` over all global DOFs, the right-hand
/// side `−r_f` at the free equations, its weighted norm and the norm of the reactions (`r` at the
/// prescribed DOFs).
struct Residual {
    r: Vec<f64>,
    rhs: Vec<f64>,
    norm: f64,
    reactions: f64,
}

fn residual(p: &IncrementProblem<'_>, asm: &Assembled, weights: &Weights) -> Residual {
    let dm = p.dm;
    let mut r = asm.residual.clone();
    for (ri, fi) in r.iter_mut().zip(p.fext) {
        *ri -= fi;
    }
    let mut rhs = free_entries(dm, &r);
    for b in &mut rhs {
        *b = -*b;
    }
    let norm_free = weighted(&rhs, &weights.residual);
    let reactions = norm((0..dm.n_nodal).filter(|&d| dm.eq[d] == NO_EQ).map(|d| r[d]));
    Residual {
        r,
        rhs,
        norm: norm_free,
        reactions,
    }
}

/// Adds the follower pressures of `p` at `u` to the residual and their tangent to the extra
/// triplets of `asm` (free equations only).
fn add_follower_terms(p: &IncrementProblem<'_>, u: &[f64], asm: &mut Assembled) {
    let (an, dm) = (p.an, p.dm);
    if p.follower.is_empty() {
        return;
    }
    let mut trip = Vec::new();
    for &(li, pressure) in p.follower {
        if let Some((_, faces)) = &an.loads[li].follower {
            follower::pressure_terms(
                &an.mesh,
                faces,
                pressure,
                u,
                &mut asm.residual,
                Some(&mut trip),
            );
        }
    }
    for (r, c, v) in trip {
        let (er, ec) = (dm.eq[r], dm.eq[c]);
        if er != NO_EQ && ec != NO_EQ {
            asm.extra.push(faer::sparse::Triplet::new(er, ec, v));
        }
    }
}

/// The entries of the global vector `v` at the free equations, in equation order.
fn free_entries(dm: &DofMap, v: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; dm.n_eq];
    for (dof, &e) in dm.eq.iter().enumerate() {
        if e != NO_EQ {
            out[e] = v[dof];
        }
    }
    out
}

/// Factors the tangent of `asm` into `solver.cached`. The extra unknowns are taken in scaled
/// variables (multipliers `λ = κ μ`, constraint rows × κ): the tangent's blocks then share one
/// scale whatever the model's units, which keeps the factorization (and its `LDLᵀ` acceptance
/// test) independent of them.
fn factor_tangent(
    pat: &Pattern,
    asm: &mut Assembled,
    weights: &Weights,
    structure: Structure,
    solver: &mut LinearSolver,
) -> Result<(), Failure> {
    let w = &weights.residual;
    for t in &mut asm.extra {
        t.val *= w[t.row] * w[t.col];
    }
    let k = asm.matrix(pat);
    let factor = solver
        .factor(k.as_ref(), structure)
        .map_err(|s| Failure::Singular(s.0))?;
    solver.cached = Some(factor);
    Ok(())
}

/// The correction for the right-hand side `rhs` by the cached factorization (in the scaled
/// variables of [`factor_tangent`], scaled back), and the factorization's method.
fn correction(
    solver: &LinearSolver,
    rhs: &[f64],
    weights: &Weights,
) -> Result<(Vec<f64>, &'static str), Failure> {
    let factor = solver
        .cached
        .as_ref()
        .ok_or_else(|| Failure::Singular("no factorization".into()))?;
    let scaled: Vec<f64> = rhs
        .iter()
        .zip(&weights.residual)
        .map(|(r, w)| r * w)
        .collect();
    let mut du = factor.solve(&scaled);
    for (d, w) in du.iter_mut().zip(&weights.residual) {
        *d *= w;
    }
    if du.iter().any(|v| !v.is_finite()) {
        return Err(Failure::Singular("non-finite solution".into()));
    }
    Ok((du, factor.method()))
}

/// The failure of an increment that used its `iterations` without converging: which test is
/// unmet (`residual_met`: the `relative` residual's; else the estimated `correction` relative to
/// the increment), with a hint when it is held at round-off.
fn not_converged(
    step: &Step,
    iterations: usize,
    residual_met: bool,
    relative: f64,
    correction: f64,
) -> Failure {
    let hint = match (residual_met, relative, correction) {
        (false, r, _) if r < ROUND_OFF => round_off_hint("residual", r),
        (true, _, c) if c < ROUND_OFF => round_off_hint("displacement", c),
        _ => String::new(),
    };
    let unmet = if residual_met {
        format!(
            "relative residual {relative:.3e} met, estimated correction \
             {correction:.3e} > displacement_tolerance {:e}",
            step.displacement_tolerance
        )
    } else {
        format!(
            "relative residual {relative:.3e} > residual_tolerance {:e}",
            step.residual_tolerance
        )
    };
    Failure::Diverged(format!(
        "no convergence in {iterations} iteration{} ({unmet}){hint}",
        if iterations == 1 { "" } else { "s" }
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The solves of an increment recorded one after another: residuals and notes in order, each
    /// solve's start shifted by what came before, the larger reference; a record of two solves
    /// appended keeps both starts.
    #[test]
    fn traces_append_solve_after_solve() {
        let trace = |residuals: &[f64], starts: &[usize], reference, note: &str| Trace {
            residuals: residuals.to_vec(),
            solve_starts: starts.to_vec(),
            reference,
            notes: vec![note.to_string()],
        };
        let mut t = trace(&[4.0, 1e-9], &[0], 4.0, "a");
        t.append(trace(&[2.0, 3.0, 1e-10], &[0], 8.0, "b"));
        t.append(trace(&[1.0, 1e-11, 0.5, 1e-12], &[0, 2], 2.0, "c"));
        assert_eq!(
            t.residuals,
            [4.0, 1e-9, 2.0, 3.0, 1e-10, 1.0, 1e-11, 0.5, 1e-12]
        );
        assert_eq!(t.solve_starts, [0, 2, 5, 7]);
        assert_eq!(t.reference, 8.0);
        assert_eq!(t.notes, ["a", "b", "c"]);
        assert_eq!(t.relative()[0], 0.5);
        // A failure before any residual still counts as a solve that starts at the end.
        t.append(Trace::default());
        assert_eq!(t.solve_starts, [0, 2, 5, 7, 9]);
    }
}
