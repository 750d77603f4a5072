//! Shape-function values and natural derivatives at a point, and the
//! quadrature rules, for every supported element kind.
//!
//! `ShapeEval::dn[a][j] = ∂N_a/∂ξ_j` in the element's natural coordinates
//! (faces use j = 0, 1 only). Rules integrate exactly the stiffness of
//! undistorted elements: hex8 2×2×2 Gauss, tet4 1 point, tet10 4 points
//! (degree 2), quad4 2×2 Gauss, tri3/tri6 3 points (degree 2).

use crate::mesh::ElementKind;
use crate::{face, hex8, tet4, tet10};

/// Largest number of nodes of a supported element.
pub const MAX_NODES: usize = 10;

/// Shape functions and their natural derivatives at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeEval {
    /// Number of nodes in use.
    pub len: usize,
    /// `N_a`.
    pub n: [f64; MAX_NODES],
    /// `∂N_a/∂ξ_j`.
    pub dn: [[f64; 3]; MAX_NODES],
}

impl ShapeEval {
    /// All-zero evaluation for `len` nodes.
    #[must_use]
    pub fn zeros(len: usize) -> Self {
        Self {
            len,
            n: [0.0; MAX_NODES],
            dn: [[0.0; 3]; MAX_NODES],
        }
    }
}

/// A quadrature point with its weight and precomputed shape functions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QPoint {
    /// Natural coordinates.
    pub xi: [f64; 3],
    /// Weight (reference-element measure included).
    pub w: f64,
    /// Shape functions at `xi`.
    pub shape: ShapeEval,
}

/// Evaluates the shape functions of `kind` at `xi`.
#[must_use]
pub fn eval(kind: ElementKind, xi: [f64; 3]) -> ShapeEval {
    match kind {
        ElementKind::Tet4 => tet4::shape(xi),
        ElementKind::Tet10 => tet10::shape(xi),
        ElementKind::Hex8 => hex8::shape(xi),
        ElementKind::Tri3 => face::tri3(xi),
        ElementKind::Tri6 => face::tri6(xi),
        ElementKind::Quad4 => face::quad4(xi),
    }
}

/// Quadrature rule of `kind` with shape functions evaluated.
#[must_use]
pub fn rule(kind: ElementKind) -> Vec<QPoint> {
    let g = 1.0 / 3f64.sqrt();
    let pts: Vec<([f64; 3], f64)> = match kind {
        ElementKind::Hex8 => {
            let mut v = Vec::new();
            for &z in &[-g, g] {
                for &y in &[-g, g] {
                    for &x in &[-g, g] {
                        v.push(([x, y, z], 1.0));
                    }
                }
            }
            v
        }
        ElementKind::Tet4 => vec![([0.25, 0.25, 0.25], 1.0 / 6.0)],
        ElementKind::Tet10 => {
            let a = 0.585_410_196_624_968_5;
            let b = 0.138_196_601_125_010_5;
            let w = 1.0 / 24.0;
            vec![
                ([b, b, b], w),
                ([a, b, b], w),
                ([b, a, b], w),
                ([b, b, a], w),
            ]
        }
        ElementKind::Quad4 => {
            let mut v = Vec::new();
            for &y in &[-g, g] {
                for &x in &[-g, g] {
                    v.push(([x, y, 0.0], 1.0));
                }
            }
            v
        }
        ElementKind::Tri3 | ElementKind::Tri6 => {
            let w = 1.0 / 6.0;
            vec![
                ([1.0 / 6.0, 1.0 / 6.0, 0.0], w),
                ([2.0 / 3.0, 1.0 / 6.0, 0.0], w),
                ([1.0 / 6.0, 2.0 / 3.0, 0.0], w),
            ]
        }
    };
    pts.into_iter()
        .map(|(xi, w)| QPoint {
            xi,
            w,
            shape: eval(kind, xi),
        })
        .collect()
}

/// Natural coordinates of the nodes of `kind` (used by tests).
#[must_use]
pub fn node_coords(kind: ElementKind) -> Vec<[f64; 3]> {
    match kind {
        ElementKind::Tet4 => tet4::NODES.to_vec(),
        ElementKind::Tet10 => tet10::NODES.to_vec(),
        ElementKind::Hex8 => hex8::NODES.to_vec(),
        ElementKind::Tri3 => face::TRI6_NODES[..3].to_vec(),
        ElementKind::Tri6 => face::TRI6_NODES.to_vec(),
        ElementKind::Quad4 => face::QUAD4_NODES.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [ElementKind; 6] = [
        ElementKind::Tet4,
        ElementKind::Tet10,
        ElementKind::Hex8,
        ElementKind::Tri3,
        ElementKind::Tri6,
        ElementKind::Quad4,
    ];

    #[test]
    fn kronecker_delta_and_partition_of_unity() {
        for kind in KINDS {
            let nodes = node_coords(kind);
            assert_eq!(nodes.len(), kind.num_nodes());
            for (b, xb) in nodes.iter().enumerate() {
                let s = eval(kind, *xb);
                for a in 0..s.len {
                    let expect = if a == b { 1.0 } else { 0.0 };
                    assert!((s.n[a] - expect).abs() < 1e-14, "{kind:?} N{a}(x{b})");
                }
            }
            let s = eval(kind, [0.21, 0.17, 0.13]);
            let sum: f64 = s.n[..s.len].iter().sum();
            assert!((sum - 1.0).abs() < 1e-14);
            for j in 0..3 {
                let d: f64 = (0..s.len).map(|a| s.dn[a][j]).sum();
                assert!(d.abs() < 1e-13);
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let h = 1e-6;
        for kind in KINDS {
            let xi = [0.21, 0.17, 0.13];
            let s = eval(kind, xi);
            for j in 0..kind.dim() {
                let mut xp = xi;
                let mut xm = xi;
                xp[j] += h;
                xm[j] -= h;
                let (sp, sm) = (eval(kind, xp), eval(kind, xm));
                for a in 0..s.len {
                    let fd = (sp.n[a] - sm.n[a]) / (2.0 * h);
                    assert!((fd - s.dn[a][j]).abs() < 1e-8, "{kind:?} dN{a}/dxi{j}");
                }
            }
        }
    }

    #[test]
    fn rules_integrate_reference_measure() {
        let expect = [
            (ElementKind::Tet4, 1.0 / 6.0),
            (ElementKind::Tet10, 1.0 / 6.0),
            (ElementKind::Hex8, 8.0),
            (ElementKind::Tri3, 0.5),
            (ElementKind::Tri6, 0.5),
            (ElementKind::Quad4, 4.0),
        ];
        for (kind, m) in expect {
            let s: f64 = rule(kind).iter().map(|q| q.w).sum();
            assert!((s - m).abs() < 1e-14, "{kind:?}");
        }
    }
}
