//! 10-node quadratic tetrahedron in Gmsh node order.
//!
//! With barycentric coordinates `L_0 = 1 − ξ − η − ζ, L_1 = ξ, L_2 = η,
//! L_3 = ζ`: corners `N_i = L_i (2 L_i − 1)`, edge nodes `N = 4 L_a L_b` with
//! Gmsh edges 4:(0,1) 5:(1,2) 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1).
//! (VTK's quadratic tetra has 8:(3,1) and 9:(3,2): nodes 8 and 9 swap.)

use crate::shape::ShapeEval;

/// Corner pairs of the edge nodes 4..9.
pub const EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [3, 0], [3, 2], [3, 1]];

/// Reference coordinates of the nodes.
pub const NODES: [[f64; 3]; 10] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.0],
    [0.0, 0.0, 0.5],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
];

/// Shape functions at `xi`.
#[must_use]
pub fn shape(xi: [f64; 3]) -> ShapeEval {
    let l = [1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]];
    // dL_i/dξ_j
    let dl: [[f64; 3]; 4] = [
        [-1.0, -1.0, -1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let mut s = ShapeEval::zeros(10);
    for i in 0..4 {
        s.n[i] = l[i] * (2.0 * l[i] - 1.0);
        for j in 0..3 {
            s.dn[i][j] = (4.0 * l[i] - 1.0) * dl[i][j];
        }
    }
    for (e, &[a, b]) in EDGES.iter().enumerate() {
        s.n[4 + e] = 4.0 * l[a] * l[b];
        for j in 0..3 {
            s.dn[4 + e][j] = 4.0 * (dl[a][j] * l[b] + l[a] * dl[b][j]);
        }
    }
    s
}
