//! The contact layer's per-node logic, independent of any finite-element code: which facet a slave
//! node is constrained against, and the assembled penalty terms of a set of such constraints.
//!
//! * [`choice`]: the facet-choice rule at edges and vertices (one constraint per node and pass);
//! * [`enforcement`]: per-node multiplier block with a complementarity switch, augmented
//!   Lagrangian force and tangent with the Uzawa update;
//! * [`assembly`]: penalty forces and tangents of many node–facet constraints scattered to global
//!   degrees of freedom (`3 × node + component`).

pub mod assembly;
pub mod choice;
pub mod enforcement;

pub use assembly::{Constraint, PenaltyAssembly, assemble_penalty};
pub use choice::{FACING_COSINE, PROJECTION_TOLERANCE, choose_facet, choose_facet_facing, faces};
pub use enforcement::{
    AugmentedTerms, MultiplierBlock, augmented, augmented_closed, lambda_hat, multiplier_block,
    wants_active,
};
