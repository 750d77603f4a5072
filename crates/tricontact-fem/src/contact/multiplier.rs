//! Lagrange-multiplier enforcement of one node: one unknown `λ` per slave node, primal–dual active
//! set (semismooth Newton on `min(−λ, κP) = 0`, `κ` the pair's penalty factor as a scale).
//!
//! ```text
//! active   (κP + λ ≤ 0):  r_u = λ∇P,  r_λ = P,    K_uu = λ∇²P,  K_uλ = K_λuᵀ = ∇P,  K_λλ = 0
//! inactive (otherwise):   r_u = 0,    r_λ = λ/κ,  K_uu = 0,     K_uλ = K_λu = 0,    K_λλ = 1/κ
//! ```
//!
//! This is the kernel's [`tricontact::contact::multiplier_block`] except that the switch uses `≤`:
//! a node touching with `P = 0` and `λ = 0` (bodies meshed in contact) starts active, so a body held
//! only by contact is supported from the first iteration; a multiplier that would pull (`λ > 0`)
//! releases the node in the next iteration. A node without a facet is inactive. Compression is
//! `λ ≤ 0`, the contact force on the slave node `−λW`. Small sliding drops `λ∇²P`.

use tricontact::{GeometryError, Mat12, Vec12};

use super::gap::Gap;

/// One node's saddle-point block.
#[derive(Clone, Copy, Debug)]
pub struct Block {
    /// `r_u`.
    pub residual_u: Vec12,
    /// `r_λ`.
    pub residual_lambda: f64,
    /// `K_uu`.
    pub k_uu: Mat12,
    /// `K_uλ` (= `K_λu`).
    pub k_ulambda: Vec12,
    /// `K_λλ`.
    pub k_lambdalambda: f64,
}

/// Whether the complementarity switch makes the node active.
#[must_use]
pub fn wants_active(gap: f64, lambda: f64, kappa: f64) -> bool {
    kappa * gap + lambda <= 0.0
}

/// The active block at multiplier `lambda`.
///
/// # Errors
/// A [`GeometryError`] of the kernel (overflow).
pub fn active_block(gap: &Gap, lambda: f64) -> Result<Block, GeometryError> {
    let (jac, k_uu) = match gap {
        Gap::Finite(pair) => {
            let t = tricontact::multiplier(pair, lambda)?;
            (t.jacobian, t.geometric_stiffness)
        }
        Gap::Linear { .. } => (gap.gradient(), Mat12::zeros()),
    };
    Ok(Block {
        residual_u: jac * lambda,
        residual_lambda: gap.gap(),
        k_uu,
        k_ulambda: jac,
        k_lambdalambda: 0.0,
    })
}

/// The inactive block (`λ → 0`).
#[must_use]
pub fn inactive_block(lambda: f64, kappa: f64) -> Block {
    Block {
        residual_u: Vec12::zeros(),
        residual_lambda: lambda / kappa,
        k_uu: Mat12::zeros(),
        k_ulambda: Vec12::zeros(),
        k_lambdalambda: 1.0 / kappa,
    }
}
