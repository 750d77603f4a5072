//! Sparse direct solution of the Newton systems with faer.
//!
//! Symmetric systems are factored with a supernodal/simplicial Cholesky
//! `K = L Lᵀ` (lower triangle read), with a caller-supplied fill-reducing
//! ordering (nested dissection, [`crate::ordering`]) or faer's AMD; when that fails (not positive
//! definite, e.g. past a limit point) or the system is unsymmetric, a sparse
//! LU with partial pivoting is used. The symbolic analysis (fill-reducing
//! ordering, elimination tree) is kept and reused while the pattern is
//! unchanged. A failed LU, or a non-finite solution, is reported as a
//! singular system.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::perm::PermRef;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
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
    /// LU with partial pivoting.
    Lu(Box<Lu<usize, f64>>),
}

impl Factor {
    /// Solves `K x = b`.
    #[must_use]
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut rhs = faer::Mat::<f64>::from_fn(b.len(), 1, |i, _| b[i]);
        match self {
            Self::Llt(f) => {
                let par = faer::get_global_parallelism();
                let mut mem = MemBuffer::new(f.symbolic.solve_in_place_scratch::<f64>(1, par));
                LltRef::new(&f.symbolic, &f.values).solve_in_place_with_conj(
                    Conj::No,
                    rhs.as_mut(),
                    par,
                    MemStack::new(&mut mem),
                );
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
            Self::Llt(f) => (
                f.values.len(),
                matches!(
                    f.symbolic.raw(),
                    faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Supernodal(_)
                ),
            ),
            Self::Lu(_) => (0, false),
        }
    }

    /// `"cholesky"` or `"lu"`.
    #[must_use]
    pub fn method(&self) -> &'static str {
        match self {
            Self::Llt(_) => "cholesky",
            Self::Lu(_) => "lu",
        }
    }
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

    /// Forgets the symbolic analyses (call when the pattern changes).
    pub fn reset(&mut self) {
        self.llt = None;
        self.lu = None;
        self.cached = None;
    }

    /// Symbolic Cholesky analysis only (for timing).
    ///
    /// # Errors
    /// Allocation failure.
    pub fn analyze(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), Singular> {
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

    /// Factors `a`: Cholesky if `symmetric` and it succeeds, LU otherwise.
    ///
    /// # Errors
    /// [`Singular`] when LU fails too.
    pub fn factor(
        &mut self,
        a: SparseColMatRef<'_, usize, f64>,
        symmetric: bool,
    ) -> Result<Factor, Singular> {
        if symmetric {
            self.analyze(a)?;
            let symbolic = self.llt.clone().expect("analysed");
            let par = faer::get_global_parallelism();
            let mut values = vec![0.0; symbolic.len_val()];
            let req = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
            let mut mem = MemBuffer::try_new(req).map_err(|_| Singular("out of memory".into()))?;
            let ok = symbolic
                .factorize_numeric_llt::<f64>(
                    &mut values,
                    a,
                    Side::Lower,
                    Default::default(),
                    par,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .is_ok();
            if ok {
                return Ok(Factor::Llt(Cholesky { symbolic, values }));
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

    #[test]
    fn cholesky_solves_spd_and_lu_takes_over_when_indefinite() {
        let n = 20;
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        for (shift, method) in [(0.0, "cholesky"), (-2.5, "lu")] {
            let a = laplacian(n, shift);
            let f = LinearSolver::new()
                .factor(a.as_ref(), true)
                .expect("regular");
            assert_eq!(f.method(), method);
            let x = f.solve(&b);
            for i in 0..n {
                let mut ax = (2.0 + shift) * x[i];
                if i > 0 {
                    ax -= x[i - 1];
                }
                if i + 1 < n {
                    ax -= x[i + 1];
                }
                assert!((ax - b[i]).abs() < 1e-9, "shift {shift}: {ax} vs {}", b[i]);
            }
        }
    }
}
