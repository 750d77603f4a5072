//! Augmented-Lagrangian enforcement of one node with a multiplier estimate `λ_k ≤ 0` held fixed
//! during a Newton solve:
//!
//! ```text
//! λ̂ = λ_k + α P;   λ̂ < 0:  f = λ̂ ∇P,   K = α ∇P⊗∇P + λ̂ ∇²P;   else nothing
//! ```
//!
//! (`λ̂ = 0` with `P = 0` keeps the stiffness `α∇P⊗∇P`, so touching bodies are supported from the
//! first iteration.) After Newton converged, the Uzawa update `λ_{k+1} = min(0, λ̂)` is applied to
//! every node until the largest penetration is below the pair's tolerance (see
//! [`super::ContactTerms`]). Finite sliding uses the kernel's [`tricontact::contact::augmented`].

use tricontact::{GeometryError, Mat12, Vec12};

use super::gap::Gap;

/// `(λ̂, force and tangent when active)`.
///
/// # Errors
/// A [`GeometryError`] of the kernel (overflow).
pub fn augmented_terms(
    gap: &Gap,
    lambda_k: f64,
    alpha: f64,
) -> Result<(f64, Option<(Vec12, Mat12)>), GeometryError> {
    let p = gap.gap();
    let lambda_hat = lambda_k + alpha * p;
    if !lambda_hat.is_finite() {
        return Err(GeometryError::Overflow);
    }
    if lambda_hat > 0.0 || (lambda_hat == 0.0 && p > 0.0) {
        return Ok((lambda_hat, None));
    }
    let terms = match gap {
        Gap::Finite(pair) if lambda_hat < 0.0 => {
            let t = tricontact::contact::augmented(pair, lambda_k, alpha)?;
            (t.force, t.stiffness)
        }
        // λ̂ = 0 = P: the penalty tangent α(∇P⊗∇P + 0·∇²P).
        Gap::Finite(pair) => {
            let t = tricontact::penalty(pair, alpha)?;
            (t.force, t.stiffness)
        }
        Gap::Linear { .. } => (gap.gradient() * lambda_hat, gap.outer(alpha)),
    };
    Ok((lambda_hat, Some(terms)))
}
