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
//! Two identities make the second derivatives short. Let `G_a = n_a/|w|` (`= ∂N_a/∂x_l`, in-plane,
//! `Σ G_a = 0`), and extend both lists to the slave node with `N_l = −1`, `G_l = 0`.
//!
//! 1. The seed's `∂W/∂x_b = (I − W⊗W)[e_b]×/|w|` is rank one: `[e_b]×` maps an in-plane vector to a
//!    multiple of `W`, which the projector removes, and maps `W` to `e_b × W = −n_b`. Hence
//!    `∂W/∂x_b = −G_b ⊗ W`: only the normal component of a node's motion tilts the facet.
//! 2. `∇_b N_a = −N_b G_a + P (G_a·G_b) W`. Moving facet node `b` in-plane by `δ` leaves the plane and
//!    the projected point `p = x_l − P W` in place; differentiating `Σ N_c x_c = p`, `Σ N_c = 1` gives
//!    `δN_a = −N_b G_a·δ`. Moving it along `W` by `ε` tilts `W` by `−ε G_b` and shifts `P` by `−ε N_b`, so
//!    `p` moves in-plane by `ε P G_b`, and `δN_a = ε P G_a·G_b` (the tilted triangle projects onto the
//!    old one unchanged to first order). For `b = l`, `∇_l N_a = G_a`, which the same formula gives.
//!
//! Differentiating `g_a = −N_a W` with both identities,
//!
//! ```text
//! ∂²P/∂x_a∂x_b = N_b W⊗G_a + N_a G_b⊗W − P (G_a·G_b) W⊗W        (a, b = i, j, k, l)
//! ```
//!
//! which is visibly symmetric. The tests compare every entry, and `∇N_a`, with central finite
//! differences.

use crate::error::GeometryError;
use crate::facet::Facet;
use crate::linalg::{Mat12, Vec3, Vec12, all_finite};

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
    /// `G_a = ∂N_a/∂x_l` for `a = i, j, k` (see [`Facet::shape_gradient`]).
    pub gradients: [Vec3; 3],
}

/// Gap and shape functions of node `xl` against `facet` (the detection step).
///
/// # Errors
/// [`GeometryError::NonFinite`] for a non-finite `xl`; [`GeometryError::Overflow`] if the result
/// overflows.
#[inline]
pub fn project(facet: &Facet, xl: &Vec3) -> Result<Projection, GeometryError> {
    let gradients = std::array::from_fn(|a| facet.shape_gradient(a));
    project_with(facet, xl, &gradients)
}

/// [`project`] given the shape-function gradients `G_a` of the facet.
#[inline]
fn project_with(facet: &Facet, xl: &Vec3, g: &[Vec3; 3]) -> Result<Projection, GeometryError> {
    let [xi, xj, xk] = facet.nodes();
    let gap = (xl - xi).dot(&facet.normal());
    let shape = [
        (xl - xj).dot(&g[0]),
        (xl - xk).dot(&g[1]),
        (xl - xi).dot(&g[2]),
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
        let gradients = std::array::from_fn(|a| facet.shape_gradient(a));
        let projection = project_with(&facet, &xl, &gradients)?;
        Ok(Self {
            facet,
            node: xl,
            projection,
            gradients,
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
        if self.cannot_overflow(0.0, 1.0) || all_finite(&h) {
            Ok(h)
        } else {
            Err(GeometryError::Overflow)
        }
    }

    /// `∇²P` without the overflow check, for callers that check their own final result.
    #[inline]
    pub(crate) fn gap_hessian_unchecked(&self) -> Mat12 {
        self.second_order(0.0, 1.0)
    }

    /// A bound on every entry of [`NodeFacet::second_order`] and of the force `β ∇P`:
    /// `|α| M_N² + 2|β| M_N M_G + 3|β P| M_G² + |β| M_N` with `M_N = max(1, |N_a|)` and
    /// `M_G` the largest component of any `G_a` (so `|G_a·G_b| ≤ 3 M_G²`). When it is below
    /// `1e300` no entry can overflow, which spares callers a pass over the 156 outputs; otherwise
    /// they check every entry.
    pub(crate) fn second_order_bound(&self, alpha: f64, beta: f64) -> f64 {
        let mn = self
            .projection
            .shape
            .iter()
            .fold(1.0f64, |m, n| m.max(n.abs()));
        let mg = self.gradients.iter().fold(0.0f64, |m, g| m.max(g.amax()));
        let p = self.gap().abs();
        alpha.abs() * mn * mn
            + 2.0 * beta.abs() * mn * mg
            + 3.0 * beta.abs() * p * mg * mg
            + beta.abs() * mn
    }

    /// `true` when [`NodeFacet::second_order_bound`] rules out overflow.
    #[inline]
    pub(crate) fn cannot_overflow(&self, alpha: f64, beta: f64) -> bool {
        self.second_order_bound(alpha, beta) < 1e300
    }

    /// `α ∇P⊗∇P + β ∇²P`, the one formula behind the Hessian (`α = 0, β = 1`), the penalty tangent
    /// (`α, β = αP`) and the geometric stiffness (`0, λ`). Block `(a, b)` is
    ///
    /// ```text
    /// W ⊗ [(α N_a N_b − β P G_a·G_b) W + β N_b G_a] + β N_a G_b ⊗ W
    /// ```
    ///
    /// Column `(b, s)` of the result is `W_s X_b + β N_b Y_s` with the 12-vectors
    /// `X_b = [c_ab W + β N_a G_b]_a` (`c_ab = α N_a N_b − β P G_a·G_b`) and `Y_s = [G_a,s W]_a`,
    /// which keeps the work in short vector loops.
    #[inline]
    pub(crate) fn second_order(&self, alpha: f64, beta: f64) -> Mat12 {
        let w = self.facet.normal();
        let n = self.shape4();
        let g = self.in_plane_gradients();
        let p = self.gap();
        let mut x = [Vec12::zeros(); 4];
        let mut y = [Vec12::zeros(); 3];
        for a in 0..4 {
            for (b, xb) in x.iter_mut().enumerate() {
                let c = alpha * n[a] * n[b] - beta * p * g[a].dot(&g[b]);
                xb.fixed_rows_mut::<3>(3 * a)
                    .copy_from(&(c * w + (beta * n[a]) * g[b]));
            }
            for (s, ys) in y.iter_mut().enumerate() {
                ys.fixed_rows_mut::<3>(3 * a).copy_from(&(g[a][s] * w));
            }
        }
        let mut k = Mat12::zeros();
        for b in 0..4 {
            for s in 0..3 {
                k.set_column(3 * b + s, &(w[s] * x[b] + (beta * n[b]) * y[s]));
            }
        }
        k
    }

    /// `G_a = n_a/|w| = ∂N_a/∂x_l` for `a = i, j, k`, and `G_l = 0`.
    #[must_use]
    #[inline]
    pub fn in_plane_gradients(&self) -> [Vec3; 4] {
        let [gi, gj, gk] = self.gradients;
        [gi, gj, gk, Vec3::zeros()]
    }

    /// `∇_b N_a = −N_b G_a + P (G_a·G_b) W` for `a ∈ {i, j, k}` and `b ∈ {i, j, k, l}` (see the
    /// module doc).
    ///
    /// # Errors
    /// [`GeometryError::Overflow`] if an entry overflows (a gap `P` so large against the facet's
    /// size that `P |G_a|²` is beyond the range of `f64`, as in [`NodeFacet::gap_hessian`]).
    pub fn shape_gradients(&self) -> Result<[[Vec3; 4]; 3], GeometryError> {
        let shape = self.shape4();
        let g = self.in_plane_gradients();
        let normal = self.facet.normal();
        let out: [[Vec3; 4]; 3] = std::array::from_fn(|a| {
            std::array::from_fn(|b| -shape[b] * g[a] + self.gap() * g[a].dot(&g[b]) * normal)
        });
        if out
            .iter()
            .flatten()
            .all(|v| v.iter().all(|c| c.is_finite()))
        {
            Ok(out)
        } else {
            Err(GeometryError::Overflow)
        }
    }
}
