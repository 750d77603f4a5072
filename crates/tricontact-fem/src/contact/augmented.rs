//! Augmented-Lagrangian enforcement of one node with a multiplier estimate `λ_k ≤ 0` held fixed
//! during a Newton solve:
//!
//! ```text
//! λ̂ = λ_k + α P;   closed (λ̂ < 0, or λ̂ = 0 ≥ P):  f = λ̂ ∇P,   K = α ∇P⊗∇P + λ̂ ∇²P;   else nothing
//! ```
//!
//! (`λ̂ = 0` with `P = 0` keeps the stiffness `α∇P⊗∇P`, so touching bodies are supported from the
//! first iteration; a node whose status cycles is held closed for the rest of the increment, see
//! [`super::ContactTerms`].) After Newton converged, the Uzawa update `λ_{k+1} = min(0, λ̂)` is applied to
//! every node until the largest gap `|P|` of a closed node is below the pair's tolerance (see
//! [`super::ContactTerms`]). Finite sliding uses the kernel's [`tricontact::contact::augmented`].

use tricontact::{GeometryError, Mat12, Vec12};

use super::gap::Gap;

/// `λ̂ = λ_k + αP` ([`tricontact::contact::lambda_hat`]).
///
/// # Errors
/// [`GeometryError::Overflow`] when it is not finite.
pub fn lambda_hat(gap: &Gap, lambda_k: f64, alpha: f64) -> Result<f64, GeometryError> {
    tricontact::contact::lambda_hat(gap.gap(), lambda_k, alpha)
}

/// Whether the node closes at `λ̂`: compression, or `λ̂ = 0` while touching or penetrating.
#[must_use]
pub fn wants_closed(gap: &Gap, lambda_hat: f64) -> bool {
    lambda_hat < 0.0 || (lambda_hat == 0.0 && gap.gap() <= 0.0)
}

/// Force `λ̂∇P` and tangent `α∇P⊗∇P + λ̂∇²P` of a closed node (a node held closed may have
/// `λ̂ > 0`: a pull; at `λ̂ = 0 = P` the stiffness `α∇P⊗∇P` alone).
///
/// # Errors
/// A [`GeometryError`] of the kernel (overflow).
pub fn augmented_terms(
    gap: &Gap,
    lambda_k: f64,
    alpha: f64,
) -> Result<(Vec12, Mat12), GeometryError> {
    Ok(match gap {
        Gap::Finite(pair) => {
            let t = tricontact::contact::augmented_closed(pair, lambda_k, alpha)?;
            (t.force, t.stiffness)
        }
        Gap::Linear { .. } => (
            gap.gradient() * lambda_hat(gap, lambda_k, alpha)?,
            gap.outer(alpha),
        ),
    })
}
