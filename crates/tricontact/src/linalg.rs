//! Small fixed-size linear-algebra helpers shared by the kernel.
//!
//! * `skew(a)` is the matrix `[a]×` with `[a]× b = a × b`.
//! * Generalised coordinates of a node–facet pair are stacked as
//!   `x = [x_i, x_j, x_k, x_l]` (12 entries); block `a` occupies rows `3a..3a+3`.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// A 3-vector of `f64`.
pub type Vec3 = Vector3<f64>;
/// A 3×3 matrix of `f64`.
pub type Mat3 = Matrix3<f64>;
/// The 12 coordinates of a node–facet pair, `[x_i, x_j, x_k, x_l]`.
pub type Vec12 = SVector<f64, 12>;
/// A 12×12 matrix over the node–facet coordinates.
pub type Mat12 = SMatrix<f64, 12, 12>;

/// The skew-symmetric matrix `[a]×`, such that `[a]× b = a × b`.
#[must_use]
#[inline]
pub fn skew(a: &Vec3) -> Mat3 {
    Mat3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// `true` when every entry is finite: NaN and ±∞ propagate into a sum (which may also overflow for
/// finite entries near `f64::MAX`: those count as not finite). Four independent partial sums let the
/// compiler vectorise the loop.
#[must_use]
#[inline]
pub(crate) fn all_finite<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> bool {
    let mut acc = [0.0f64; 4];
    let chunks = m.as_slice().chunks_exact(4);
    let rest: f64 = chunks.remainder().iter().sum();
    for chunk in chunks {
        for (a, v) in acc.iter_mut().zip(chunk) {
            *a += v;
        }
    }
    (acc[0] + acc[1] + acc[2] + acc[3] + rest).is_finite()
}
