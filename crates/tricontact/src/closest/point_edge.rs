//! Distance from a node to the line of an edge, with exact derivatives.
//!
//! Coordinates stacked `[x_a, x_b, x_l]` (edge ends, then slave node). With `e = x_b − x_a`,
//! `r = x_l − x_a`, the foot of the perpendicular is `x_a + t e`, `t = (r·e)/(e·e)`, and
//!
//! ```text
//! q = r − t e,   d = |q|,   n = q/d
//! ∇d = [−(1 − t) n,  −t n,  n]
//! ```
//!
//! (the same "shape function" structure as the facet gap: moving an edge end in the direction `n`
//! moves the foot by its linear shape function). Differentiating again, with
//!
//! ```text
//! ∂t/∂x_l = e/|e|²,  ∂t/∂x_b = (r − 2t e)/|e|²,  ∂t/∂x_a = (2t e − e − r)/|e|²
//! ∂q/∂x_l = I − e⊗e/|e|²,  ∂q/∂x_b = −t I − e⊗∂t/∂x_b,  ∂q/∂x_a = −(1 − t) I − e⊗∂t/∂x_a
//! ∂n/∂x_c = (I − n⊗n)/d · ∂q/∂x_c
//! ```
//!
//! the Hessian rows are `∂n/∂x_c` for the node, `n⊗∂t/∂x_c − (1 − t)∂n/∂x_c` for `a` and
//! `−n⊗∂t/∂x_c − t ∂n/∂x_c` for `b`.
//!
//! The result is the distance to the infinite line; it is the distance to the edge when
//! `0 ≤ t ≤ 1` (otherwise the closest feature is a vertex, see [`crate::closest::point_vertex()`]).

use nalgebra::{SMatrix, SVector};

use crate::error::GeometryError;
use crate::linalg::{Mat3, Vec3, all_finite};

/// Distance from a node to an edge's line with its derivatives over `[x_a, x_b, x_l]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointEdge {
    /// `d`, the distance from the node to the line through the edge.
    pub distance: f64,
    /// `t`, the position of the foot along the edge (`0` at `x_a`, `1` at `x_b`).
    pub parameter: f64,
    /// `n`, the unit direction from the foot to the node.
    pub direction: Vec3,
    /// `∇d`, 9 entries.
    pub gradient: SVector<f64, 9>,
    /// `∇²d`, 9×9.
    pub hessian: SMatrix<f64, 9, 9>,
}

/// Distance from node `xl` to the line of edge `(xa, xb)` and its derivatives.
///
/// # Errors
/// [`GeometryError::NonFinite`] for non-finite input; [`GeometryError::DegenerateEdge`] when the
/// edge ends coincide; [`GeometryError::ZeroDistance`] when the node lies on the line;
/// [`GeometryError::Overflow`] for finite coordinates whose differences or squares overflow, or of
/// wildly different magnitudes.
pub fn point_edge(xa: &Vec3, xb: &Vec3, xl: &Vec3) -> Result<PointEdge, GeometryError> {
    let e = xb - xa;
    let r = xl - xa;
    let e2 = e.norm_squared();
    if !(e2.is_finite() && r.norm_squared().is_finite()) {
        return Err(
            if [xa, xb, xl].into_iter().flatten().all(|c| c.is_finite()) {
                GeometryError::Overflow
            } else {
                GeometryError::NonFinite
            },
        );
    }
    let scale2 = xa.norm_squared().max(xb.norm_squared());
    if e2 <= 1e-24 * scale2 || !e2.is_normal() {
        return Err(GeometryError::DegenerateEdge { length_squared: e2 });
    }
    let t = r.dot(&e) / e2;
    let q = r - t * e;
    let distance = q.norm();
    if distance.is_nan() || distance <= 1e-12 * e2.sqrt() {
        return Err(GeometryError::ZeroDistance { distance });
    }
    let n = q / distance;
    let eye = Mat3::identity();
    let dt = [(2.0 * t * e - e - r) / e2, (r - 2.0 * t * e) / e2, e / e2];
    let dq = [
        -(1.0 - t) * eye - e * dt[0].transpose(),
        -t * eye - e * dt[1].transpose(),
        eye - e * dt[2].transpose(),
    ];
    let proj = (eye - n * n.transpose()) / distance;
    let dn: [Mat3; 3] = std::array::from_fn(|c| proj * dq[c]);
    let mut gradient = SVector::<f64, 9>::zeros();
    gradient.fixed_rows_mut::<3>(0).copy_from(&(-(1.0 - t) * n));
    gradient.fixed_rows_mut::<3>(3).copy_from(&(-t * n));
    gradient.fixed_rows_mut::<3>(6).copy_from(&n);
    let mut hessian = SMatrix::<f64, 9, 9>::zeros();
    for c in 0..3 {
        let rows = [
            n * dt[c].transpose() - (1.0 - t) * dn[c],
            -n * dt[c].transpose() - t * dn[c],
            dn[c],
        ];
        for (a, block) in rows.iter().enumerate() {
            hessian
                .fixed_view_mut::<3, 3>(3 * a, 3 * c)
                .copy_from(block);
        }
    }
    if !(all_finite(&gradient) && all_finite(&hessian)) {
        return Err(GeometryError::Overflow);
    }
    Ok(PointEdge {
        distance,
        parameter: t,
        direction: n,
        gradient,
        hessian,
    })
}
