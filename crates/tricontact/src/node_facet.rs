//! Node–facet terms: the gap `P`, the shape functions `N_a`, and the exact gradient and Hessian of `P`.
//!
//! # Definitions
//! For a facet `(x_i, x_j, x_k)` with unit normal `W` (see [`crate::facet`]) and a slave node `x_l`:
//!
//! ```text
//! P   = (x_l − x_i) · W                         gap; P ≤ 0 is penetration
//! n_a = W × e_a                                 inner normal of the edge opposite a (not normalised)
//! N_i = (x_l − x_j)·n_i/|w|,  N_j = (x_l − x_k)·n_j/|w|,  N_k = (x_l − x_i)·n_k/|w|
//! ```
//!
//! `N_a` are the barycentric coordinates of the projection of `x_l` on the facet plane:
//! `Σ N_a = 1`, `N_a(x_b) = δ_ab`. The node "projects inside" when every `N_a ≥ −tol`.
//!
//! # Gradient
//! Stack the coordinates as `x = [x_i, x_j, x_k, x_l]` and set `N_l = −1`. Then
//!
//! ```text
//! ∂P/∂x_a = −N_a W          (a = i, j, k, l)
//! ```
//!
//! Proof for `a = i`: `∂P/∂x_i = −W + (∂W/∂x_i)ᵀ r` with `r = x_l − x_i`. Using
//! `∂W/∂x_i = (I − W⊗W)[e_i]×/|w|`, the second term is `(r_t × e_i)/|w|` with `r_t` the in-plane
//! part of `r`, which equals `(1 − N_i) W` by the area formula of `N_i`. Nodes `j`, `k` follow by
//! the same argument; `∂P/∂x_l = W` directly. Moving a facet node in its own plane leaves the plane,
//! hence `P`, unchanged; moving it along `W` shifts the plane under the slave node by `N_a`.
//!
//! # Hessian
//! Differentiating `g_a = −N_a W` once more:
//!
//! ```text
//! ∂²P/∂x_a∂x_b = −W ⊗ ∇_b N_a − N_a ∂W/∂x_b      (∂W/∂x_l = 0, ∇N_l = 0)
//! ```
//!
//! For `∇N_a`, write `N_a = (w · m_a)/|w|²` with `m_a` the area vector of the sub-triangle
//! obtained by replacing node `a` by the slave node: `m_i = (x_k − x_j) × (x_l − x_j)` on
//! `(j, k, l)`, `m_j` on `(k, i, l)`, `m_k` on `(i, j, l)`. For a triangle `(p, q, s)`,
//! `∂m/∂x_p = [x_s − x_q]×`, `∂m/∂x_q = [x_p − x_s]×`, `∂m/∂x_s = [x_q − x_p]×` (the seed's edge
//! rule, applied to the sub-triangle). Hence, with `∂w/∂x_b = [e_b]×` (`e_l = 0`) and
//! `∂m_a/∂x_b = [c_ab]×`,
//!
//! ```text
//! ∇_b N_a = ((m_a − 2 N_a w) × e_b + w × c_ab) / |w|²
//! ```
//!
//! The Hessian is symmetric (it is a second derivative); the tests check that and compare every entry
//! with central finite differences of the gradient.

use crate::error::GeometryError;
use crate::facet::Facet;
use crate::linalg::{Mat3, Mat12, Vec3, Vec12, all_finite};

/// Gap and shape functions of a slave node against a facet: everything contact detection needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// `P = (x_l − x_i)·W`: positive outside (on the side `W` points to), negative when penetrating.
    pub gap: f64,
    /// Barycentric shape functions `[N_i, N_j, N_k]` of the projection of `x_l` on the facet plane.
    pub shape: [f64; 3],
}

impl Projection {
    /// `true` when the projection of the node falls inside the facet or on its boundary, with
    /// tolerance `tol` on the (dimensionless) barycentric coordinates: every `N_a ≥ −tol`.
    #[must_use]
    #[inline]
    pub fn is_inside(&self, tol: f64) -> bool {
        self.shape.iter().all(|&n| n >= -tol)
    }

    /// `true` when the node penetrates the facet plane (`P ≤ 0`).
    #[must_use]
    #[inline]
    pub fn is_penetrating(&self) -> bool {
        self.gap <= 0.0
    }
}

/// A slave node paired with a facet, with its projection evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeFacet {
    /// The master facet.
    pub facet: Facet,
    /// The slave node position `x_l`.
    pub node: Vec3,
    /// Gap and shape functions.
    pub projection: Projection,
}

/// Gap and shape functions of node `xl` against `facet` (the detection step).
///
/// # Errors
/// [`GeometryError::NonFinite`] for a non-finite `xl`; [`GeometryError::Overflow`] if the result
/// overflows.
#[inline]
pub fn project(facet: &Facet, xl: &Vec3) -> Result<Projection, GeometryError> {
    let [xi, xj, xk] = facet.nodes();
    let inv = 1.0 / facet.twice_area();
    let gap = (xl - xi).dot(&facet.normal());
    let shape = [
        (xl - xj).dot(&facet.inner_edge_normal(0)) * inv,
        (xl - xk).dot(&facet.inner_edge_normal(1)) * inv,
        (xl - xi).dot(&facet.inner_edge_normal(2)) * inv,
    ];
    if (gap + shape[0] + shape[1] + shape[2]).is_finite() {
        Ok(Projection { gap, shape })
    } else if xl.iter().all(|c| c.is_finite()) {
        Err(GeometryError::Overflow)
    } else {
        Err(GeometryError::NonFinite)
    }
}

/// Gap and shape functions of node `xl` against the facet `(xi, xj, xk)`.
///
/// # Errors
/// As [`Facet::new`] and [`project`].
#[inline]
pub fn detect(xi: Vec3, xj: Vec3, xk: Vec3, xl: Vec3) -> Result<Projection, GeometryError> {
    project(&Facet::new(xi, xj, xk)?, &xl)
}

impl NodeFacet {
    /// Pairs node `xl` with the facet `(xi, xj, xk)` and evaluates the projection.
    ///
    /// # Errors
    /// As [`Facet::new`] and [`project`].
    #[inline]
    pub fn new(xi: Vec3, xj: Vec3, xk: Vec3, xl: Vec3) -> Result<Self, GeometryError> {
        let facet = Facet::new(xi, xj, xk)?;
        let projection = project(&facet, &xl)?;
        Ok(Self {
            facet,
            node: xl,
            projection,
        })
    }

    /// Pairs node `x[3]` with the facet `(x[0], x[1], x[2])`, coordinates stacked as a 12-vector.
    ///
    /// # Errors
    /// As [`NodeFacet::new`].
    #[inline]
    pub fn from_stacked(x: &Vec12) -> Result<Self, GeometryError> {
        let node = |a: usize| Vec3::new(x[3 * a], x[3 * a + 1], x[3 * a + 2]);
        Self::new(node(0), node(1), node(2), node(3))
    }

    /// The gap `P`.
    #[must_use]
    #[inline]
    pub fn gap(&self) -> f64 {
        self.projection.gap
    }

    /// The shape functions `[N_i, N_j, N_k, N_l]` with `N_l = −1`, so that `∂P/∂x_a = −N_a W`.
    #[must_use]
    #[inline]
    pub fn shape4(&self) -> [f64; 4] {
        let [ni, nj, nk] = self.projection.shape;
        [ni, nj, nk, -1.0]
    }

    /// The gradient `∇P = [−N_i W, −N_j W, −N_k W, W]`.
    #[must_use]
    #[inline]
    pub fn gap_gradient(&self) -> Vec12 {
        let normal = self.facet.normal();
        let mut g = Vec12::zeros();
        for (a, n) in self.shape4().into_iter().enumerate() {
            g.fixed_rows_mut::<3>(3 * a).copy_from(&(-n * normal));
        }
        g
    }

    /// The Hessian `∇²P` (12×12, symmetric); see the module doc for the derivation.
    ///
    /// # Errors
    /// [`GeometryError::Overflow`] if an entry overflows (coordinates of wildly different
    /// magnitudes).
    pub fn gap_hessian(&self) -> Result<Mat12, GeometryError> {
        let h = self.gap_hessian_unchecked();
        if all_finite(&h) {
            Ok(h)
        } else {
            Err(GeometryError::Overflow)
        }
    }

    /// `∇²P` without the overflow check, for callers that check their own final result.
    pub(crate) fn gap_hessian_unchecked(&self) -> Mat12 {
        let grad_n = self.shape_gradients();
        let normal = self.facet.normal();
        let projector = self.facet.normal_projector();
        let d_normal: [Mat3; 3] = std::array::from_fn(|b| projector * self.facet.d_area_normal(b));
        let shape = self.shape4();
        let mut h = Mat12::zeros();
        for a in 0..3 {
            for b in 0..4 {
                let mut block = -normal * grad_n[a][b].transpose();
                if b < 3 {
                    block -= shape[a] * d_normal[b];
                }
                h.fixed_view_mut::<3, 3>(3 * a, 3 * b).copy_from(&block);
            }
        }
        for (b, dw) in d_normal.iter().enumerate() {
            h.fixed_view_mut::<3, 3>(9, 3 * b).copy_from(dw);
        }
        h
    }

    /// `∇_b N_a` for `a ∈ {i, j, k}` and `b ∈ {i, j, k, l}` (see the module doc).
    #[must_use]
    pub fn shape_gradients(&self) -> [[Vec3; 4]; 3] {
        let [xi, xj, xk] = *self.facet.nodes();
        let xl = self.node;
        let w = self.facet.area_normal();
        let inv_w2 = 1.0 / (self.facet.twice_area() * self.facet.twice_area());
        // Sub-triangles (p, q, s) with node a replaced by the slave node.
        let tri = [(xj, xk), (xk, xi), (xi, xj)];
        let edges = [xk - xj, xi - xk, xj - xi, Vec3::zeros()];
        std::array::from_fn(|a| {
            let (p, q) = tri[a];
            let m = (q - p).cross(&(xl - p));
            let base = m - 2.0 * self.projection.shape[a] * w;
            // c_ab: ∂m_a/∂x_b = [c_ab]×, indexed by the global node b.
            let mut c = [Vec3::zeros(); 4];
            c[(a + 1) % 3] = xl - q; // b = p: [x_s − x_q]×
            c[(a + 2) % 3] = p - xl; // b = q: [x_p − x_s]×
            c[3] = q - p; // b = s = l: [x_q − x_p]×
            std::array::from_fn(|b| (base.cross(&edges[b]) + w.cross(&c[b])) * inv_w2)
        })
    }
}
