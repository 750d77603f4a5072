//! Hilbert codes: the position along a 3D Hilbert curve of a point quantised to 21 bits per axis,
//! 63 bits in all.
//!
//! The code is computed by Skilling's transform ("Programming the Hilbert curve", AIP Conference
//! Proceedings 707, 2004): the three coordinates are turned, level by level from the top bit, into
//! the "transposed" index (at each level, an axis whose bit is set inverts the lower bits of the
//! first axis, and one whose bit is clear exchanges its lower bits with the first axis's; then a
//! Gray decoding), whose bits, interleaved with the first axis most significant, are the index.
//! Here the branches of that loop are replaced by masks, and eight points are encoded at once,
//! one per lane of a `wide::u32x8`. Only the top 12 levels of the 21 follow
//! the Hilbert curve; within each cell of level 12 (a 2⁻¹² part of the box per axis, far below a
//! facet of any mesh the tree is worth building for) the nine finer levels follow the Z curve: on
//! all 21 levels the transform took half the build's time (figures below).
//!
//! Like a Morton code, the top `3k` bits name the cell of level `k` that holds the point, so the
//! codes of a cell form one contiguous range and a range split at its highest differing bit splits
//! into whole sub-cells. Unlike the Z curve, the Hilbert curve never jumps: consecutive cells along
//! it share a face. Sorted along it, runs of consecutive facets are compact more often, and the
//! leaves cut from them (`search::leaves`) fuller and smaller: on the benchmark's 10⁶-facet torus,
//! 6.58 facets a leaf against 6.3 in Z-order. With all 21 levels along the Hilbert curve, coherent
//! queries were 5 % faster than in Z-order (`search_loop closest 1000`, best of two sets of four
//! interleaved rounds, 319.9 and 322.7 vs 337.8 and 339.7 ns) and 3.5 % at 10⁵ (310.6 vs 321.6);
//! with the top 12 levels, as built now, 4 % (328.6 vs 340.8 ns at 10⁶, 315.8 vs 329.7 at 10⁵,
//! 284.1 vs 297.5 at 10⁴, best of three or four interleaved rounds). The build on two threads at
//! 10⁶ (`search_loop build 1000 5 2`, best of three interleaved rounds): 130.5 ns per facet, against
//! 118.4 in Z-order and 140.2 with the transform one point at a time (197.1 with all 21 levels,
//! one point at a time, in an earlier round).

use rayon::prelude::*;
use wide::u32x8;

use crate::linalg::Vec3;
use crate::search::aabb::Aabb;
use crate::search::layout::index;
use crate::search::morton::{BITS, interleave, quantise};

/// Levels ordered along the Hilbert curve; the `BITS − LEVELS` finer ones follow the Z curve
/// within each cell of level [`LEVELS`].
const LEVELS: u32 = 12;

/// The Hilbert code of `p` quantised on a 2²¹ grid over `bounds` (the quantisation of
/// [`crate::search::morton::morton_code`]): its top `LEVELS` (12) levels along the Hilbert curve, the
/// finer ones in Z-order within their cell. One lane of [`hilbert_codes`], which the tree and the
/// reordering of batches call through `sorted_keys`.
#[must_use]
#[inline]
pub fn hilbert_code(p: &Vec3, bounds: &Aabb) -> u64 {
    hilbert_codes(std::slice::from_ref(p), bounds)[0]
}

/// [`hilbert_code`] of up to eight points at once (the transform in lanes of `u32x8`): entry `k`
/// is the code of `points[k]`; the entries past `points.len()` repeat the last point's.
///
/// # Panics
/// If `points` is empty or holds more than eight points.
#[must_use]
#[inline]
pub fn hilbert_codes(points: &[Vec3], bounds: &Aabb) -> [u64; 8] {
    assert!((1..=8).contains(&points.len()), "one to eight points");
    let cells: [[u32; 3]; 8] =
        std::array::from_fn(|k| quantise(&points[k.min(points.len() - 1)], bounds));
    let fine = BITS - LEVELS;
    let axis = |d: usize| u32x8::new(std::array::from_fn(|k| cells[k][d] >> fine));
    let index = hilbert_index([axis(0), axis(1), axis(2)]).map(u32x8::to_array);
    std::array::from_fn(|k| {
        let below = interleave(cells[k].map(|v| u64::from(v & ((1 << fine) - 1))));
        (first_axis_high(index, k) << (3 * fine)) | below
    })
}

/// Lane `k` of a transposed index interleaved, its first axis most significant.
#[inline]
fn first_axis_high(index: [[u32; 8]; 3], k: usize) -> u64 {
    interleave([2, 1, 0].map(|d| u64::from(index[d][k])))
}

/// The keys `(code, i)` of the items `0..n` sorted (by code, then index: deterministic), the code
/// the [`hilbert_code`] of `point(i)`, computed eight at a time in parallel; an item without a
/// point is keyed `u64::MAX`, past every code, so it sorts last.
pub(crate) fn sorted_keys(
    n: usize,
    bounds: &Aabb,
    point: impl Fn(usize) -> Option<Vec3> + Sync,
) -> Vec<(u64, u32)> {
    // Written in place: a parallel collect gathers pieces and copies them.
    let mut keys: Vec<(u64, u32)> = vec![(0, 0); n];
    keys.par_chunks_mut(8).enumerate().for_each(|(at, out)| {
        let points: [Option<Vec3>; 8] =
            std::array::from_fn(|k| (k < out.len()).then(|| point(8 * at + k)).flatten());
        let placed = points.map(|p| p.unwrap_or(bounds.min));
        let codes = hilbert_codes(&placed[..out.len()], bounds);
        for (k, key) in out.iter_mut().enumerate() {
            let code = if points[k].is_some() {
                codes[k]
            } else {
                u64::MAX
            };
            *key = (code, index(8 * at + k));
        }
    });
    keys.par_sort_unstable();
    keys
}

/// The transposed Hilbert index of eight cells of a grid of 2^[`LEVELS`] cells per axis, lane by
/// lane: interleaved, first axis most significant, they are the index.
#[inline]
fn hilbert_index(mut x: [u32x8; 3]) -> [u32x8; 3] {
    let zero = u32x8::ZERO;
    // Inverse undo, from the top level down.
    let mut q = 1u32 << (LEVELS - 1);
    while q > 1 {
        let (p, bit) = (u32x8::splat(q - 1), u32x8::splat(q));
        // Where bit `q` of axis `i` is set, the lower bits of the first axis are inverted; where
        // it is clear (`keep` all ones), they are exchanged with axis `i`'s (nothing for the
        // first axis itself).
        let clear = |v: u32x8| (v & bit).simd_eq(zero);
        x[0] ^= p & !clear(x[0]);
        for i in 1..3 {
            let keep = clear(x[i]);
            let t = (x[0] ^ x[i]) & p & keep;
            x[0] ^= (p & !keep) | t;
            x[i] ^= t;
        }
        q >>= 1;
    }
    // Gray encode: `t` is the XOR of `q − 1` over the bits `q > 1` set in the last axis, so its
    // bit `j` is the parity of that axis's bits above `j` (a suffix XOR, by shifts).
    x[1] ^= x[0];
    x[2] ^= x[1];
    let mut t = x[2] >> 1;
    for shift in [1, 2, 4, 8, 16] {
        t ^= t >> shift;
    }
    x.map(|v| v ^ t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells of a grid of `2^k` per axis (coordinates spaced by `2^(LEVELS − k)`), sorted by
    /// Hilbert index.
    fn cells_in_order(k: u32) -> Vec<([u32; 3], u64)> {
        let n = 1u32 << k;
        let step = 1u32 << (LEVELS - k);
        let mut cells: Vec<([u32; 3], u64)> = (0..n * n * n)
            .map(|i| {
                let c = [i % n, (i / n) % n, i / (n * n)];
                let lanes = hilbert_index(c.map(|v| u32x8::splat(v * step))).map(u32x8::to_array);
                (c, first_axis_high(lanes, 0))
            })
            .collect();
        cells.sort_by_key(|&(_, code)| code);
        cells
    }

    #[test]
    fn consecutive_cells_share_a_face() {
        for k in 1..=4 {
            let cells = cells_in_order(k);
            for w in cells.windows(2) {
                assert!(w[0].1 < w[1].1, "codes are distinct");
                let steps: u32 = (0..3).map(|d| w[0].0[d].abs_diff(w[1].0[d])).sum();
                assert_eq!(steps, 1, "{:?} then {:?} (level {k})", w[0].0, w[1].0);
            }
        }
    }

    #[test]
    fn the_top_bits_name_the_cell() {
        // Level 4: the cells of each octant of level 1 are one contiguous run of the order, and
        // their codes share their top three bits.
        let cells = cells_in_order(4);
        for run in cells.chunks(cells.len() / 8) {
            let octant = |c: &[u32; 3]| c.map(|v| v / 8);
            assert!(run.iter().all(|(c, _)| octant(c) == octant(&run[0].0)));
            let top = 3 * LEVELS - 3;
            assert!(run.iter().all(|(_, code)| code >> top == run[0].1 >> top));
        }
    }

    #[test]
    fn eight_at_once_equal_one_at_a_time() {
        let b = Aabb {
            min: Vec3::new(-1.0, 0.0, 2.0),
            max: Vec3::new(3.0, 0.5, 9.0),
        };
        let points: [Vec3; 8] = std::array::from_fn(|k| {
            #[allow(clippy::cast_precision_loss)]
            let s = k as f64;
            Vec3::new(-1.0 + 0.53 * s, 0.07 * s, 2.0 + 0.9 * s)
        });
        let codes = hilbert_codes(&points, &b);
        for (p, code) in points.iter().zip(codes) {
            assert_eq!(code, hilbert_code(p, &b));
        }
        assert!(codes.windows(2).all(|w| w[0] != w[1]));
        // Fewer than eight: the rest repeat the last point's code.
        let three: [u64; 8] = std::array::from_fn(|k| codes[k.min(2)]);
        assert_eq!(hilbert_codes(&points[..3], &b), three);
    }

    #[test]
    fn sorted_keys_are_the_codes_in_order_with_the_pointless_last() {
        let b = Aabb {
            min: Vec3::zeros(),
            max: Vec3::repeat(1.0),
        };
        // Twenty items (two full chunks of eight and a part), every fifth without a point, and
        // two items at one point (their order is that of their indices).
        let point = |i: usize| {
            #[allow(clippy::cast_precision_loss)]
            let t = (i % 13) as f64 / 13.0;
            (i % 5 != 4).then(|| Vec3::new(t, (3.0 * t) % 1.0, (7.0 * t) % 1.0))
        };
        let keys = sorted_keys(20, &b, point);
        let mut expected: Vec<(u64, u32)> = (0..20)
            .map(|i| {
                (
                    point(i).map_or(u64::MAX, |p| hilbert_code(&p, &b)),
                    index(i),
                )
            })
            .collect();
        expected.sort_unstable();
        assert_eq!(keys, expected);
        assert!(
            keys[16..]
                .iter()
                .all(|&(code, i)| code == u64::MAX && i % 5 == 4)
        );
        assert_eq!(point(0), point(13), "a tie, ordered by index");
    }

    #[test]
    fn the_code_spans_63_bits_from_the_origin() {
        let b = Aabb {
            min: Vec3::zeros(),
            max: Vec3::repeat(1.0),
        };
        assert_eq!(hilbert_code(&Vec3::zeros(), &b), 0);
        // Every code is below 2⁶³, and a point outside the box is clamped into it.
        let far = hilbert_code(&Vec3::repeat(7.0), &b);
        assert!(far < 1 << 63);
        assert_eq!(far, hilbert_code(&Vec3::repeat(1.0), &b));
        // Two points of one cell of level 12 share the top 36 bits and differ below them.
        let (p, q) = (Vec3::new(0.3, 0.6, 0.2), Vec3::new(0.3, 0.6, 0.2 + 1e-5));
        let fine = 3 * (BITS - LEVELS);
        assert_eq!(hilbert_code(&p, &b) >> fine, hilbert_code(&q, &b) >> fine);
        assert_ne!(hilbert_code(&p, &b), hilbert_code(&q, &b));
    }
}
