//! Tree nodes: four child boxes in `f32` (rounded outwards) stored axis by axis, and four child
//! references.
//!
//! A reference with the top bit set is a leaf: `LEAF_FLAG | count << 27 | first` names `count ≤ 15`
//! facets from `order[first..]`; otherwise it is the index of an internal node. An unused slot is
//! the empty leaf with an empty box (`+∞ … −∞`), whose distance is `+∞`, so it is never visited.
//!
//! The squared distances from a point to the four boxes,
//! `Σ_axis max(lo − x, x − hi, 0)²`, are computed for the four boxes together in one
//! `wide::f64x4` per quantity, the `f32` bounds widened to `f64`; rounding the boxes outwards keeps
//! every distance a lower bound of the true one.

use wide::f64x4;

use crate::linalg::Vec3;
use crate::search::aabb::Aabb;

/// Children per internal node.
pub(crate) const WIDTH: usize = 4;

/// Top bit of a child reference: the child is a leaf.
const LEAF_FLAG: u32 = 1 << 31;

/// A child reference: an internal node index, or a leaf `LEAF_FLAG | count << 28 | first`.
pub(crate) type Child = u32;

/// The reference of an unused child slot (an empty leaf).
pub(crate) const EMPTY: Child = LEAF_FLAG;

/// A leaf reference holding `count ≤ 15` facets from `order[first..]` (`first < 2²⁷`).
#[inline]
pub(crate) fn leaf(first: u32, count: u32) -> Child {
    debug_assert!(count < 16 && first < 1 << 27);
    LEAF_FLAG | (count << 27) | first
}

/// `Some((first, count))` for a leaf reference.
#[inline]
pub(crate) fn as_leaf(child: Child) -> Option<(usize, usize)> {
    (child & LEAF_FLAG != 0).then_some((
        (child & 0x07ff_ffff) as usize,
        ((child >> 27) & 15) as usize,
    ))
}

/// An internal node.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    lo: [[f32; WIDTH]; 3],
    hi: [[f32; WIDTH]; 3],
    pub(crate) child: [Child; WIDTH],
}

impl Node {
    /// A node with the given references and empty boxes.
    pub(crate) const fn new(child: [Child; WIDTH]) -> Self {
        Self {
            lo: [[f32::INFINITY; WIDTH]; 3],
            hi: [[f32::NEG_INFINITY; WIDTH]; 3],
            child,
        }
    }

    /// Squared distances from `p` to the four child boxes (zero inside, `+∞` for empty slots).
    #[inline]
    pub(crate) fn child_distances_squared(&self, p: &Vec3) -> [f64; WIDTH] {
        self.distances_squared(p, p).to_array()
    }

    /// Squared distances from the box `b` to the four child boxes (zero where they overlap, `+∞`
    /// for empty slots): a lower bound of the squared distance from any point of `b`.
    #[inline]
    pub(crate) fn child_distances_squared_to_box(&self, b: &Aabb) -> [f64; WIDTH] {
        self.distances_squared(&b.min, &b.max).to_array()
    }

    /// `Σ_axis max(lo − high, low − hi, 0)²` for the box `[low, high]` (a point when equal).
    #[inline(always)]
    fn distances_squared(&self, low: &Vec3, high: &Vec3) -> f64x4 {
        let mut d = f64x4::ZERO;
        for axis in 0..3 {
            let lo = f64x4::new(self.lo[axis].map(f64::from));
            let hi = f64x4::new(self.hi[axis].map(f64::from));
            let below = lo - f64x4::splat(high[axis]);
            let above = f64x4::splat(low[axis]) - hi;
            // `fast_max` is the machine's max: an empty slot gives +∞ (its lo is +∞, hi −∞).
            let g = below.fast_max(above).fast_max(f64x4::ZERO);
            d += g * g;
        }
        d
    }

    /// The box of child `k` (as stored: `f32`, rounded outwards).
    #[inline]
    pub(crate) fn child_box(&self, k: usize) -> Aabb {
        Aabb {
            min: Vec3::new(
                f64::from(self.lo[0][k]),
                f64::from(self.lo[1][k]),
                f64::from(self.lo[2][k]),
            ),
            max: Vec3::new(
                f64::from(self.hi[0][k]),
                f64::from(self.hi[1][k]),
                f64::from(self.hi[2][k]),
            ),
        }
    }

    /// Stores `b` as the box of child `k`, rounded outwards to `f32`.
    pub(crate) fn set_child_box(&mut self, k: usize, b: &Aabb) {
        for axis in 0..3 {
            self.lo[axis][k] = round_down(b.min[axis]);
            self.hi[axis][k] = round_up(b.max[axis]);
        }
    }
}

/// The largest `f32` not above `x` (NaN for NaN).
///
/// `y = x as f32` is the nearest; when it lies above `x` the answer is the `f32` below it, whose
/// bits are one less for `y > 0` and one more for `y < 0` (`y` is never `+0` then: `x as f32`
/// is `+0` only for `0 ≤ x`, and `−0` steps to the smallest negative subnormal, one more). The
/// step is taken without a branch: coordinates of both signs made `f32::next_down`'s branch on
/// the sign mispredict in the tree's build.
#[allow(clippy::cast_possible_truncation)]
pub(crate) fn round_down(x: f64) -> f32 {
    let y = x as f32;
    let toward = if y > 0.0 { u32::MAX } else { 1 };
    let step = if f64::from(y) > x { toward } else { 0 };
    f32::from_bits(y.to_bits().wrapping_add(step))
}

/// The smallest `f32` not below `x` (NaN for NaN): as [`round_down`], mirrored (`y` is never `−0`
/// when it lies below `x`, and `+0` steps to the smallest positive subnormal).
#[allow(clippy::cast_possible_truncation)]
fn round_up(x: f64) -> f32 {
    let y = x as f32;
    let toward = if y < 0.0 { u32::MAX } else { 1 };
    let step = if f64::from(y) < x { toward } else { 0 };
    f32::from_bits(y.to_bits().wrapping_add(step))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The branch-free steps equal `next_down` / `next_up` wherever a step is taken, and the
    /// results bracket `x`, on special values and on values of both signs at every scale.
    #[test]
    fn rounding_is_next_down_and_next_up() {
        let mut xs = vec![
            0.0,
            -0.0,
            f64::from(f32::MIN_POSITIVE),
            1e-46,
            -1e-46,
            1e-300,
            -1e-300,
            f64::from(f32::MAX) * 1.000_000_1,
            -f64::from(f32::MAX) * 1.000_000_1,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut r = crate::search::scenes::uniform(3);
        for _ in 0..20_000 {
            let scale = 10f64.powf(90.0 * r() - 50.0);
            xs.push((r() - 0.5) * scale);
        }
        for x in xs {
            #[allow(clippy::cast_possible_truncation)]
            let y = x as f32;
            let down = if f64::from(y) > x { y.next_down() } else { y };
            let up = if f64::from(y) < x { y.next_up() } else { y };
            assert_eq!(round_down(x).to_bits(), down.to_bits(), "round_down({x:e})");
            assert_eq!(round_up(x).to_bits(), up.to_bits(), "round_up({x:e})");
            assert!(
                f64::from(round_down(x)) <= x && f64::from(round_up(x)) >= x,
                "{x:e}"
            );
        }
        assert!(round_down(f64::NAN).is_nan() && round_up(f64::NAN).is_nan());
    }

    #[test]
    fn leaf_references_keep_their_first_slot_and_count() {
        // Every slot of the largest surface the search takes fits.
        let last = u32::try_from(crate::search::MAX_FACETS).unwrap();
        for first in [0u32, 1, 12_345, last] {
            for count in 0..16 {
                let c = leaf(first, count);
                assert_eq!(as_leaf(c), Some((first as usize, count as usize)));
            }
        }
        assert_eq!(as_leaf(EMPTY), Some((0, 0)));
        // Internal node indices are not leaves.
        for node in [0u32, 1, (1 << 31) - 1] {
            assert_eq!(as_leaf(node), None);
        }
    }

    #[test]
    fn boxes_round_outwards() {
        for x in [0.1f64, -0.1, 1e10 + 0.3, -3.7e-5, 0.0] {
            assert!(f64::from(round_down(x)) <= x && f64::from(round_up(x)) >= x);
        }
    }

    #[test]
    fn distances_are_lower_bounds_and_empty_slots_infinite() {
        let mut n = Node::new([EMPTY; WIDTH]);
        let b = Aabb {
            min: Vec3::new(0.1, 0.2, 0.3),
            max: Vec3::new(1.1, 1.2, 1.3),
        };
        n.set_child_box(1, &b);
        for p in [
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(-1.0, 2.0, 0.7),
            Vec3::new(3.0, -0.4, 9.0),
        ] {
            let d = n.child_distances_squared(&p);
            assert!(
                d[1] <= b.distance_squared(&p) && d[1] >= b.distance_squared(&p) * (1.0 - 1e-6)
            );
            assert!(d[0].is_infinite() && d[2].is_infinite() && d[3].is_infinite());
        }
        assert_eq!(as_leaf(leaf(12345, 4)), Some((12345, 4)));
        assert_eq!(as_leaf(EMPTY), Some((0, 0)));
        assert_eq!(as_leaf(77), None);
    }
}
