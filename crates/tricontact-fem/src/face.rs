//! Face elements used for surface loads: tri3, tri6 (Gmsh order, edge nodes
//! 3:(0,1) 4:(1,2) 5:(2,0)) and quad4 on `[-1, 1]^2`.
//!
//! The area vector of a face at a point is `∂x/∂ξ × ∂x/∂η`; its direction
//! follows the node order (right-hand rule). Pressure loads orient it
//! outward from the adjacent volume element (see [`crate::loads`]).

use crate::shape::ShapeEval;

/// Reference coordinates of the tri6 nodes (tri3 uses the first three).
pub const TRI6_NODES: [[f64; 3]; 6] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.5, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.0],
];

/// Reference coordinates of the quad4 nodes.
pub const QUAD4_NODES: [[f64; 3]; 4] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];

/// Linear triangle.
#[must_use]
pub fn tri3(xi: [f64; 3]) -> ShapeEval {
    let mut s = ShapeEval::zeros(3);
    s.n[0] = 1.0 - xi[0] - xi[1];
    s.n[1] = xi[0];
    s.n[2] = xi[1];
    s.dn[0] = [-1.0, -1.0, 0.0];
    s.dn[1] = [1.0, 0.0, 0.0];
    s.dn[2] = [0.0, 1.0, 0.0];
    s
}

/// Quadratic triangle.
#[must_use]
pub fn tri6(xi: [f64; 3]) -> ShapeEval {
    let l = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
    let dl = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    let mut s = ShapeEval::zeros(6);
    for i in 0..3 {
        s.n[i] = l[i] * (2.0 * l[i] - 1.0);
        for j in 0..2 {
            s.dn[i][j] = (4.0 * l[i] - 1.0) * dl[i][j];
        }
    }
    for (e, [a, b]) in [[0usize, 1usize], [1, 2], [2, 0]].into_iter().enumerate() {
        s.n[3 + e] = 4.0 * l[a] * l[b];
        for j in 0..2 {
            s.dn[3 + e][j] = 4.0 * (dl[a][j] * l[b] + l[a] * dl[b][j]);
        }
    }
    s
}

/// Bilinear quadrilateral.
#[must_use]
pub fn quad4(xi: [f64; 3]) -> ShapeEval {
    let mut s = ShapeEval::zeros(4);
    for (a, p) in QUAD4_NODES.iter().enumerate() {
        let fx = 1.0 + p[0] * xi[0];
        let fy = 1.0 + p[1] * xi[1];
        s.n[a] = fx * fy / 4.0;
        s.dn[a] = [p[0] * fy / 4.0, fx * p[1] / 4.0, 0.0];
    }
    s
}
