//! Leaves: the sorted facets (along a Hilbert curve, `search::hilbert`) cut into runs of at most
//! [`LEAF_SIZE`], each run's box as small as the run allows.
//!
//! # Cost
//! A query measures every leaf whose box is within its bound of it, and a leaf costs the same to
//! measure whether it holds one facet or eight (one lane each, `search::lanes`). For queries
//! spread around the surface, the chance that a leaf is listed grows with its box expanded by
//! the query's bound; the cost of a run is therefore taken as the half-area of its box `e`
//! expanded by a margin `m` on each axis,
//!
//! `c(run) = (e_x + m)(e_y + m) + (e_y + m)(e_z + m) + (e_z + m)(e_x + m)`,
//!
//! with `m` = [`MARGIN`] times the mean diagonal of the facets' boxes (of the chunk below, so it
//! follows the local mesh size), plus twice the search distance the leaf boxes are inflated by.
//! The `3m²` every run pays is the price of one more leaf; the rest prefers compact runs. Margins
//! of 0.5, 1, 1.5, 2 and 3 mean diagonals, coherent queries on the 10⁶-facet torus
//! (`search_loop closest 1000`, best of four interleaved rounds): 345.1, 333.5, 335.8, 341.0 and
//! 342.9 ns, against 356.9 for the leaves cut by code-bit splits alone (facets in Z-order then).
//! With the facets in Hilbert order, margins of 0.7, 1 and 1.5 were within noise of one another
//! (376.8, 357.8 and 350.7 ns in six rounds on a slow spell); in Z-order, the expanded box's
//! volume as the cost instead of its half-area was too (347.4 ns at a margin of two diagonals vs
//! 344.5, four rounds).
//!
//! # Partition
//! Among all cuts of a sequence of `n` facets into runs of 1 … [`LEAF_SIZE`] consecutive ones,
//! the one of least total cost follows by dynamic programming: `C(0) = 0`,
//! `C(j) = min_{1 ≤ k ≤ 8} C(j − k) + c(facets j − k … j − 1)`, the run's box grown facet by facet
//! (eight box unions per facet; ties keep the shortest last run, so the cut is deterministic). A
//! run does not join facets far apart along the curve's turns, whose box would be large, and leaves
//! fill up: with the facets in Z-order, on the benchmark's 10⁶-facet torus, 6.3 facets per leaf
//! against 5.2 when a range is split at its highest differing code bit down to eight facets or
//! fewer (the rule the tree above the leaves still follows, `search::layout`).
//!
//! The sorted facets are first cut at code-bit splits into chunks of at most [`CHUNK`]; each
//! chunk is partitioned on its own, in parallel. A chunk is a grid cell, so the cut between two
//! chunks is one the splits would have made anyway.

use rayon::prelude::*;

use crate::search::aabb::Aabb;
use crate::search::layout::{LEAF_SIZE, index, split_at_bit};

/// The margin `m`, in mean facet-box diagonals (see the module documentation).
pub(crate) const MARGIN: f64 = 1.0;

/// Most facets a chunk partitioned on its own holds.
const CHUNK: usize = 4096;

/// The cost of a run whose box is `b`, with margin `m`.
#[inline]
fn cost(b: &Aabb, m: f64) -> f64 {
    let e = b.max - b.min;
    let (x, y, z) = (e.x + m, e.y + m, e.z + m);
    x * y + y * z + z * x
}

/// The first index of each leaf over the sorted `keys`, then `keys.len()`: runs of at most
/// [`LEAF_SIZE`] of least total cost (see the module documentation). `facet_box` gives the box
/// of a facet; `inflation` is the search distance the leaf boxes will be inflated by.
pub(crate) fn leaf_starts(
    keys: &[(u64, u32)],
    inflation: f64,
    facet_box: impl Fn(u32) -> Aabb + Sync,
) -> Vec<u32> {
    let mut chunks = Vec::new();
    cut_chunks(keys, 0, keys.len(), &mut chunks);
    let mut starts: Vec<u32> = chunks
        .par_iter()
        .flat_map_iter(|&(lo, hi)| {
            let boxes: Vec<Aabb> = keys[lo..hi].iter().map(|&(_, f)| facet_box(f)).collect();
            runs(&boxes, margin(&boxes, inflation))
                .into_iter()
                .map(move |s| index(lo) + s)
        })
        .collect();
    starts.push(index(keys.len()));
    starts
}

/// Cuts `keys[lo..hi]` at code-bit splits into ranges of at most [`CHUNK`], in order.
fn cut_chunks(keys: &[(u64, u32)], lo: usize, hi: usize, out: &mut Vec<(usize, usize)>) {
    if hi - lo <= CHUNK {
        if hi > lo {
            out.push((lo, hi));
        }
        return;
    }
    let mid = split_at_bit(|i| keys[i].0, lo, hi);
    cut_chunks(keys, lo, mid, out);
    cut_chunks(keys, mid, hi, out);
}

/// The margin `m` for a chunk whose facet boxes are `boxes` (without the inflation if that is
/// not finite: every leaf box is then unbounded, and the facet size alone chooses the cut).
fn margin(boxes: &[Aabb], inflation: f64) -> f64 {
    let sum: f64 = boxes.iter().map(|b| (b.max - b.min).norm()).sum();
    #[allow(clippy::cast_precision_loss)]
    let mean = MARGIN * sum / boxes.len() as f64;
    let m = mean + 2.0 * inflation;
    if m.is_finite() { m } else { mean }
}

/// The first index of each run of least total cost over `boxes` (in order, from 0; without the
/// final end).
fn runs(boxes: &[Aabb], m: f64) -> Vec<u32> {
    let n = boxes.len();
    let mut total = vec![0.0; n + 1];
    let mut start = vec![0u32; n + 1];
    for j in 1..=n {
        let (mut best, mut from) = (f64::INFINITY, j - 1);
        let mut b = Aabb::EMPTY;
        for k in 1..=LEAF_SIZE.min(j) {
            b = b.union(&boxes[j - k]);
            let c = total[j - k] + cost(&b, m);
            if c < best {
                (best, from) = (c, j - k);
            }
        }
        total[j] = best;
        start[j] = index(from);
    }
    let mut starts = Vec::with_capacity(n / 4 + 1);
    let mut j = n;
    while j > 0 {
        j = start[j] as usize;
        starts.push(index(j));
    }
    starts.reverse();
    starts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::Vec3;

    fn unit_box(x: f64) -> Aabb {
        Aabb {
            min: Vec3::new(x, 0.0, 0.0),
            max: Vec3::new(x + 1.0, 1.0, 0.0),
        }
    }

    /// The total cost of the runs starting at `starts` (ending at `boxes.len()`).
    fn total(boxes: &[Aabb], starts: &[u32], m: f64) -> f64 {
        let ends = starts.iter().skip(1).copied().chain([index(boxes.len())]);
        starts
            .iter()
            .zip(ends)
            .map(|(&a, b)| {
                let run = &boxes[a as usize..b as usize];
                cost(&run.iter().fold(Aabb::EMPTY, |u, b| u.union(b)), m)
            })
            .sum()
    }

    #[test]
    fn runs_cover_every_facet_in_order_and_hold_at_most_a_leaf() {
        let boxes: Vec<Aabb> = (0..1000).map(|i| unit_box(f64::from(i % 37))).collect();
        let starts = runs(&boxes, 1.0);
        assert_eq!(starts[0], 0);
        let ends = starts.iter().skip(1).copied().chain([1000]);
        for (&a, b) in starts.iter().zip(ends) {
            assert!(a < b && (b - a) as usize <= LEAF_SIZE, "run {a}..{b}");
        }
    }

    #[test]
    fn runs_do_not_straddle_a_jump() {
        // Twelve facets in a row, then twelve far away: no run holds facets of both.
        let boxes: Vec<Aabb> = (0..24)
            .map(|i| unit_box(f64::from(i % 12) + if i < 12 { 0.0 } else { 1e3 }))
            .collect();
        let starts = runs(&boxes, 1.0);
        assert!(starts.contains(&12), "{starts:?}");
    }

    #[test]
    fn the_partition_costs_no_more_than_any_other() {
        // Against every cut into runs of one fixed size, from one to eight.
        let boxes: Vec<Aabb> = (0..200)
            .map(|i| unit_box(f64::from(i) + if i % 50 < 25 { 0.0 } else { 7.5 }))
            .collect();
        let m = 0.7;
        let best = total(&boxes, &runs(&boxes, m), m);
        for size in 1..=LEAF_SIZE {
            let fixed: Vec<u32> = (0..200).step_by(size).map(index).collect();
            assert!(
                best <= total(&boxes, &fixed, m) * (1.0 + 1e-12),
                "size {size}"
            );
        }
    }

    #[test]
    fn an_unbounded_inflation_leaves_the_facet_size_to_choose() {
        let boxes: Vec<Aabb> = (0..64).map(|i| unit_box(f64::from(i))).collect();
        let m = margin(&boxes, f64::INFINITY);
        assert!(m.is_finite() && m > 0.0);
        assert_eq!(runs(&boxes, m), runs(&boxes, margin(&boxes, 0.0)));
    }

    #[test]
    fn leaf_starts_end_at_the_count_and_cut_at_chunks() {
        let keys: Vec<(u64, u32)> = (0..3 * CHUNK as u64)
            .map(|i| (i, index(i as usize)))
            .collect();
        let starts = leaf_starts(&keys, 0.0, |f| unit_box(f64::from(f)));
        assert_eq!(*starts.last().unwrap(), index(keys.len()));
        assert!(
            starts
                .windows(2)
                .all(|w| w[0] < w[1] && (w[1] - w[0]) as usize <= LEAF_SIZE)
        );
        // Chunks are whole grid cells: with keys 0 … 3·4096 − 1 the first cut is at 8192,
        // the next at 4096.
        assert!(starts.contains(&4096) && starts.contains(&8192));
        assert!(leaf_starts(&[], 0.0, |f| unit_box(f64::from(f))) == vec![0]);
    }
}
