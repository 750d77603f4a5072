//! # tricontact — the node-to-triangular-facet contact kernel
//!
//! Pure functions of node positions that evaluate the node–facet contact formulation exactly:
//! values, first and second derivatives, verified against finite differences.
//!
//! * [`facet`]: the facet normal `w`, the triad `U, V, W` and their derivatives;
//! * [`node_facet`]: the gap `P = (x_l − x_i)·W`, shape functions `N_a`, `∇P`, `∇²P`;
//! * [`mod@penalty`]: the penalty force `αP∇P` (resistance `R_a = αN_aPW`) and tangent;
//! * [`mod@multiplier`]: the constraint `c = P`, its Jacobian and geometric stiffness `λ∇²c`;
//! * [`closest`]: closest points near facet boundaries (face / edge / vertex), point–edge and
//!   point–vertex distances with derivatives;
//! * [`contact`]: the facet-choice rule at edges and vertices, assembled penalty terms;
//! * [`search`]: which facet each slave node meets, in meshes of millions of facets (BVH,
//!   incremental search from neighbourhood lists, parallel queries).
//!
//! Coordinates of a node–facet pair are stacked `[x_i, x_j, x_k, x_l]` (12 entries). No function
//! panics or returns NaN for finite input: degenerate geometry is a [`GeometryError`].
//!
//! ```
//! use tricontact::{NodeFacet, Vec3, penalty};
//! let pair = NodeFacet::new(
//!     Vec3::new(0.0, 0.0, 0.0),
//!     Vec3::new(1.0, 0.0, 0.0),
//!     Vec3::new(0.0, 1.0, 0.0),
//!     Vec3::new(0.25, 0.25, -0.01),
//! )?;
//! assert!(pair.projection.is_inside(0.0) && pair.gap() < 0.0);
//! let terms = penalty(&pair, 1e3)?;
//! // The slave node is pushed out along +z.
//! assert!(terms.resistance(3).z > 0.0);
//! # Ok::<(), tricontact::GeometryError>(())
//! ```

pub mod closest;
pub mod contact;
pub mod error;
pub mod facet;
pub mod linalg;
pub mod multiplier;
pub mod node_facet;
pub mod penalty;
pub mod search;

pub use closest::{
    ClosestPoint, Feature, PointEdge, PointVertex, closest_point, closest_point_on_triangle,
    distance_squared_to_triangle, point_edge, point_vertex,
};
pub use error::GeometryError;
pub use facet::{DEGENERACY_TOLERANCE, Facet, Triad, TriadDerivative};
pub use linalg::{Mat3, Mat12, Vec3, Vec12, skew};
pub use multiplier::{MultiplierTerms, multiplier};
pub use node_facet::{NodeFacet, Projection, detect, project};
pub use penalty::{PenaltyTerms, penalty};
