//! Sparse direct solution of the Newton systems with faer.
//!
//! Symmetric systems are factored with a supernodal/simplicial Cholesky
//! `K = L Lᵀ` (lower triangle read), with a caller-supplied fill-reducing
//! ordering (nested dissection, [`crate::ordering`]) or faer's AMD. When that fails (not positive
//! definite: the saddle-point systems of contact multipliers, or past a limit point), the same
//! symbolic structure is used for `K = L D Lᵀ` without pivoting, accepted only if the solution of
//! `K x = K·1` has a small backward error (`‖K x − b‖ ≤ 10⁻¹⁰ (‖K‖_F ‖x‖ + ‖b‖)`); otherwise,
//! and for unsymmetric systems, a sparse LU with partial pivoting is used. A rejected `LDLᵀ` is not
//! tried again by the same solver (one per step): a body held only by contact makes the
//! displacement block singular, and without pivoting every factorization then loses accuracy
//! (the contact patch test: backward error 3·10⁻⁶). Each multiplier is ordered
//! after the nested-dissection block of its slave node ([`crate::ordering`]), so the
//! displacements it constrains there come first, its `LDLᵀ` pivot is a (negative) Schur
//! complement `−bᵀK̃⁻¹b` and no pivoting is needed (also for a node's two multipliers at a
//! concave kink, while their rows are independent; where they repeat each other, LU takes
//! over, or the system is singular and the contact layer names the nodes). The symbolic
//! analysis (fill-reducing ordering, elimination tree) is kept and reused while the pattern is
//! unchanged, and so is the memory of the numeric factorizations: a factor given back
//! ([`LinearSolver::recycle`]) lends its values to the next one, and the scratch space is kept. A
//! failed LU, or a non-finite solution, is reported as a singular system.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::solvers::Solve;
use faer::perm::PermRef;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{
    LdltRef, LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::{Conj, Side};

/// Numeric Cholesky factor with its (shared) symbolic structure.
#[derive(Debug)]
pub struct Cholesky {
    symbolic: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
}

/// A factorization ready to solve.
#[derive(Debug)]
pub enum Factor {
    /// Cholesky.
    Llt(Cholesky),
    /// `L D Lᵀ` without pivoting (symmetric indefinite).
    Ldlt(Cholesky),
    /// LU with partial pivoting.
    Lu(Box<Lu<usize, f64>>),
}

impl Factor {
    /// Solves `K x = b`.
    #[must_use]
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut rhs = faer::Mat::<f64>::from_fn(b.len(), 1, |i, _| b[i]);
        match self {
            Self::Llt(f) | Self::Ldlt(f) => {
                let par = faer::get_global_parallelism();
                let mut mem = MemBuffer::new(f.symbolic.solve_in_place_scratch::<f64>(1, par));
                let (rhs, stack) = (rhs.as_mut(), MemStack::new(&mut mem));
                if matches!(self, Self::Llt(_)) {
                    LltRef::new(&f.symbolic, &f.values).solve_in_place_with_conj(
                        Conj::No,
                        rhs,
                        par,
                        stack,
                    );
                } else {
                    LdltRef::new(&f.symbolic, &f.values).solve_in_place_with_conj(
                        Conj::No,
                        rhs,
                        par,
                        stack,
                    );
                }
            }
            Self::Lu(f) => f.solve_in_place(rhs.as_mut()),
        }
        (0..b.len()).map(|i| rhs[(i, 0)]).collect()
    }

    /// Stored entries of the Cholesky factor (0 for LU) and whether it is
    /// supernodal.
    #[must_use]
    pub fn factor_size(&self) -> (usize, bool) {
        match self {
            Self::Llt(f) | Self::Ldlt(f) => (
                f.values.len(),
                matches!(
                    f.symbolic.raw(),
                    faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Supernodal(_)
                ),
            ),
            Self::Lu(_) => (0, false),
        }
    }

    /// `"cholesky"`, `"ldlt"` or `"lu"`.
    #[must_use]
    pub fn method(&self) -> &'static str {
        match self {
            Self::Llt(_) => "cholesky",
            Self::Ldlt(_) => "ldlt",
            Self::Lu(_) => "lu",
        }
    }
}

/// What is known of a matrix before it is factored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Structure {
    /// Symmetric, expected positive definite: Cholesky, then `LDLᵀ`, then LU.
    SymmetricDefinite,
    /// Symmetric indefinite (saddle point of multipliers): `LDLᵀ`, then LU.
    SymmetricIndefinite,
    /// Unsymmetric: LU.
    Unsymmetric,
}

/// Why a factorization failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Singular(pub String);

/// Factorizer with cached symbolic analyses.
#[derive(Debug, Default)]
pub struct LinearSolver {
    llt: Option<Arc<SymbolicCholesky<usize>>>,
    lu: Option<SymbolicLu<usize>>,
    /// Fill-reducing order `new → old` (AMD when `None`).
    order: Option<(Vec<usize>, Vec<usize>)>,
    /// A factorization kept for reuse while the tangent is constant.
    pub cached: Option<Factor>,
    /// `LDLᵀ` was rejected once: go straight to LU from then on (kept by [`Self::reset`]).
    ldlt_rejected: bool,
    /// The key ([`pattern_key`]) of the pattern the symbolic analyses were made for.
    pattern: Option<PatternKey>,
    /// Memory of earlier factorizations, reused by the next (see [`Buffers`]).
    buffers: Buffers,
}

/// The values of a Cholesky factor given back ([`LinearSolver::recycle`]) and the scratch space of
/// the last numeric factorization, kept for the next one. Allocated afresh for each factorization,
/// both came from the system as new pages, which it zeroed and mapped one fault at a time: on the
/// fine Hertz mesh, 3 % of the run's processor time (`perf`), on the thread that waits for the
/// factorization.
#[derive(Default)]
struct Buffers {
    values: Vec<f64>,
    scratch: Option<(StackReq, MemBuffer)>,
}

impl std::fmt::Debug for Buffers {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Buffers")
            .field("values", &self.values.capacity())
            .field("scratch", &self.scratch.as_ref().map(|(req, _)| req))
            .finish()
    }
}

impl Buffers {
    /// A vector of `len` zeros, in the kept values' memory when it is large enough.
    fn values(&mut self, len: usize) -> Vec<f64> {
        let mut v = std::mem::take(&mut self.values);
        v.clear();
        v.resize(len, 0.0);
        v
    }

    /// Scratch space for `req`: the kept one if it is large and aligned enough.
    fn scratch(&mut self, req: StackReq) -> Result<&mut MemBuffer, Singular> {
        let fits = self.scratch.as_ref().is_some_and(|(kept, _)| {
            kept.size_bytes() >= req.size_bytes() && kept.align_bytes() >= req.align_bytes()
        });
        if !fits {
            self.scratch = None;
            let buffer = MemBuffer::try_new(req).map_err(|_| Singular("out of memory".into()))?;
            self.scratch = Some((req, buffer));
        }
        Ok(&mut self.scratch.as_mut().expect("kept above").1)
    }
}

/// Size, entry count and a hash of a sparsity pattern's column pointers and row indices.
type PatternKey = (usize, usize, usize, u64);

/// The key of `a`'s pattern: equal patterns give equal keys, and a changed one (another mesh,
/// contact constraints added) differs but for a 64-bit hash collision. It costs one pass over
/// the indices, small beside a factorization.
fn pattern_key(a: SparseColMatRef<'_, usize, f64>) -> PatternKey {
    let sym = a.symbolic();
    let mut hash = 0xcbf2_9ce4_8422_2325_u64;
    for &i in sym.col_ptr().iter().chain(sym.row_idx()) {
        hash = (hash ^ i as u64).wrapping_mul(0x0000_0100_0000_01b3);
    }
    (a.nrows(), a.ncols(), sym.row_idx().len(), hash)
}

impl LinearSolver {
    /// Creates a solver with no cached analysis.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Uses the equation order `perm` (`new → old`) for Cholesky.
    ///
    /// # Panics
    /// If `perm` is not a permutation.
    #[must_use]
    pub fn with_order(mut self, perm: Vec<usize>) -> Self {
        let mut inv = vec![usize::MAX; perm.len()];
        for (new, &old) in perm.iter().enumerate() {
            inv[old] = new;
        }
        assert!(inv.iter().all(|&i| i != usize::MAX), "not a permutation");
        self.order = Some((perm, inv));
        self.llt = None;
        self
    }

    /// Forgets the symbolic analyses and the cached factorization. A matrix of another pattern
    /// is analysed afresh without it; call it to drop a factorization kept in
    /// [`Self::cached`].
    pub fn reset(&mut self) {
        self.llt = None;
        self.lu = None;
        if let Some(f) = self.cached.take() {
            self.recycle(f);
        }
        self.pattern = None;
    }

    /// Takes back a factorization that is no longer needed, so that the next one reuses its
    /// memory.
    pub fn recycle(&mut self, f: Factor) {
        if let Factor::Llt(c) | Factor::Ldlt(c) = f
            && c.values.capacity() > self.buffers.values.capacity()
        {
            self.buffers.values = c.values;
        }
    }

    /// Resets the solver if `a`'s pattern is not the one it analysed.
    fn adopt(&mut self, a: SparseColMatRef<'_, usize, f64>) {
        let key = pattern_key(a);
        if self.pattern != Some(key) {
            self.reset();
            self.pattern = Some(key);
        }
    }

    /// Symbolic Cholesky analysis only (for timing).
    ///
    /// # Errors
    /// Allocation failure.
    pub fn analyze(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), Singular> {
        self.adopt(a);
        self.analyze_adopted(a)
    }

    /// [`Self::analyze`] for a matrix whose pattern [`Self::adopt`] has seen.
    fn analyze_adopted(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), Singular> {
        if self.llt.is_none() {
            let ord = match &self.order {
                Some((fwd, inv)) if fwd.len() == a.nrows() => {
                    SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, fwd.len()))
                }
                _ => SymmetricOrdering::Amd,
            };
            let sym =
                factorize_symbolic_cholesky(a.symbolic(), Side::Lower, ord, Default::default())
                    .map_err(|e| Singular(format!("{e:?}")))?;
            self.llt = Some(Arc::new(sym));
        }
        Ok(())
    }

    /// Factors `a` by the first of the methods its [`Structure`] allows that succeeds.
    ///
    /// # Errors
    /// [`Singular`] when LU fails too. LU with partial pivoting does not detect every singular
    /// matrix (an all-zero one factors): a solve then gives values that are not finite, which
    /// the Newton solver reports as a singular tangent.
    pub fn factor(
        &mut self,
        a: SparseColMatRef<'_, usize, f64>,
        structure: Structure,
    ) -> Result<Factor, Singular> {
        self.adopt(a);
        if structure != Structure::Unsymmetric {
            self.analyze_adopted(a)?;
            let symbolic = self.llt.clone().expect("analysed");
            if structure == Structure::SymmetricDefinite
                && let Some(f) = llt(&symbolic, a, &mut self.buffers)?
            {
                return Ok(f);
            }
            if !self.ldlt_rejected {
                if let Some(f) = ldlt(&symbolic, a, &mut self.buffers)? {
                    return Ok(f);
                }
                self.ldlt_rejected = true;
            }
        }
        if self.lu.is_none() {
            self.lu =
                Some(SymbolicLu::try_new(a.symbolic()).map_err(|e| Singular(format!("{e:?}")))?);
        }
        let sym = self.lu.clone().expect("analysed");
        Lu::try_new_with_symbolic(sym, a)
            .map(|f| Factor::Lu(Box::new(f)))
            .map_err(|e| Singular(format!("LU factorization failed ({e:?})")))
    }
}

/// `L Lᵀ` of `a`, `None` when `a` is not positive definite.
fn llt(
    symbolic: &Arc<SymbolicCholesky<usize>>,
    a: SparseColMatRef<'_, usize, f64>,
    buffers: &mut Buffers,
) -> Result<Option<Factor>, Singular> {
    let par = faer::get_global_parallelism();
    let req = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
    let values = numeric(symbolic, buffers, req, |values, stack| {
        let side = Side::Lower;
        let (regularization, params) = (Default::default(), Default::default());
        symbolic
            .factorize_numeric_llt::<f64>(values, a, side, regularization, par, stack, params)
            .is_ok()
    })?;
    Ok(values.map(|values| {
        Factor::Llt(Cholesky {
            symbolic: symbolic.clone(),
            values,
        })
    }))
}

/// The values of a numeric factorization on `symbolic`, made by `factor` (given them and its
/// scratch space, `true` when it succeeds) in the memory `buffers` keep; `None` when it fails,
/// the memory kept again.
fn numeric(
    symbolic: &SymbolicCholesky<usize>,
    buffers: &mut Buffers,
    req: StackReq,
    factor: impl FnOnce(&mut [f64], &mut MemStack) -> bool,
) -> Result<Option<Vec<f64>>, Singular> {
    let mut values = buffers.values(symbolic.len_val());
    if factor(&mut values, MemStack::new(buffers.scratch(req)?)) {
        return Ok(Some(values));
    }
    buffers.values = values;
    Ok(None)
}

/// `L D Lᵀ` of `a` on the Cholesky structure, if it exists and solves `a x = a·1` accurately.
fn ldlt(
    symbolic: &Arc<SymbolicCholesky<usize>>,
    a: SparseColMatRef<'_, usize, f64>,
    buffers: &mut Buffers,
) -> Result<Option<Factor>, Singular> {
    let par = faer::get_global_parallelism();
    let req = symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default());
    let Some(values) = numeric(symbolic, buffers, req, |values, stack| {
        let side = Side::Lower;
        let (regularization, params) = (Default::default(), Default::default());
        symbolic
            .factorize_numeric_ldlt::<f64>(values, a, side, regularization, par, stack, params)
            .is_ok()
    })?
    else {
        return Ok(None);
    };
    let factor = Factor::Ldlt(Cholesky {
        symbolic: symbolic.clone(),
        values,
    });
    let ones = vec![1.0; a.ncols()];
    let b = matvec(a, &ones);
    let x = factor.solve(&b);
    let r = matvec(a, &x);
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let frobenius = norm(a.val());
    let residual: Vec<f64> = r.iter().zip(&b).map(|(r, b)| r - b).collect();
    let ok = norm(&residual) <= 1e-10 * (frobenius * norm(&x) + norm(&b));
    if ok {
        return Ok(Some(factor));
    }
    if let Factor::Ldlt(c) = factor {
        buffers.values = c.values;
    }
    Ok(None)
}

/// `a x` for a matrix holding both triangles.
fn matvec(a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    for (j, &xj) in x.iter().enumerate() {
        for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            y[i] += v * xj;
        }
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};

    fn laplacian(n: usize, shift: f64) -> SparseColMat<usize, f64> {
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0 + shift));
            if i + 1 < n {
                t.push(Triplet::new(i, i + 1, -1.0));
                t.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        SparseColMat::try_new_from_triplets(n, n, &t).expect("valid")
    }

    /// `a x = b` to 1e-9 for a matrix holding both triangles.
    fn assert_solves(a: &SparseColMat<usize, f64>, f: &Factor, b: &[f64], what: &str) {
        let x = f.solve(b);
        let ax = matvec(a.as_ref(), &x);
        for i in 0..b.len() {
            assert!(
                (ax[i] - b[i]).abs() < 1e-9,
                "{what}: row {i}: {} vs {}",
                ax[i],
                b[i]
            );
        }
    }

    /// A solver given a matrix of another pattern analyses it afresh (it kept the first
    /// pattern's symbolic factorization, and panicked or solved wrongly, unless reset).
    #[test]
    fn a_new_pattern_is_analysed_afresh() {
        for structure in [
            Structure::SymmetricDefinite,
            Structure::SymmetricIndefinite,
            Structure::Unsymmetric,
        ] {
            let mut solver = LinearSolver::new();
            for n in [20, 7, 20, 31] {
                let a = laplacian(n, 0.5);
                let b: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
                let f = solver.factor(a.as_ref(), structure).expect("factors");
                assert_solves(&a, &f, &b, &format!("{structure:?} n = {n}"));
            }
        }
    }

    /// A factorization given back lends its memory to the next one, which solves as a fresh one
    /// does: Cholesky and `LDLᵀ`, for a matrix of the same size, a smaller one and a larger one
    /// (which needs more memory, then lends its own).
    #[test]
    fn a_recycled_factorization_lends_its_memory_to_the_next() {
        for (shift, structure, method) in [
            (0.5, Structure::SymmetricDefinite, "cholesky"),
            (-2.5, Structure::SymmetricIndefinite, "ldlt"),
        ] {
            let mut solver = LinearSolver::new();
            let mut lent: Option<(*const f64, usize)> = None;
            let mut reused = 0;
            for n in [40, 40, 25, 60, 60] {
                let a = laplacian(n, shift);
                let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
                let f = solver.factor(a.as_ref(), structure).expect("factors");
                assert_eq!(f.method(), method);
                assert_solves(&a, &f, &b, &format!("{method}, n = {n}"));
                let (Factor::Llt(c) | Factor::Ldlt(c)) = &f else {
                    panic!("{method} expected");
                };
                if let Some((at, room)) = lent
                    && c.values.len() <= room
                {
                    assert_eq!(
                        c.values.as_ptr(),
                        at,
                        "{method}, n = {n}: memory not reused"
                    );
                    reused += 1;
                }
                lent = Some((c.values.as_ptr(), c.values.capacity()));
                solver.recycle(f);
            }
            assert_eq!(reused, 3, "{method}");
        }
    }

    #[test]
    fn each_structure_gets_the_right_factorization() {
        let n = 20;
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        for (shift, structure, method) in [
            (0.0, Structure::SymmetricDefinite, "cholesky"),
            (-2.5, Structure::SymmetricDefinite, "ldlt"),
            (-2.5, Structure::SymmetricIndefinite, "ldlt"),
            (0.0, Structure::Unsymmetric, "lu"),
        ] {
            let a = laplacian(n, shift);
            let f = LinearSolver::new()
                .factor(a.as_ref(), structure)
                .expect("regular");
            assert_eq!(f.method(), method, "shift {shift}, {structure:?}");
            assert_solves(&a, &f, &b, method);
        }
    }

    #[test]
    fn zero_pivot_saddle_point_falls_back_to_lu() {
        // [[0, 1], [1, 0]] ⊕ [[2]]: regular, but `LDLᵀ` without pivoting meets a zero pivot.
        let t = [
            Triplet::new(0, 1, 1.0),
            Triplet::new(1, 0, 1.0),
            Triplet::new(2, 2, 2.0),
            Triplet::new(0, 0, 0.0),
        ];
        let a = SparseColMat::try_new_from_triplets(3, 3, &t).expect("valid");
        for structure in [Structure::SymmetricDefinite, Structure::SymmetricIndefinite] {
            let f = LinearSolver::new()
                .with_order(vec![0, 1, 2])
                .factor(a.as_ref(), structure)
                .expect("regular");
            assert_eq!(f.method(), "lu", "{structure:?}");
            assert_solves(&a, &f, &[1.0, 2.0, 3.0], "lu");
        }
    }
}
