//! Per-node contact state, part of the committed state of an increment (restored on cutback).
//!
//! Kept ready for tangential (friction) terms: the facet and the barycentric coordinates of the
//! foot point are stored with the normal.

/// State of one slave node in one pass.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeState {
    /// Facet (index into the pass's surface) at the last evaluation, `None` when none found.
    pub facet: Option<u32>,
    /// Barycentric coordinates `N_i, N_j, N_k` of the foot point.
    pub shape: [f64; 3],
    /// Facet normal `W`.
    pub normal: [f64; 3],
    /// Gap `P` (0 without facet).
    pub gap: f64,
    /// At the last convergence, the node's depth behind the master beyond its own facet's
    /// plane: behind a facet across a concave edge of its facet ([`super::flank`]; held by the
    /// second constraint with finite sliding where the kink is large enough, unheld
    /// otherwise), or with `small_sliding` behind the facet it is over now (0 for
    /// none).
    pub flank: f64,
    /// Normal multiplier at the last evaluation (`λ`, `αP` or `λ̂`; ≤ 0 in compression, 0 open).
    pub lambda: f64,
    /// Augmented Lagrangian: Uzawa estimate `λ_k`.
    pub lambda_k: f64,
    /// Closed (carrying force) at the last evaluation.
    pub active: bool,
    /// Status changes in this increment (cycle detection).
    pub switches: u32,
    /// Held closed for the rest of the increment after cycling.
    pub held: bool,
    /// Facet changes in this increment (cycle detection).
    pub facet_switches: u32,
    /// Facet frozen for the rest of the increment after cycling.
    pub facet_frozen: bool,
    /// The facet the node left at its last facet change in this increment (two-cycle detection).
    pub left_facet: Option<u32>,
    /// Small sliding: facet, shape functions and normal at the start of the increment.
    pub start: Option<(u32, [f64; 3], [f64; 3])>,
    /// The second constraint, against the flank across a concave kink of the node's facet
    /// (finite sliding; with multipliers its multiplier is a second unknown of the node).
    pub second: SecondFlank,
}

impl NodeState {
    /// Closed on its own constraint or on its second flank.
    #[must_use]
    pub fn closed(&self) -> bool {
        self.active || self.second.active
    }
}

/// The state of a node's second constraint ([`super::flank::second_flank`]) at the last
/// evaluation: as the node's own, with a multiplier estimate (augmented Lagrangian) or a
/// multiplier unknown (Lagrange multipliers) of its own.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SecondFlank {
    /// The flank's facet, `None` when the node has none.
    pub facet: Option<u32>,
    /// Its gap `P_G` (0 without facet).
    pub gap: f64,
    /// Its facet normal `W_G` (0 without facet).
    pub normal: [f64; 3],
    /// Its multiplier (`αP_G` or `λ̂`; ≤ 0 in compression, 0 open).
    pub lambda: f64,
    /// Augmented Lagrangian: its Uzawa estimate.
    pub lambda_k: f64,
    /// Closed at the last evaluation.
    pub active: bool,
    /// Lagrange multipliers: the node's facet and its second flank have traded places an odd
    /// number of times, so that each multiplier unknown stays with its facet: the own
    /// constraint's multiplier is the second of the node's two unknowns, the flank's the first.
    pub traded: bool,
}
