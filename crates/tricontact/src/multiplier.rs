//! Lagrange-multiplier enforcement of the node–facet constraint.
//!
//! # Constraint and sign convention
//! ```text
//! c = P = (x_l − x_i) · W = 0        while the pair is active
//! ```
//!
//! The constraint enters the Lagrangian as `L = Π + λ c`. Stationarity gives the residual
//! contribution `λ ∇c` to the displacement equations and the row `∇c` (and column `∇cᵀ`) of the
//! saddle-point system, and the second variation the geometric stiffness `λ ∇²c`:
//!
//! ```text
//! ∇c   = ∇P = [−N_i W, −N_j W, −N_k W, W]
//! K_λ  = λ ∇²P
//! ```
//!
//! With this sign `λ` plays the role of `αP` in the penalty method: a compressive contact force has
//! `λ < 0`, and the contact force on the slave node is `−λ W`. A multiplier that turns positive would
//! pull the bodies together (tension): the contact layer releases such a pair.

use crate::error::GeometryError;
use crate::linalg::{Mat12, Vec12, all_finite};
use crate::node_facet::NodeFacet;

/// Constraint value, Jacobian row and geometric stiffness of one node–facet pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultiplierTerms {
    /// `c = P`.
    pub constraint: f64,
    /// `∇c = ∇P`, stacked `[i, j, k, l]`.
    pub jacobian: Vec12,
    /// `λ ∇²c` for the multiplier passed in.
    pub geometric_stiffness: Mat12,
}

/// Constraint, Jacobian and geometric stiffness for multiplier value `lambda`.
///
/// # Errors
/// [`GeometryError::Overflow`] if the geometric stiffness overflows (a non-finite `lambda`
/// included).
#[inline]
pub fn multiplier(pair: &NodeFacet, lambda: f64) -> Result<MultiplierTerms, GeometryError> {
    let geometric_stiffness = pair.second_order(0.0, lambda);
    if !(pair.cannot_overflow(0.0, lambda) || all_finite(&geometric_stiffness)) {
        return Err(GeometryError::Overflow);
    }
    Ok(MultiplierTerms {
        constraint: pair.gap(),
        jacobian: pair.gap_gradient(),
        geometric_stiffness,
    })
}
