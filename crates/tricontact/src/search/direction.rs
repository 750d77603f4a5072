//! Directions in four bytes, for the unit vectors the incremental search keeps per listed facet.
//!
//! The components of a unit vector (or of the zero vector) are rounded to multiples of 1/1023
//! (`x`, `y`: eleven bits each) and 1/511 (`z`: ten bits) and packed into a `u32` as signed
//! integers. Decoding multiplies back, without normalising: the decoded vector is the encoded one
//! within `√(2 (1/2046)² + (1/1022)²) < 1.198·10⁻³` (Euclidean), whatever its length; the search
//! widens its bounds by [`DIRECTION_ERROR`] times the length it multiplies. (Three bytes, one per
//! component in steps of 1/127, were within 6.9·10⁻³: on the benchmark's 10⁶-facet torus after a
//! motion of 0.01 element sizes, the search measured 1.099 facets per query with them and 1.071
//! with these; the entry is twelve bytes either way.)

use crate::linalg::Vec3;

/// Largest distance between an encoded vector (components in `[−1, 1]`) and its decoded code.
pub(crate) const DIRECTION_ERROR: f64 = 1.2e-3;

/// Steps per unit of `x` and `y` (eleven bits, signed).
const XY_STEPS: f64 = 1023.0;

/// Steps per unit of `z` (ten bits, signed).
const Z_STEPS: f64 = 511.0;

/// A vector with components in `[−1, 1]`, in four bytes: `x` in bits 0–10, `y` in 11–21, `z` in
/// 22–31, each a two's-complement count of steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Direction(u32);

impl Direction {
    /// The zero vector.
    pub(crate) const ZERO: Direction = Direction(0);

    /// The code of `n` (the zero vector for a vector that is not finite).
    #[must_use]
    pub(crate) fn encode(n: &Vec3) -> Direction {
        if !n.iter().all(|c| c.is_finite()) {
            return Direction::ZERO;
        }
        // At most 1023 steps either way: fits its field (the casts keep the low bits).
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let q = |t: f64, steps: f64, bits: u32| {
            ((t.clamp(-1.0, 1.0) * steps).round() as i32 as u32) & ((1 << bits) - 1)
        };
        Direction(q(n.x, XY_STEPS, 11) | (q(n.y, XY_STEPS, 11) << 11) | (q(n.z, Z_STEPS, 10) << 22))
    }

    /// The vector this code stands for.
    #[must_use]
    #[inline(always)]
    #[allow(clippy::cast_possible_wrap)]
    pub(crate) fn decode(self) -> Vec3 {
        // Each field shifted to the top, then back with its sign extended.
        let c = self.0 as i32;
        let (x, y, z) = ((c << 21) >> 21, (c << 10) >> 21, c >> 22);
        Vec3::new(
            f64::from(x) * (1.0 / XY_STEPS),
            f64::from(y) * (1.0 / XY_STEPS),
            f64::from(z) * (1.0 / Z_STEPS),
        )
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
        // Components exactly between two steps (the bound's worst case), and the cube's corners.
        check(Vec3::new(0.5 / XY_STEPS, -0.5 / XY_STEPS, 0.5 / Z_STEPS));
        check(Vec3::new(1.0, -1.0, 1.0));
        check(Vec3::new(-1.0, 1.0, -1.0));
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
