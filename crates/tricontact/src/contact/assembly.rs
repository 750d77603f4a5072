//! Penalty terms of many node–facet constraints, scattered to global degrees of freedom.
//!
//! A [`Constraint`] names its four nodes `[i, j, k, l]` (facet nodes, then the slave). Global DOF
//! `3n + d` is component `d` of node `n`. For the active constraints (`P ≤ 0`),
//!
//! ```text
//! Φ = Σ ½ α P²,    f = ∂Φ/∂x = Σ α P ∇P,    K = ∂f/∂x = Σ α (∇P⊗∇P + P ∇²P)
//! ```
//!
//! with each pair's 12-entry gradient and 12×12 tangent from [`crate::penalty()`] scattered by its
//! node numbers. `f` is an internal force: it enters the residual `r = f_int − f_ext` with a plus
//! sign. Inactive constraints (`P > 0`) contribute nothing.

use crate::error::GeometryError;
use crate::linalg::Vec3;
use crate::node_facet::NodeFacet;
use crate::penalty::penalty;

/// One node–facet constraint: global node numbers `[i, j, k, l]` (slave last).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Constraint {
    /// Facet nodes, then the slave node.
    pub nodes: [u32; 4],
}

impl Constraint {
    /// The evaluated pair at `positions`.
    ///
    /// # Errors
    /// [`GeometryError::MissingNode`] for a node beyond `positions`; otherwise as
    /// [`NodeFacet::new`].
    pub fn pair(&self, positions: &[Vec3]) -> Result<NodeFacet, GeometryError> {
        let mut x = [Vec3::zeros(); 4];
        for (x, &node) in x.iter_mut().zip(&self.nodes) {
            *x = *positions
                .get(node as usize)
                .ok_or(GeometryError::MissingNode {
                    node,
                    nodes: positions.len(),
                })?;
        }
        NodeFacet::new(x[0], x[1], x[2], x[3])
    }
}

/// Assembled penalty terms.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PenaltyAssembly {
    /// Internal force over all global DOFs.
    pub force: Vec<f64>,
    /// Tangent entries `(row, col, value)` over global DOFs (duplicates add up).
    pub triplets: Vec<(usize, usize, f64)>,
    /// Penalty energy `Σ ½αP²`.
    pub energy: f64,
    /// How many constraints were active (`P ≤ 0`).
    pub active: usize,
}

/// Penalty force and tangent of `constraints` at `positions` with penalty factor `alpha`.
///
/// # Errors
/// The first [`GeometryError`] met (a degenerate facet, a node without a position), with nothing
/// half-assembled returned.
pub fn assemble_penalty(
    constraints: &[Constraint],
    positions: &[Vec3],
    alpha: f64,
) -> Result<PenaltyAssembly, GeometryError> {
    let mut out = PenaltyAssembly {
        force: vec![0.0; 3 * positions.len()],
        ..PenaltyAssembly::default()
    };
    for c in constraints {
        let pair = c.pair(positions)?;
        if pair.gap() > 0.0 {
            continue;
        }
        let terms = penalty(&pair, alpha)?;
        out.energy += 0.5 * alpha * pair.gap() * pair.gap();
        out.active += 1;
        let dof = |r: usize| 3 * c.nodes[r / 3] as usize + r % 3;
        for r in 0..12 {
            out.force[dof(r)] += terms.force[r];
            for s in 0..12 {
                out.triplets.push((dof(r), dof(s), terms.stiffness[(r, s)]));
            }
        }
    }
    Ok(out)
}
