//! Closest-point queries used near facet boundaries, one file per query:
//!
//! * [`point_triangle`]: where on a facet the closest point to a node lies (face, edge, vertex);
//! * [`mod@point_edge`]: distance from a node to an edge's line, with gradient and Hessian;
//! * [`mod@point_vertex`]: distance from a node to a vertex, with gradient and Hessian.

pub mod point_edge;
pub mod point_triangle;
pub mod point_vertex;

pub use point_edge::{PointEdge, point_edge};
pub use point_triangle::{
    ClosestPoint, Feature, TINY, closest_point, closest_point_and_distance_squared,
    closest_point_on_triangle, distance_squared_to_triangle,
};
pub use point_vertex::{PointVertex, point_vertex};
