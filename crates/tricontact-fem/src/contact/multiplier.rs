//! Lagrange-multiplier enforcement of one node: one unknown `λ` per slave node and constraint
//! (a second for a node's second flank at a concave kink, `contact/mod.rs`), the kernel's
//! primal–dual active-set block ([`tricontact::contact::multiplier_block`], switch
//! `κP + λ ≤ 0` with `κ` the pair's penalty factor as a scale). A node without a facet is
//! inactive. Compression is `λ ≤ 0`, the contact force on the slave node `−λW`. Small sliding
//! (`P` linear in `x`) drops `λ∇²P`.

use tricontact::contact::MultiplierBlock;
pub use tricontact::contact::wants_active;
use tricontact::{GeometryError, Mat12};

use super::gap::Gap;

/// One node's saddle-point block.
pub type Block = MultiplierBlock;

/// The active block at multiplier `lambda`.
///
/// # Errors
/// A [`GeometryError`] of the kernel (overflow).
pub fn active_block(gap: &Gap, lambda: f64) -> Result<Block, GeometryError> {
    Ok(match gap {
        Gap::Finite(pair) => {
            let t = tricontact::multiplier(pair, lambda)?;
            MultiplierBlock::active(t.constraint, t.jacobian, t.geometric_stiffness, lambda)
        }
        Gap::Linear { .. } => {
            MultiplierBlock::active(gap.gap(), gap.gradient(), Mat12::zeros(), lambda)
        }
    })
}

/// The inactive block (`λ → 0`).
#[must_use]
pub fn inactive_block(lambda: f64, kappa: f64) -> Block {
    MultiplierBlock::inactive(lambda, kappa)
}
