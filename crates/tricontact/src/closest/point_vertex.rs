//! Distance from a node to a vertex, with exact derivatives.
//!
//! Coordinates stacked `[x_a, x_l]` (vertex, then slave node). With `r = x_l − x_a`, `d = |r|`,
//! `n = r/d`:
//!
//! ```text
//! ∂d/∂x_l = n,            ∂d/∂x_a = −n
//! ∂²d/∂x_l² = (I − n⊗n)/d = H,   Hessian = [[H, −H], [−H, H]]
//! ```
//!
//! `d` is not differentiable at `d = 0`: a node within `1e-12 · max(|x_a|, |x_l|)` of the vertex
//! (the larger distance of the two points from the origin; at least `1e-12 · 1.5·10⁻¹⁵⁴`, the
//! square root of the smallest normal `f64`) is a [`GeometryError::ZeroDistance`].

use nalgebra::{SMatrix, SVector};

use crate::error::GeometryError;
use crate::linalg::{Mat3, Vec3, all_finite};

/// Distance from a node to a vertex with its derivatives over `[x_a, x_l]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointVertex {
    /// `d = |x_l − x_a|`.
    pub distance: f64,
    /// `n = (x_l − x_a)/d`, the unit direction from the vertex to the node.
    pub direction: Vec3,
    /// `∇d`, 6 entries.
    pub gradient: SVector<f64, 6>,
    /// `∇²d`, 6×6.
    pub hessian: SMatrix<f64, 6, 6>,
}

/// Distance from node `xl` to vertex `xa` and its derivatives.
///
/// # Errors
/// [`GeometryError::NonFinite`] for non-finite input; [`GeometryError::ZeroDistance`] when the node
/// sits on the vertex; [`GeometryError::Overflow`] for finite coordinates whose difference
/// overflows, or of wildly different magnitudes.
pub fn point_vertex(xa: &Vec3, xl: &Vec3) -> Result<PointVertex, GeometryError> {
    let r = xl - xa;
    let distance = r.norm();
    if !distance.is_finite() {
        return Err(if [xa, xl].into_iter().flatten().all(|c| c.is_finite()) {
            GeometryError::Overflow
        } else {
            GeometryError::NonFinite
        });
    }
    let scale = xa.norm().max(xl.norm()).max(f64::MIN_POSITIVE.sqrt());
    if distance <= 1e-12 * scale {
        return Err(GeometryError::ZeroDistance { distance });
    }
    let direction = r / distance;
    let h: Mat3 = (Mat3::identity() - direction * direction.transpose()) / distance;
    let mut gradient = SVector::<f64, 6>::zeros();
    gradient.fixed_rows_mut::<3>(0).copy_from(&(-direction));
    gradient.fixed_rows_mut::<3>(3).copy_from(&direction);
    let mut hessian = SMatrix::<f64, 6, 6>::zeros();
    hessian.fixed_view_mut::<3, 3>(0, 0).copy_from(&h);
    hessian.fixed_view_mut::<3, 3>(3, 3).copy_from(&h);
    hessian.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-h));
    hessian.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-h));
    if !(all_finite(&gradient) && all_finite(&hessian)) {
        return Err(GeometryError::Overflow);
    }
    Ok(PointVertex {
        distance,
        direction,
        gradient,
        hessian,
    })
}
