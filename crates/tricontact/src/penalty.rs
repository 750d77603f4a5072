//! Penalty enforcement of the node–facet constraint.
//!
//! # Energy and sign convention
//! The penalty energy of a penetrating pair is `Φ = ½ α P²` (applied by the caller only while the
//! pair is active, normally when `P ≤ 0`). Its gradient is the **internal force** that enters the
//! residual `r = f_int − f_ext` like an element's:
//!
//! ```text
//! f_a = ∂Φ/∂x_a = α P ∂P/∂x_a = −α N_a P W          (a = i, j, k, l;  N_l = −1)
//! ```
//!
//! The **resistance** of the formulation is the contact force acting on the nodes,
//! `R_a = −f_a = α N_a P W`: for a penetrating slave node (`P < 0`, `N_l = −1`)
//! `R_l = −α P W` pushes it back out along `W`, and the facet nodes are pushed the other way in
//! proportion to their shape functions. `Σ_a R_a = 0` because `Σ_{i,j,k} N_a = 1 = −N_l`, and the
//! moment `Σ x_a × R_a` vanishes because `Σ_{i,j,k} N_a x_a` is the projection of `x_l`, which
//! differs from `x_l` only along `W`.
//!
//! # Consistent tangent
//! ```text
//! K = ∂f/∂x = α (∇P ⊗ ∇P + P ∇²P)                    (12×12, symmetric)
//! ```

use crate::error::GeometryError;
use crate::linalg::{Mat12, Vec3, Vec12, all_finite};
use crate::node_facet::NodeFacet;

/// Force and tangent of the penalty term of one node–facet pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenaltyTerms {
    /// The gap `P`.
    pub gap: f64,
    /// Internal force `f = α P ∇P` (the gradient of `½αP²`), stacked `[i, j, k, l]`.
    pub force: Vec12,
    /// Tangent `K = α(∇P⊗∇P + P∇²P)`.
    pub stiffness: Mat12,
}

impl PenaltyTerms {
    /// The resistance `R_a = α N_a P W` of the formulation: the contact force on node `a`,
    /// `R = −f`.
    ///
    /// # Panics
    /// If `a > 3` (nodes `i, j, k, l` are 0 to 3).
    #[must_use]
    #[inline]
    pub fn resistance(&self, a: usize) -> Vec3 {
        -self.force.fixed_rows::<3>(3 * a).into_owned()
    }
}

/// Penalty force and tangent for penalty factor `alpha` (force per length, the user's units).
///
/// # Errors
/// [`GeometryError::Overflow`] if the force or tangent overflows (a non-finite `alpha` included).
#[inline]
pub fn penalty(pair: &NodeFacet, alpha: f64) -> Result<PenaltyTerms, GeometryError> {
    penalty_with(pair, alpha, alpha * pair.gap())
}

/// The force `λ̂∇P` and tangent `α∇P⊗∇P + λ̂∇²P` for a given force measure `λ̂`: the penalty
/// method is `λ̂ = αP`, the augmented Lagrangian `λ̂ = λ_k + αP`.
///
/// # Errors
/// [`GeometryError::Overflow`] if the force or tangent overflows.
#[inline]
pub(crate) fn penalty_with(
    pair: &NodeFacet,
    alpha: f64,
    lambda_hat: f64,
) -> Result<PenaltyTerms, GeometryError> {
    let gap = pair.gap();
    let grad = pair.gap_gradient();
    let stiffness = pair.second_order(alpha, lambda_hat);
    let force = grad * lambda_hat;
    let checked =
        pair.cannot_overflow(alpha, lambda_hat) || (all_finite(&stiffness) && all_finite(&force));
    if !checked {
        return Err(GeometryError::Overflow);
    }
    Ok(PenaltyTerms {
        gap,
        force,
        stiffness,
    })
}
