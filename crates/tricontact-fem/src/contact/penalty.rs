//! Penalty enforcement of one node: energy `½ α P²` while `P ≤ 0`.
//!
//! ```text
//! f = α P ∇P,    K = α (∇P⊗∇P + P ∇²P)        (closed: P ≤ 0; else nothing)
//! ```
//!
//! A node whose status cycles is held closed for the rest of the increment (see
//! [`super::ContactTerms`]); the same terms then apply at `P > 0` (a small pull).
//!
//! `f` is an internal force (it enters `r = f_int − f_ext` with a plus sign); the contact force on
//! the slave node is `−αP W`, i.e. the multiplier equivalent is `λ = αP ≤ 0`. Finite sliding uses the
//! kernel's [`tricontact::penalty()`]; small sliding drops `∇²P`.

use tricontact::{GeometryError, Mat12, Vec12};

use super::gap::Gap;

/// Whether the node closes: it penetrates or touches (`P ≤ 0`).
#[must_use]
pub fn wants_closed(gap: &Gap) -> bool {
    gap.gap() <= 0.0
}

/// Force and tangent of a closed node.
///
/// # Errors
/// A [`GeometryError`] of the kernel (overflow).
pub fn penalty_terms(gap: &Gap, alpha: f64) -> Result<(Vec12, Mat12), GeometryError> {
    Ok(match gap {
        Gap::Finite(pair) => {
            let t = tricontact::penalty(pair, alpha)?;
            (t.force, t.stiffness)
        }
        Gap::Linear { .. } => (gap.gradient() * (alpha * gap.gap()), gap.outer(alpha)),
    })
}
