//! Morton (Z-order) codes: 21 bits per axis interleaved into 63 bits.
//!
//! Sorting points by their code puts points that are close in space close in the sorted order.
//! The search itself sorts along a Hilbert curve (`search::hilbert`: the tree's facets, and the
//! batches of queries in no particular order), whose codes share the quantisation and the bit
//! interleaving here; the Z curve jumps where the Hilbert curve does not.

use crate::linalg::Vec3;
use crate::search::aabb::Aabb;

/// Bits per axis of the grid the points are quantised on.
pub(crate) const BITS: u32 = 21;

/// Spreads the low 21 bits of `v` so that bit `b` moves to bit `3b`.
#[must_use]
#[inline]
pub(crate) fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// The Morton code of `p` quantised on a 2²¹ grid over `bounds`.
#[must_use]
#[inline]
pub fn morton_code(p: &Vec3, bounds: &Aabb) -> u64 {
    interleave(quantise(p, bounds).map(u64::from))
}

/// The low 21 bits of `x`, `y`, `z` interleaved, bit `b` of `x` at bit `3b`, of `y` at `3b + 1`,
/// of `z` at `3b + 2`.
#[must_use]
#[inline]
pub(crate) fn interleave([x, y, z]: [u64; 3]) -> u64 {
    spread(x) | (spread(y) << 1) | (spread(z) << 2)
}

/// The cell of `p` on a 2²¹ grid over `bounds`, each coordinate in `0 … 2²¹ − 1` (points outside
/// the box are clamped into it, a NaN coordinate goes to 0).
#[must_use]
#[inline]
pub(crate) fn quantise(p: &Vec3, bounds: &Aabb) -> [u32; 3] {
    let extent = (bounds.max - bounds.min).sup(&Vec3::repeat(f64::MIN_POSITIVE));
    let scale = f64::from((1u32 << BITS) - 1);
    std::array::from_fn(|d| {
        let t = ((p[d] - bounds.min[d]) / extent[d]).clamp(0.0, 1.0);
        // Truncation of a value in [0, 2^21) is the quantisation.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let cell = (t * scale) as u32;
        cell
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_interleaves_bits() {
        assert_eq!(spread(0b1), 0b1);
        assert_eq!(spread(0b11), 0b1001);
        assert_eq!(spread(0x1f_ffff), 0x1249_2492_4924_9249);
        let b = Aabb {
            min: Vec3::zeros(),
            max: Vec3::repeat(1.0),
        };
        assert_eq!(morton_code(&Vec3::zeros(), &b), 0);
        assert_eq!(morton_code(&Vec3::repeat(1.0), &b), (1u64 << 63) - 1);
        // x is the lowest bit of each triple.
        assert_eq!(
            morton_code(&Vec3::new(1.0, 0.0, 0.0), &b),
            0x1249_2492_4924_9249
        );
    }
}
