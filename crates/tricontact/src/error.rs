//! Typed errors of the kernel.
//!
//! Every public function that builds geometry from node positions returns one of these instead of
//! producing a NaN or panicking.

use thiserror::Error;

/// Why a node–facet evaluation could not be carried out.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum GeometryError {
    /// A node coordinate is NaN or infinite.
    #[error("non-finite node coordinate")]
    NonFinite,
    /// The facet has (nearly) coincident or collinear nodes: `|w|` is at most
    /// [`crate::DEGENERACY_TOLERANCE`] times the squared longest edge.
    #[error(
        "degenerate facet: twice its area is {twice_area:e}, the squared longest edge is {longest_edge_squared:e}"
    )]
    DegenerateFacet {
        /// `|w| = |(x_j − x_i) × (x_k − x_i)|`, twice the facet area.
        twice_area: f64,
        /// The squared length of the longest facet edge.
        longest_edge_squared: f64,
    },
    /// The two end nodes of an edge coincide (relative to the problem's length scale).
    #[error("degenerate edge: its squared length {length_squared:e} is negligible")]
    DegenerateEdge {
        /// Squared edge length.
        length_squared: f64,
    },
    /// The slave node lies on the feature whose distance was asked for, where the distance is not
    /// differentiable.
    #[error("the slave node lies on the feature: distance {distance:e} is not differentiable")]
    ZeroDistance {
        /// The distance found.
        distance: f64,
    },
    /// A constraint names a node that has no position.
    #[error("node {node} has no position: {nodes} node positions were given")]
    MissingNode {
        /// The node named.
        node: u32,
        /// How many node positions there are.
        nodes: usize,
    },
    /// The result overflowed `f64` (coordinates of wildly different magnitudes).
    #[error("floating-point overflow in the node–facet terms")]
    Overflow,
}
