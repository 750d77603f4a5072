//! Contact search: which facet of a master surface is closest to each slave node.
//!
//! * [`surface`]: facets as node triples, with facet adjacency;
//! * [`aabb`], [`morton`], [`hilbert`]: boxes, Z-order codes and Hilbert codes;
//! * [`bvh`]: the bounding-volume hierarchy (parallel build, refit, rebuild on degraded quality);
//! * [`layout`]: its topology (code-bit splits collapsed to four-wide nodes); `leaves`: the facets
//!   cut into leaves of small boxes; `node`: its nodes;
//! * [`query`]: closest facet and facets within a distance, parallel over nodes, deterministic,
//!   optionally from a hint facet; `lanes`: a leaf's facets measured at once, one per lane;
//! * [`packet`]: coherent batches, a packet of consecutive queries sharing one traversal;
//! * [`incremental`]: answers again after a small motion from per-query neighbourhood lists, with
//!   a certificate from the motion, and tree fallback; `screen`: its bounds for a vector of
//!   queries at once; `direction`: unit vectors in four bytes.
//!
//! The search uses the kernel's closest-point query, so each answer says whether the node faces the
//! interior, an edge or a vertex of its facet.

pub mod aabb;
pub mod bvh;
pub(crate) mod direction;
pub mod hilbert;
pub mod incremental;
pub(crate) mod lanes;
pub mod layout;
pub(crate) mod leaves;
pub mod morton;
pub(crate) mod node;
pub mod packet;
pub mod query;
pub mod scenes;
pub(crate) mod screen;
pub mod surface;

pub use aabb::Aabb;
pub use bvh::{Bvh, LEAF_SIZE, REBUILD_RATIO, Update};
pub use incremental::{IncrementalStats, Moved, Neighbourhoods};
pub use query::{HINT_CHUNK, Hit, Query, brute_force_closest, measure, sort_hits};
pub use surface::{MAX_FACETS, Surface, SurfaceError};
