//! Directions in three bytes, for the unit vectors the incremental search keeps per listed facet.
//!
//! Each component of a unit vector (or of the zero vector) is rounded to a multiple of 1/127 and
//! stored as an `i8`. Decoding multiplies back (by the rounded 1/127), without normalising: the decoded vector is the
//! encoded one within `√3/254 < 6.9·10⁻³` (Euclidean), whatever its length; the search widens its
//! bounds by [`DIRECTION_ERROR`] times the length it multiplies.

use crate::linalg::Vec3;

/// Largest distance between an encoded vector (components in `[−1, 1]`) and its decoded code.
pub(crate) const DIRECTION_ERROR: f64 = 7e-3;

/// Steps per unit.
const STEPS: f64 = 127.0;

/// A vector with components in `[−1, 1]`, in three bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Direction([i8; 3]);

impl Direction {
    /// The zero vector.
    pub(crate) const ZERO: Direction = Direction([0; 3]);

    /// The code of `n` (the zero vector for a vector that is not finite).
    #[must_use]
    pub(crate) fn encode(n: &Vec3) -> Direction {
        if !n.iter().all(|c| c.is_finite()) {
            return Direction::ZERO;
        }
        #[allow(clippy::cast_possible_truncation)]
        let q = |t: f64| (t.clamp(-1.0, 1.0) * STEPS).round() as i8;
        Direction([q(n.x), q(n.y), q(n.z)])
    }

    /// The vector this code stands for.
    #[must_use]
    #[inline(always)]
    pub(crate) fn decode(self) -> Vec3 {
        let [x, y, z] = self.0;
        let f = |c: i8| f64::from(c) * (1.0 / STEPS);
        Vec3::new(f(x), f(y), f(z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::scenes::uniform;

    #[test]
    fn decoded_directions_are_within_the_stated_error() {
        let mut r = uniform(21);
        let mut worst = 0.0f64;
        let mut check = |n: Vec3| {
            let back = Direction::encode(&n).decode();
            worst = worst.max((back - n).norm());
        };
        for _ in 0..1_000_000 {
            // Uniform on the sphere: z uniform, azimuth uniform.
            let z = 2.0 * r() - 1.0;
            let a = std::f64::consts::TAU * r();
            let s = (1.0 - z * z).sqrt();
            check(Vec3::new(s * a.cos(), s * a.sin(), z));
        }
        // Components exactly between two steps, and the cube's corners.
        let half = 0.5 / STEPS;
        check(Vec3::new(half, half, half));
        check(Vec3::new(1.0, -1.0, 1.0));
        assert!(worst <= DIRECTION_ERROR, "worst error {worst:e}");
        assert!(
            worst > 0.5 * DIRECTION_ERROR,
            "the bound is tight: {worst:e}"
        );
    }

    #[test]
    fn zero_and_non_finite_vectors_decode_to_zero() {
        for n in [Vec3::zeros(), Vec3::new(f64::NAN, 0.0, 1.0)] {
            assert_eq!(Direction::encode(&n).decode(), Vec3::zeros());
        }
        assert_eq!(Direction::ZERO.decode(), Vec3::zeros());
    }
}
