//! Coherent batches: a packet of consecutive queries shares one traversal.
//!
//! Queries that come in spatial order (the nodes of a slave surface, numbered along it) ask about
//! the same few leaves. For a packet of [`PACKET`] consecutive queries with bounding box `Q`, one
//! traversal gathers every leaf whose box is within a radius `R` of `Q` (into fixed arrays, boxes
//! eight to a `wide::f64x8`). Each query first measures the whole gathered leaf that held the
//! previous query's answer (for the first query of a packet: the previous answer's facet), which
//! gives its first bound; it then lists the gathered leaves whose boxes are within that bound (a
//! flat loop, eight boxes per step, the kept ones compacted by AVX-512 `vpcompressd` where the
//! build has it) and measures all of them. Nearly every listed leaf would be measured even with a
//! bound shrinking between them (4.1 of 4.3 on the 10⁵ torus), and without a test between them
//! their measurements overlap: the query keeps its best lane by lane (`lanes::LaneBest`),
//! branch-free, with the closest point of each lane's best, so the winner needs no further
//! measurement.
//!
//! On the 10⁵-facet torus of the benchmark a packet gathers about 42 leaves (of up to eight
//! facets, in an AVX-512 build) in 42 node visits, and a query lists 4.3 of them, the previous
//! answer's among them, and measures them all. The alternatives measured and not kept (bounds per
//! leaf and per facet that would measure fewer leaves, other packet sizes and radii, prefetching,
//! gathering ahead, padded rows, huge pages), with their figures, are in
//! `docs/search-benchmarks.md` ("The coherent query, as measured"): fewer measurements have not
//! bought time, since the measurements overlap with the rest of the work.
//!
//! # Exactness
//! A leaf left out is farther than `R` from `Q`, hence from every query of the packet. So when a
//! query's best squared distance `b²` satisfies `b² ≤ R²`, no facet outside the gathered leaves can
//! beat or tie it (the gathering bound has the same relative tie margin as the tree's pruning), and
//! the answer — the best in the total order (distance, then facet index) — is the tree's. When a
//! query's answer is not certified that way (it is farther than `R`), the query falls back to the
//! full traversal, seeded with what it found.
//!
//! # Batches in no particular order
//! A batch of at least 4096 queries (`REORDER_MIN`) whose consecutive queries are far apart (the
//! median step over evenly spaced samples above four mean leaf diagonals) is answered in the order
//! of its points along the tree's Hilbert curve (`search::hilbert`) and the answers put back in
//! place. On the 10⁶-facet torus, shuffled queries went from 0.41 to 1.2 M/s per core when this
//! reordering came, in Z-order; the Hilbert order, whose curve never jumps, then took them from
//! 648.3 to 592.6 ns a query (`search_loop random 1000`, best of three interleaved rounds).
//! Forcing the Z-order on a batch already in surface order made it 1.4–1.7× slower (sorting,
//! copies, and Z-order packets are less compact than rows along the surface), hence the test.
//!
//! # Radius and fallbacks
//! `R` follows the data: 1.25 times the largest answer distance of the previous packet, capped by
//! the search distance (with a finite search distance `R` never needs to exceed it: answers beyond
//! it are `None`). A chunk's first query is answered alone by a traversal; 1.25 times its answer
//! distance, or the mean leaf diagonal if longer, is the first estimate (answering the whole
//! first packet query by query instead cost about 2 % at 10⁶). A packet whose queries are spread
//! out (random order) would gather too much: when the gathering exceeds [`MAX_LEAVES`] leaves it
//! is abandoned and the packet is answered query by query, so an incoherent batch costs about what
//! it costs without packets; so is a packet whose queries are spread over more than eight radii,
//! without trying.

use std::cell::RefCell;

use rayon::prelude::*;

use wide::f64x8;

use crate::linalg::Vec3;
use crate::search::aabb::Aabb;
use crate::search::bvh::{Bvh, index};
use crate::search::hilbert::sorted_keys;
use crate::search::lanes::LaneBest;
use crate::search::node::{Child, as_leaf};
use crate::search::query::{Candidate, HINT_CHUNK, Hit, Query, TIE_MARGIN};
use crate::search::surface::Surface;

/// Queries per packet.
pub const PACKET: usize = 16;

/// Most leaves a packet gathers before it falls back to one traversal per query.
pub const MAX_LEAVES: usize = 128;

/// A packet whose box diagonal exceeds this many gathering radii is answered query by query.
const SPREAD: f64 = 8.0;

/// Growth of the gathering radius over the previous packet's largest answer distance.
const RADIUS_FACTOR: f64 = 1.25;

/// Batches smaller than this are answered in the order given.
const REORDER_MIN: usize = 4 * HINT_CHUNK;

/// Consecutive query pairs sampled to judge a batch's order.
const ORDER_SAMPLES: usize = 255;

/// A batch whose median step between consecutive queries exceeds this many leaf sizes is answered
/// in Hilbert order.
const ORDER_SPREAD: f64 = 4.0;

/// The leaves gathered for a packet: boxes axis by axis, and leaf references (fixed capacity,
/// [`MAX_LEAVES`], so a gathering allocates nothing).
struct Gathered {
    lo: [Lanes; 3],
    hi: [Lanes; 3],
    leaves: [(u32, u32); MAX_LEAVES],
    len: usize,
    /// Per-query scratch: the gathered leaves within a query's bound.
    index: [u32; MAX_LEAVES + 8],
    /// The nodes the gathering visits, level after level.
    nodes: Vec<Child>,
}

/// One coordinate of every gathered box, eight lanes at a time.
type Lanes = [f64x8; MAX_LEAVES / 8];

impl Default for Gathered {
    fn default() -> Self {
        Self {
            lo: [[f64x8::ZERO; MAX_LEAVES / 8]; 3],
            hi: [[f64x8::ZERO; MAX_LEAVES / 8]; 3],
            leaves: [(0, 0); MAX_LEAVES],
            len: 0,
            index: [0; MAX_LEAVES + 8],
            nodes: Vec::new(),
        }
    }
}

impl Gathered {
    fn clear(&mut self) {
        self.len = 0;
        self.nodes.clear();
    }

    /// Appends a leaf; `false` when [`MAX_LEAVES`] are gathered already.
    fn push(&mut self, b: &Aabb, first: usize, count: usize) -> bool {
        let j = self.len;
        if j == MAX_LEAVES {
            return false;
        }
        for axis in 0..3 {
            self.lo[axis][j / 8].as_mut_array()[j % 8] = b.min[axis];
            self.hi[axis][j / 8].as_mut_array()[j % 8] = b.max[axis];
        }
        self.leaves[j] = (index(first), index(count));
        self.len = j + 1;
        true
    }

    /// Lists the gathered leaves whose boxes are within `bound` (squared) of `p`: their indices
    /// go to the front of `self.index`; returns how many.
    fn candidates(&mut self, p: &Vec3, bound: f64) -> usize {
        let n = self.len;
        let x: [f64x8; 3] = std::array::from_fn(|axis| f64x8::splat(p[axis]));
        let mut kept = 0;
        for block in 0..n.div_ceil(8) {
            let mut d = f64x8::ZERO;
            for ((lo, hi), x) in self.lo.iter().zip(&self.hi).zip(&x) {
                let below = lo[block] - *x;
                let above = *x - hi[block];
                let g = below.fast_max(above).fast_max(f64x8::ZERO);
                d += g * g;
            }
            // Lanes past the end hold stale boxes: masked off.
            let live = (1u32 << (n - 8 * block).min(8)) - 1;
            let mask = d.simd_le(f64x8::splat(bound)).to_bitmask() & live;
            let base = index(8 * block);
            compact(mask, base, &mut self.index[kept..kept + 8]);
            kept += mask.count_ones() as usize;
        }
        kept
    }
}

/// Writes `base + k` for the lanes `k` set in `mask` (eight bits) to the front of `out`; the
/// rest of `out` is scratch.
#[inline(always)]
fn compact(mask: u32, base: u32, out: &mut [u32]) {
    #[cfg(all(
        target_arch = "x86_64",
        target_feature = "avx512f",
        target_feature = "avx512vl"
    ))]
    {
        use std::arch::x86_64::{
            _mm256_add_epi32, _mm256_maskz_compress_epi32, _mm256_set1_epi32, _mm256_setr_epi32,
            _mm256_storeu_si256,
        };
        #[allow(clippy::cast_possible_truncation, clippy::cast_possible_wrap)]
        let (k, b) = (mask as u8, base as i32);
        let out: &mut [u32; 8] = (&mut out[..8]).try_into().expect("eight entries");
        // SAFETY: the target features these intrinsics need are enabled for the whole build (the
        // `cfg` above); `out` holds eight u32 (32 bytes) and the store is unaligned.
        unsafe {
            let lanes = _mm256_add_epi32(
                _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
                _mm256_set1_epi32(b),
            );
            let kept = _mm256_maskz_compress_epi32(k, lanes);
            _mm256_storeu_si256(out.as_mut_ptr().cast(), kept);
        }
    }
    #[cfg(not(all(
        target_arch = "x86_64",
        target_feature = "avx512f",
        target_feature = "avx512vl"
    )))]
    compact_portably(mask, base, out);
}

/// [`compact`] without AVX-512: every lane written, the position advanced only past a kept one.
#[cfg_attr(
    all(
        target_arch = "x86_64",
        target_feature = "avx512f",
        target_feature = "avx512vl"
    ),
    allow(dead_code)
)]
#[inline(always)]
fn compact_portably(mask: u32, base: u32, out: &mut [u32]) {
    let mut at = 0;
    for k in 0..8 {
        out[at] = base + k;
        at += usize::from(mask & (1 << k) != 0);
    }
}

thread_local! {
    static GATHERED: RefCell<Box<Gathered>> = RefCell::new(Box::default());
}

/// The state carried from packet to packet within a chunk.
#[derive(Debug, Clone, Copy)]
struct Chain {
    /// The previous answer: the next query's hint.
    hint: Option<u32>,
    /// The gathering radius squared for the next packet (`+∞` until a packet has an answer).
    radius2: f64,
}

impl Chain {
    const START: Chain = Chain {
        hint: None,
        radius2: f64::INFINITY,
    };
}

impl Bvh {
    /// Answers a chunk of queries, packet by packet, into `out`.
    pub(crate) fn closest_chunk(
        &self,
        surface: &Surface,
        queries: &[Query],
        out: &mut [Option<Hit>],
        max2: f64,
    ) {
        let mut chain = Chain::START;
        // The chunk's first query alone, by a traversal: its answer, or a leaf size if that is
        // longer, gives the first packet its gathering radius.
        let Some(((head, queries), (first, out))) = queries
            .split_first_chunk::<1>()
            .zip(out.split_first_chunk_mut::<1>())
        else {
            return;
        };
        self.answer_each(surface, head, first, max2, &mut chain.hint);
        if let Some(h) = &first[0] {
            chain.radius2 = (RADIUS_FACTOR * h.closest.distance.max(self.leaf_size)).powi(2);
        }
        for (qs, hits) in queries.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
            let radius2 = chain.radius2.min(max2);
            GATHERED.with_borrow_mut(|g| {
                if radius2 < f64::INFINITY && self.gather(qs, radius2, g) {
                    self.answer_packet(surface, qs, hits, (max2, radius2), &mut chain.hint, g);
                } else {
                    self.answer_each(surface, qs, hits, max2, &mut chain.hint);
                }
            });
            let largest = hits.iter().flatten().map(|h| h.closest.distance);
            chain.radius2 = largest
                .reduce(f64::max)
                .map_or(f64::INFINITY, |d| (RADIUS_FACTOR * d).powi(2));
        }
    }

    /// Answers `queries` one traversal each, each hinted with the previous answer.
    fn answer_each(
        &self,
        surface: &Surface,
        queries: &[Query],
        hits: &mut [Option<Hit>],
        max2: f64,
        hint: &mut Option<u32>,
    ) {
        for (q, hit) in queries.iter().zip(hits.iter_mut()) {
            let seed = hint.and_then(|f| self.candidate(surface, q, f));
            *hit = self
                .closest_candidate(surface, q, max2, seed)
                .map(|c| self.finish(c, q));
            *hint = hit.map(|h| h.facet).or(*hint);
        }
    }

    /// Gathers into `g` the leaves within `radius2` (squared) of the box of `queries`; `false`
    /// when there are more than [`MAX_LEAVES`].
    fn gather(&self, queries: &[Query], radius2: f64, g: &mut Gathered) -> bool {
        g.clear();
        // The box of the finite queries only (the others have no answer): a NaN coordinate would
        // not merely be left out of a running minimum but restart it, and the box would miss the
        // queries before it.
        let b = queries
            .iter()
            .filter(|q| q.is_finite())
            .fold(Aabb::EMPTY, |b, q| b.union_point(&q.point));
        // Queries spread over more than a few radii (random order) would gather too much. A box
        // that is not finite (no finite query) gathers nothing reliably: the certificate needs
        // every leaf left out to be far, not merely incomparable.
        let spread2 = (b.max - b.min).norm_squared();
        if !spread2.is_finite() || spread2 > SPREAD * SPREAD * radius2 {
            return false;
        }
        let bound = radius2 * TIE_MARGIN;
        // A tree that is a single leaf has no box to gather.
        if as_leaf(self.root).is_some() {
            return false;
        }
        // Breadth first (a queue, level after level): the nodes waiting in it do not depend on
        // one another, so their loads from memory overlap, where a depth-first walk waits for
        // each node before it knows the next.
        g.nodes.push(self.root);
        let mut at = 0;
        while let Some(&next) = g.nodes.get(at) {
            at += 1;
            let node = &self.nodes[next as usize];
            let d = node.child_distances_squared_to_box(&b);
            for (k, &c) in node.child.iter().enumerate() {
                if !(d[k] <= bound && d[k] < f64::INFINITY) {
                    continue;
                }
                match as_leaf(c) {
                    Some((first, count)) => {
                        if !g.push(&node.child_box(k), first, count) {
                            return false;
                        }
                    }
                    None => g.nodes.push(c),
                }
            }
        }
        true
    }

    /// Answers the packet `queries` from the gathered leaves `g`, gathered within `radius2` (the
    /// second of `bounds`, the first being the squared search distance); a query whose answer is
    /// not certified falls back to the full traversal.
    fn answer_packet(
        &self,
        surface: &Surface,
        queries: &[Query],
        hits: &mut [Option<Hit>],
        (max2, radius2): (f64, f64),
        hint: &mut Option<u32>,
        g: &mut Gathered,
    ) {
        // The gathered leaf that held the previous answer: measured first, whole, for the bound.
        let mut previous: Option<u32> = None;
        for (q, hit) in queries.iter().zip(hits.iter_mut()) {
            if !q.is_finite() {
                *hit = None;
                continue;
            }
            let mut lanes = LaneBest::new(max2);
            match previous {
                Some(j) => {
                    let (first, count) = g.leaves[j as usize];
                    self.take_leaf(surface, q, (first as usize, count as usize), j, &mut lanes);
                }
                None => {
                    if let Some(c) = hint.and_then(|f| self.candidate(surface, q, f)) {
                        lanes.seed(c.d2, c.facet, c.slot);
                    }
                }
            }
            // Every other gathered leaf within that first bound is measured: nearly all of them
            // would be even with the bound shrinking (4.1 of 4.3 on the 10⁵ torus), and without
            // a test between them their measurements overlap.
            let n = g.candidates(&q.point, lanes.bound() * TIE_MARGIN);
            for &j in &g.index[..n] {
                if Some(j) != previous {
                    let (first, count) = g.leaves[j as usize];
                    self.take_leaf(surface, q, (first as usize, count as usize), j, &mut lanes);
                }
            }
            let found = lanes.best();
            previous = found.and_then(|w| w.leaf);
            *hit = match found {
                Some(w) if w.d2 <= radius2 => Some(Hit {
                    facet: w.facet,
                    closest: w.closest(&self.slot_corners(w.slot), &q.point),
                }),
                // Not certified by the gathering: the full traversal, from what was found.
                _ => {
                    let best = found.map(|w| Candidate {
                        d2: w.d2,
                        facet: w.facet,
                        slot: w.slot,
                    });
                    self.closest_candidate(surface, q, max2, best)
                        .map(|c| self.finish(c, q))
                }
            };
            *hint = hit.map(|h| h.facet).or(*hint);
        }
    }

    /// `false` for a batch worth answering in Hilbert order: large, and with a median distance
    /// between consecutive queries (on evenly spaced samples) above [`ORDER_SPREAD`] leaf sizes.
    pub(crate) fn coherent(&self, queries: &[Query]) -> bool {
        let n = queries.len();
        if n < REORDER_MIN || self.leaf_size.is_nan() || self.leaf_size <= 0.0 {
            return true;
        }
        let mut steps: Vec<f64> = (0..ORDER_SAMPLES)
            .map(|s| {
                let i = s * (n - 1) / ORDER_SAMPLES;
                (queries[i + 1].point - queries[i].point).norm()
            })
            .collect();
        steps.sort_by(f64::total_cmp);
        steps[ORDER_SAMPLES / 2] <= ORDER_SPREAD * self.leaf_size
    }

    /// Answers `queries` in the Hilbert order of their points (`search::hilbert`, codes on the
    /// tree's box, ties by
    /// index, so the order is deterministic) and writes each answer to its query's place in `out`.
    /// Every answer is the one the given order would give; only the packets differ.
    pub(crate) fn closest_reordered(
        &self,
        surface: &Surface,
        queries: &[Query],
        max2: f64,
        out: &mut [Option<Hit>],
    ) {
        let bounds = self.bounds().unwrap_or(Aabb::EMPTY);
        let keys = sorted_keys(queries.len(), &bounds, |i| Some(queries[i].point));
        let sorted: Vec<Query> = keys.par_iter().map(|&(_, i)| queries[i as usize]).collect();
        let mut answers = vec![None; queries.len()];
        answers
            .par_chunks_mut(HINT_CHUNK)
            .zip(sorted.par_chunks(HINT_CHUNK))
            .for_each(|(hits, qs)| self.closest_chunk(surface, qs, hits, max2));
        let mut rank = vec![0u32; queries.len()];
        for (k, &(_, i)) in keys.iter().enumerate() {
            rank[i as usize] = index(k);
        }
        out.par_iter_mut()
            .zip(rank.par_iter())
            .with_min_len(4096)
            .for_each(|(hit, &k)| *hit = answers[k as usize]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::scenes::{near_surface, shuffle, torus};

    #[test]
    fn compaction_keeps_the_masked_lanes_in_order() {
        for mask in 0..256u32 {
            let kept: Vec<u32> = (0..8)
                .filter(|k| mask & (1 << k) != 0)
                .map(|k| 40 + k)
                .collect();
            for f in [compact, compact_portably] {
                let mut out = [u32::MAX; 8];
                f(mask, 40, &mut out);
                assert_eq!(out[..kept.len()], kept[..], "mask {mask:08b}");
            }
        }
    }

    #[test]
    fn surface_order_is_coherent_and_a_shuffle_is_not() {
        let (nodes, facets) = torus(80, 40, 2.0, 0.6);
        let surface = Surface::new(facets.clone(), nodes.len()).unwrap();
        let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
        let mut queries: Vec<Query> = near_surface(&nodes, &facets, 0.1, 3)
            .into_iter()
            .map(Query::point)
            .collect();
        assert!(bvh.coherent(&queries));
        // Too small a batch is never reordered.
        assert!(bvh.coherent(&queries[..REORDER_MIN - 1]));
        shuffle(&mut queries, 8);
        assert!(!bvh.coherent(&queries));
        assert!(bvh.coherent(&queries[..REORDER_MIN - 1]));
    }
}
