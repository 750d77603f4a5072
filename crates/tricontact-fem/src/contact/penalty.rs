//! Penalty enforcement of one node: energy `½ α P²` while `P ≤ 0`.
//!
//! ```text
//! f = α P ∇P,    K = α (∇P⊗∇P + P ∇²P)        (P ≤ 0; else nothing)
//! ```
//!
//! `f` is an internal force (it enters `r = f_int − f_ext` with a plus sign); the contact force on
//! the slave node is `−αP W`, i.e. the multiplier equivalent is `λ = αP ≤ 0`. Finite sliding uses the
//! kernel's [`tricontact::penalty()`]; small sliding drops `∇²P`.

use tricontact::{GeometryError, Mat12, Vec12};

use super::gap::Gap;

/// Force and tangent of a penetrating node, `None` when open (`P > 0`).
///
/// # Errors
/// A [`GeometryError`] of the kernel (overflow).
pub fn penalty_terms(gap: &Gap, alpha: f64) -> Result<Option<(Vec12, Mat12)>, GeometryError> {
    let p = gap.gap();
    if p > 0.0 {
        return Ok(None);
    }
    Ok(Some(match gap {
        Gap::Finite(pair) => {
            let t = tricontact::penalty(pair, alpha)?;
            (t.force, t.stiffness)
        }
        Gap::Linear { .. } => (gap.gradient() * (alpha * p), gap.outer(alpha)),
    }))
}
