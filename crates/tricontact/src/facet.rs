//! Facet geometry: the normal, the local triad and their derivatives.
//!
//! A facet has nodes `x_i, x_j, x_k` (counter-clockwise seen from the outside). Its un-normalised
//! normal (twice its area vector) is
//!
//! ```text
//! w = (x_j − x_i) × (x_k − x_i),        W = w / |w|.
//! ```
//!
//! The local triad takes the first edge as reference axis:
//!
//! ```text
//! u = x_j − x_i,   U = u / |u|,   V = U × W.
//! ```
//!
//! `V` lies in the facet plane, perpendicular to edge i–j and pointing away from node k; note that
//! `(U, V, W)` is left-handed (`U × V = −W`), exactly as the formulation defines it.
//!
//! # Derivatives
//! With `e_a` the edge opposite node `a`,
//! `e_i = x_k − x_j`, `e_j = x_i − x_k`, `e_k = x_j − x_i`, and `[a]×` the skew matrix of `a`:
//!
//! ```text
//! ∂w/∂x_a = [e_a]×
//! ∂W/∂x_a = (I − W⊗W)/|w| · [e_a]×
//! ∂U/∂x_i = −(I − U⊗U)/|u|,   ∂U/∂x_j = (I − U⊗U)/|u|,   ∂U/∂x_k = 0
//! ∂V/∂x_a = [U]× ∂W/∂x_a − [W]× ∂U/∂x_a
//! ```
//!
//! Every one of them is checked against central finite differences in `tests/facet_fd.rs`.

use crate::error::GeometryError;
use crate::linalg::{Mat3, Vec3, skew};

/// A facet is degenerate when `|w| ≤ DEGENERACY_TOLERANCE · (longest edge)²`, i.e. when the sine of
/// its smallest angle (up to a factor of order one) is below this value.
pub const DEGENERACY_TOLERANCE: f64 = 1e-12;

/// A validated, non-degenerate triangular facet with its normal.
///
/// Construction computes only what detection needs (`w`, `|w|`, `W`); the in-plane triad and the
/// derivatives are evaluated on demand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Facet {
    x: [Vec3; 3],
    w: Vec3,
    w_norm: f64,
    /// `1/|w|²`, shared by the shape-function gradients.
    inv_w2: f64,
    normal: Vec3,
}

/// The orthonormal local triad `(U, V, W)` of a facet (left-handed, see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triad {
    /// `U = u/|u|`, along the first edge `x_j − x_i`.
    pub u: Vec3,
    /// `V = U × W`, in-plane and perpendicular to `U`.
    pub v: Vec3,
    /// `W = w/|w|`, the outer unit normal.
    pub w: Vec3,
}

/// Derivatives of the triad with respect to one facet node: `∂U/∂x_a`, `∂V/∂x_a`, `∂W/∂x_a`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriadDerivative {
    /// `∂U/∂x_a`.
    pub du: Mat3,
    /// `∂V/∂x_a`.
    pub dv: Mat3,
    /// `∂W/∂x_a`.
    pub dw: Mat3,
}

impl Facet {
    /// Builds the facet of nodes `x_i, x_j, x_k`.
    ///
    /// # Errors
    /// [`GeometryError::NonFinite`] for a NaN or infinite coordinate;
    /// [`GeometryError::DegenerateFacet`] for coincident or collinear nodes (see
    /// [`DEGENERACY_TOLERANCE`]); [`GeometryError::Overflow`] when the coordinates are so large that
    /// the area overflows.
    #[inline]
    pub fn new(xi: Vec3, xj: Vec3, xk: Vec3) -> Result<Self, GeometryError> {
        let (eij, eik, ejk) = (xj - xi, xk - xi, xk - xj);
        let w = eij.cross(&eik);
        let w_norm = w.norm();
        let longest = eij
            .norm_squared()
            .max(eik.norm_squared())
            .max(ejk.norm_squared());
        if !(w_norm.is_finite() && longest.is_finite()) {
            return Err(if [xi, xj, xk].iter().flatten().all(|c| c.is_finite()) {
                GeometryError::Overflow
            } else {
                GeometryError::NonFinite
            });
        }
        // `|w|²` must stay a normal number: the shape-function gradients divide by it.
        if w_norm <= DEGENERACY_TOLERANCE * longest || !(w_norm * w_norm).is_normal() {
            return Err(GeometryError::DegenerateFacet {
                twice_area: w_norm,
                longest_edge_squared: longest,
            });
        }
        let inv = 1.0 / w_norm;
        Ok(Self {
            x: [xi, xj, xk],
            w,
            w_norm,
            inv_w2: inv * inv,
            normal: w * inv,
        })
    }

    /// The node positions `[x_i, x_j, x_k]`.
    #[must_use]
    #[inline]
    pub fn nodes(&self) -> &[Vec3; 3] {
        &self.x
    }

    /// The un-normalised normal `w = (x_j − x_i) × (x_k − x_i)`.
    #[must_use]
    #[inline]
    pub fn area_normal(&self) -> Vec3 {
        self.w
    }

    /// `|w|`, twice the facet area.
    #[must_use]
    #[inline]
    pub fn twice_area(&self) -> f64 {
        self.w_norm
    }

    /// The outer unit normal `W`.
    #[must_use]
    #[inline]
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// The length of the longest edge: the facet's length scale for relative tolerances.
    #[must_use]
    pub fn size(&self) -> f64 {
        (0..3)
            .map(|a| self.opposite_edge(a).norm_squared())
            .fold(0.0, f64::max)
            .sqrt()
    }

    /// The edge opposite local node `a` (0 = i, 1 = j, 2 = k):
    /// `e_i = x_k − x_j`, `e_j = x_i − x_k`, `e_k = x_j − x_i`.
    ///
    /// # Panics
    /// If `a > 2`.
    #[must_use]
    #[inline]
    pub fn opposite_edge(&self, a: usize) -> Vec3 {
        assert!(a < 3, "facet node index {a} out of range 0..3");
        self.x[(a + 2) % 3] - self.x[(a + 1) % 3]
    }

    /// The inner normal of the edge opposite node `a`, `n_a = W × e_a` (not normalised:
    /// `|n_a| = |e_a|`). It points from that edge into the facet.
    ///
    /// # Panics
    /// If `a > 2`.
    #[must_use]
    #[inline]
    pub fn inner_edge_normal(&self, a: usize) -> Vec3 {
        self.normal.cross(&self.opposite_edge(a))
    }

    /// `G_a = n_a/|w|`: the gradient of shape function `N_a` with respect to the slave node, an
    /// in-plane vector of length `1/h_a` (`h_a` the facet height over the edge opposite `a`).
    ///
    /// # Panics
    /// If `a > 2`.
    #[must_use]
    #[inline]
    pub fn shape_gradient(&self, a: usize) -> Vec3 {
        self.w.cross(&self.opposite_edge(a)) * self.inv_w2
    }

    /// `∂w/∂x_a = [e_a]×`.
    ///
    /// # Panics
    /// If `a > 2`.
    #[must_use]
    #[inline]
    pub fn d_area_normal(&self, a: usize) -> Mat3 {
        skew(&self.opposite_edge(a))
    }

    /// `∂W/∂x_a = (I − W⊗W)/|w| · [e_a]×`.
    ///
    /// # Panics
    /// If `a > 2`.
    #[must_use]
    #[inline]
    pub fn d_normal(&self, a: usize) -> Mat3 {
        (Mat3::identity() - self.normal * self.normal.transpose()) / self.w_norm
            * self.d_area_normal(a)
    }

    /// The local triad `(U, V, W)`.
    #[must_use]
    pub fn triad(&self) -> Triad {
        let u = (self.x[1] - self.x[0]).normalize();
        Triad {
            u,
            v: u.cross(&self.normal),
            w: self.normal,
        }
    }

    /// Derivatives of the triad with respect to node `a` (0 = i, 1 = j, 2 = k).
    ///
    /// # Panics
    /// If `a > 2`.
    #[must_use]
    pub fn d_triad(&self, a: usize) -> TriadDerivative {
        assert!(a < 3, "facet node index {a} out of range 0..3");
        let edge = self.x[1] - self.x[0];
        let len = edge.norm();
        let u = edge / len;
        let du_j = (Mat3::identity() - u * u.transpose()) / len;
        let du = match a {
            0 => -du_j,
            1 => du_j,
            _ => Mat3::zeros(),
        };
        let dw = self.d_normal(a);
        let dv = skew(&u) * dw - skew(&self.normal) * du;
        TriadDerivative { du, dv, dw }
    }
}
