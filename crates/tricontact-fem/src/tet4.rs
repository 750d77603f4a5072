//! 4-node linear tetrahedron: `N_0 = 1 − ξ − η − ζ`, `N_1 = ξ`, `N_2 = η`,
//! `N_3 = ζ` on the unit reference tetrahedron (Gmsh and VTK node order).

use crate::shape::ShapeEval;

/// Reference coordinates of the nodes.
pub const NODES: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];

/// Shape functions at `xi`.
#[must_use]
pub fn shape(xi: [f64; 3]) -> ShapeEval {
    let mut s = ShapeEval::zeros(4);
    s.n[0] = 1.0 - xi[0] - xi[1] - xi[2];
    s.n[1] = xi[0];
    s.n[2] = xi[1];
    s.n[3] = xi[2];
    s.dn[0] = [-1.0, -1.0, -1.0];
    s.dn[1] = [1.0, 0.0, 0.0];
    s.dn[2] = [0.0, 1.0, 0.0];
    s.dn[3] = [0.0, 0.0, 1.0];
    s
}
