//! Per-node enforcement of the contact constraint: penalty, Lagrange multiplier with a
//! complementarity switch, and augmented Lagrangian — as blocks a finite-element code scatters.
//!
//! Sign convention (see [`mod@crate::multiplier`]): the constraint enters as `Π + λP`; a compressive
//! contact force has `λ ≤ 0`; the contact conditions are `P ≥ 0`, `λ ≤ 0`, `λ P = 0`.
//!
//! # Multiplier with a complementarity switch (primal–dual active set)
//! The conditions are written as one equation, `C(λ, P) = min(−λ, κP) = 0`, with `κ > 0` a scale
//! in the model's units (force per length, e.g. the default penalty). Newton on `C` gives, per
//! iteration and without stored state:
//!
//! ```text
//! active   (κP + λ ≤ 0): r_u = λ∇P,  r_λ = P,     K_uu = λ∇²P,  K_uλ = K_λuᵀ = ∇P,  K_λλ = 0
//! inactive (otherwise):  r_u = 0,    r_λ = λ/κ,   K_uu = 0,     K_uλ = K_λu = 0,    K_λλ = 1/κ
//! ```
//!
//! A node switches to active when it penetrates by more than its multiplier allows, and releases
//! when its multiplier would pull (`λ > 0` drives `−λ` below `κP`). The switch is `≤`, so a node
//! touching with `P = 0` and `λ = 0` (bodies meshed in contact) starts active and a body held only
//! by contact is supported from the first iteration. The caller detects cycling (a node switching
//! back and forth) and freezes the set. For small sliding (`P` linear in `x`) the active block is
//! built with a zero `λ∇²P` ([`MultiplierBlock::active`]).
//!
//! # Augmented Lagrangian (Uzawa)
//! With a multiplier estimate `λ_k` held fixed during an equilibrium solve, the node's energy is
//! `(1/2α) min(0, λ_k + αP)²`, whose gradient and Hessian are
//!
//! ```text
//! λ̂ = λ_k + αP;   if λ̂ < 0:  f = λ̂ ∇P,   K = α ∇P⊗∇P + λ̂ ∇²P;   else f = 0, K = 0
//! ```
//!
//! (for `λ_k = 0` this is the penalty method). After convergence the estimate is updated,
//! `λ_{k+1} = min(0, λ̂)`, until every closed node's gap `|P|` is below the tolerance.

use crate::error::GeometryError;
use crate::linalg::{Mat12, Vec12};
use crate::node_facet::NodeFacet;

/// The saddle-point block of one node's multiplier equation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultiplierBlock {
    /// Whether the node is in contact this iteration.
    pub active: bool,
    /// `r_u`, over the pair's 12 coordinates.
    pub residual_u: Vec12,
    /// `r_λ`.
    pub residual_lambda: f64,
    /// `K_uu = ∂r_u/∂x`.
    pub k_uu: Mat12,
    /// `K_uλ = ∂r_u/∂λ` (the column; `K_λu = ∂r_λ/∂x` is the same vector as a row).
    pub k_ulambda: Vec12,
    /// `K_λλ = ∂r_λ/∂λ`.
    pub k_lambdalambda: f64,
}

/// Whether the complementarity switch makes a node active: `κP + λ ≤ 0`.
#[must_use]
#[inline]
pub fn wants_active(gap: f64, lambda: f64, kappa: f64) -> bool {
    kappa * gap + lambda <= 0.0
}

impl MultiplierBlock {
    /// The active block from the gap `P`, its gradient `∇P` and the geometric stiffness `λ∇²P`
    /// (zero for small sliding).
    #[must_use]
    pub fn active(gap: f64, gradient: Vec12, geometric_stiffness: Mat12, lambda: f64) -> Self {
        Self {
            active: true,
            residual_u: gradient * lambda,
            residual_lambda: gap,
            k_uu: geometric_stiffness,
            k_ulambda: gradient,
            k_lambdalambda: 0.0,
        }
    }

    /// The inactive block, which drives `λ` to zero, for a scale `kappa > 0` (at `kappa = 0` its
    /// entries are infinite, which [`multiplier_block`] reports as [`GeometryError::Overflow`]).
    #[must_use]
    pub fn inactive(lambda: f64, kappa: f64) -> Self {
        let inv = 1.0 / kappa;
        Self {
            active: false,
            residual_u: Vec12::zeros(),
            residual_lambda: lambda * inv,
            k_uu: Mat12::zeros(),
            k_ulambda: Vec12::zeros(),
            k_lambdalambda: inv,
        }
    }
}

/// The multiplier block of `pair` for multiplier `lambda` and scale `kappa > 0`.
///
/// # Errors
/// [`GeometryError::Overflow`] for a non-finite result.
pub fn multiplier_block(
    pair: &NodeFacet,
    lambda: f64,
    kappa: f64,
) -> Result<MultiplierBlock, GeometryError> {
    if wants_active(pair.gap(), lambda, kappa) {
        let terms = crate::multiplier::multiplier(pair, lambda)?;
        return Ok(MultiplierBlock::active(
            terms.constraint,
            terms.jacobian,
            terms.geometric_stiffness,
            lambda,
        ));
    }
    let block = MultiplierBlock::inactive(lambda, kappa);
    if block.residual_lambda.is_finite() && block.k_lambdalambda.is_finite() {
        Ok(block)
    } else {
        Err(GeometryError::Overflow)
    }
}

/// Force and tangent of one node under the augmented Lagrangian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AugmentedTerms {
    /// `λ̂ = λ_k + αP`.
    pub lambda_hat: f64,
    /// Internal force `f = min(0, λ̂) ∇P`.
    pub force: Vec12,
    /// Tangent `α∇P⊗∇P + λ̂∇²P` when `λ̂ < 0`, else zero.
    pub stiffness: Mat12,
}

impl AugmentedTerms {
    /// The Uzawa update `λ_{k+1} = min(0, λ̂)`.
    #[must_use]
    pub fn updated_multiplier(&self) -> f64 {
        self.lambda_hat.min(0.0)
    }
}

/// The augmented Lagrangian's force measure `λ̂ = λ_k + αP` at gap `P`.
///
/// # Errors
/// [`GeometryError::Overflow`] when it is not finite.
#[inline]
pub fn lambda_hat(gap: f64, lambda_k: f64, alpha: f64) -> Result<f64, GeometryError> {
    let lambda_hat = lambda_k + alpha * gap;
    if lambda_hat.is_finite() {
        Ok(lambda_hat)
    } else {
        Err(GeometryError::Overflow)
    }
}

/// Augmented-Lagrangian force and tangent of `pair` for estimate `lambda_k` and penalty `alpha`.
///
/// # Errors
/// [`GeometryError::Overflow`] for a non-finite result.
pub fn augmented(
    pair: &NodeFacet,
    lambda_k: f64,
    alpha: f64,
) -> Result<AugmentedTerms, GeometryError> {
    let lambda_hat = lambda_hat(pair.gap(), lambda_k, alpha)?;
    if lambda_hat >= 0.0 {
        return Ok(AugmentedTerms {
            lambda_hat,
            force: Vec12::zeros(),
            stiffness: Mat12::zeros(),
        });
    }
    augmented_closed(pair, lambda_k, alpha)
}

/// The augmented-Lagrangian terms of a node held closed whatever the sign of `λ̂`: `f = λ̂∇P`,
/// `K = α∇P⊗∇P + λ̂∇²P`, the gradient and Hessian of `λ̂²/(2α)` (for `λ̂ > 0` a pull; the host
/// holds a node closed when its status cycles). Equal to [`augmented`] where `λ̂ < 0`.
///
/// # Errors
/// [`GeometryError::Overflow`] for a non-finite result.
pub fn augmented_closed(
    pair: &NodeFacet,
    lambda_k: f64,
    alpha: f64,
) -> Result<AugmentedTerms, GeometryError> {
    let lambda_hat = lambda_hat(pair.gap(), lambda_k, alpha)?;
    // α∇P⊗∇P + λ̂∇²P is the penalty builder with (α, β) = (α, λ̂).
    let terms = crate::penalty::penalty_with(pair, alpha, lambda_hat)?;
    Ok(AugmentedTerms {
        lambda_hat,
        force: terms.force,
        stiffness: terms.stiffness,
    })
}
