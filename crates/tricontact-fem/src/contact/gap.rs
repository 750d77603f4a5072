//! The gap of one slave node against its facet, in the two kinematic settings.
//!
//! * **Finite sliding** (default): the kernel's node–facet pair at the current positions
//!   `x = X + u`, `P = (x_l − x_i)·W` with its exact gradient `∇P = [−N_i W, −N_j W, −N_k W, W]` and
//!   Hessian `∇²P` (the facet is chosen anew at every evaluation).
//! * **Small sliding**: facet, shape functions `N⁰_a` and normal `W⁰` frozen at the start of the
//!   increment, `P = (x_l − Σ N⁰_a x_a)·W⁰`, linear in `x`: `∇P = [−N⁰_i W⁰, −N⁰_j W⁰, −N⁰_k W⁰, W⁰]`,
//!   `∇²P = 0`. Exact for small relative motion; cheaper and more robust when nodes sit on edges of a
//!   curved master, but wrong once a node slides by a sizeable part of a facet in one increment.

use tricontact::{Mat12, NodeFacet, Vec3, Vec12};

/// A node's gap with its derivatives.
#[derive(Clone, Copy, Debug)]
#[allow(clippy::large_enum_variant)] // short-lived, on the stack
pub enum Gap {
    /// Finite sliding: the kernel pair.
    Finite(NodeFacet),
    /// Small sliding: linear gap.
    Linear {
        /// `P`.
        gap: f64,
        /// `N⁰`.
        shape: [f64; 3],
        /// `W⁰`.
        normal: Vec3,
    },
}

impl Gap {
    /// Small-sliding gap of `xl` against facet corners `xf` with frozen `shape` and `normal`.
    #[must_use]
    pub fn linear(xf: [Vec3; 3], xl: Vec3, shape: [f64; 3], normal: Vec3) -> Self {
        let foot = xf[0] * shape[0] + xf[1] * shape[1] + xf[2] * shape[2];
        Self::Linear {
            gap: (xl - foot).dot(&normal),
            shape,
            normal,
        }
    }

    /// `P`.
    #[must_use]
    pub fn gap(&self) -> f64 {
        match self {
            Self::Finite(p) => p.gap(),
            Self::Linear { gap, .. } => *gap,
        }
    }

    /// Barycentric coordinates of the foot point.
    #[must_use]
    pub fn shape(&self) -> [f64; 3] {
        match self {
            Self::Finite(p) => p.projection.shape,
            Self::Linear { shape, .. } => *shape,
        }
    }

    /// `W`.
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        match self {
            Self::Finite(p) => p.facet.normal(),
            Self::Linear { normal, .. } => *normal,
        }
    }

    /// `∇P` over `[x_i, x_j, x_k, x_l]`.
    #[must_use]
    pub fn gradient(&self) -> Vec12 {
        match self {
            Self::Finite(p) => p.gap_gradient(),
            Self::Linear { shape, normal, .. } => {
                let mut g = Vec12::zeros();
                for a in 0..3 {
                    g.fixed_rows_mut::<3>(3 * a)
                        .copy_from(&(-shape[a] * normal));
                }
                g.fixed_rows_mut::<3>(9).copy_from(normal);
                g
            }
        }
    }

    /// `α ∇P⊗∇P`.
    #[must_use]
    pub fn outer(&self, alpha: f64) -> Mat12 {
        let g = self.gradient();
        g * g.transpose() * alpha
    }
}
