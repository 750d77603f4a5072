//! 8-node trilinear hexahedron on `[-1, 1]^3`:
//! `N_a = (1 + ξ_a ξ)(1 + η_a η)(1 + ζ_a ζ) / 8`, nodes 0–3 on `ζ = −1`
//! counter-clockwise seen from `+ζ`, nodes 4–7 above them (Gmsh = VTK order).

use crate::shape::ShapeEval;

/// Reference coordinates of the nodes.
pub const NODES: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Shape functions at `xi`.
#[must_use]
pub fn shape(xi: [f64; 3]) -> ShapeEval {
    let mut s = ShapeEval::zeros(8);
    for (a, p) in NODES.iter().enumerate() {
        let f = [1.0 + p[0] * xi[0], 1.0 + p[1] * xi[1], 1.0 + p[2] * xi[2]];
        s.n[a] = f[0] * f[1] * f[2] / 8.0;
        s.dn[a] = [
            p[0] * f[1] * f[2] / 8.0,
            f[0] * p[1] * f[2] / 8.0,
            f[0] * f[1] * p[2] / 8.0,
        ];
    }
    s
}
