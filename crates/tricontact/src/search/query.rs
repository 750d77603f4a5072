//! Queries: the closest facet to a point, and every facet within a distance.
//!
//! # Closest facet
//! Depth-first traversal with an explicit stack, nearer child first: the four children of a node
//! are sorted by the distance to their boxes (a sorting network) and pushed without branches, the
//! top of the stack advancing only for children within the bound. A subtree is pruned when the
//! squared distance to its box exceeds the best squared distance so far (with a relative margin of
//! 1e-12, so that exact ties are never pruned). The facets of a leaf are measured together
//! (`lanes`: the branch-free [`distance_squared_to_triangle`], bit for bit, a group of a leaf's
//! facets at a time) on the tree's rows (each group's corners coordinate by coordinate); only the
//! winner is measured with the kernel's [`closest_point_on_triangle`], which says where its
//! closest point lies (face, edge, vertex) and gives the reported distance. (Packets of coherent
//! queries, `search::packet`, take the winner's closest point from the same lane arithmetic.)
//!
//! # Hints
//! A query may start from a hint facet ([`Bvh::closest_with_hint`]): its exact squared distance is
//! the first bound, so boxes farther than it are pruned from the root down. Since the bound is
//! inclusive and ties are decided by the order below, a hint never changes the answer.
//! [`Bvh::closest_all`] cuts the queries into chunks of [`HINT_CHUNK`], answered in parallel;
//! within a chunk, packets of consecutive queries share one traversal ([`crate::search::packet`])
//! and each query is hinted with the previous answer.
//!
//! # Ties and determinism
//! A candidate is better when its squared distance is smaller, or equal with a smaller facet index.
//! The best candidate under this total order does not depend on the traversal order, so the answer
//! equals the brute-force one exactly and is the same for any number of threads. A node at a
//! vertex shared by six facets gets the lowest-numbered of them.
//!
//! # Points that are not finite
//! A query at NaN or infinity has no answer (`None`) on every path (single, hinted, in a batch,
//! brute force, incremental): its distance to every facet is infinite or undefined.
//!
//! # Self-contact
//! A query may name its own node (`exclude`): facets that contain it are skipped, so a node never
//! pairs with a facet it belongs to.

use rayon::prelude::*;

use crate::closest::{ClosestPoint, closest_point_on_triangle, distance_squared_to_triangle};
use crate::facet::Facet;
use crate::linalg::Vec3;
use crate::search::bvh::{Bvh, NO_SLOT, TREE, index};
use crate::search::lanes;
use crate::search::node::{Child, EMPTY, as_leaf};
use crate::search::surface::{Surface, SurfaceError};

thread_local! {
    /// The traversal stack of [`Bvh::closest`], kept per thread so a query allocates nothing.
    static STACK: std::cell::RefCell<Vec<(u32, f64)>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Queries per sequential chunk of [`Bvh::closest_all`] (packets and hints run within a chunk).
/// A chunk's first query is answered by a traversal (it has no gathering radius yet): 1024 queries
/// (256 was measured 3 % slower when a chunk's whole first packet was answered that way) still
/// make about a hundred chunks of 10⁵ queries for the threads.
pub const HINT_CHUNK: usize = 1024;

/// Relative margin on squared distances below which a box is never pruned.
pub(crate) const TIE_MARGIN: f64 = 1.0 + 1e-12;

/// A facet found by a query, with the closest point on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// The facet index in the surface.
    pub facet: u32,
    /// The closest point of that facet, its feature and distance.
    pub closest: ClosestPoint,
}

/// One point to look up: its position, and the node it is (for self-contact), if any.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Query {
    /// The point.
    pub point: Vec3,
    /// Facets containing this node are skipped.
    pub exclude: Option<u32>,
}

impl Query {
    /// A query for a point that is not a node of the searched surface.
    #[must_use]
    pub fn point(point: Vec3) -> Self {
        Self {
            point,
            exclude: None,
        }
    }

    /// `true` when the query point is finite (a query at NaN or infinity has no answer).
    #[must_use]
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.point.iter().all(|c| c.is_finite())
    }

    /// `true` when the query skips `facet` (it contains the query's own node).
    ///
    /// # Panics
    /// If the query excludes a node and `facet` is not below [`Surface::len`].
    #[must_use]
    #[inline]
    pub fn excludes(&self, surface: &Surface, facet: u32) -> bool {
        self.exclude
            .is_some_and(|n| surface.facets()[facet as usize].contains(&n))
    }
}

/// The best candidate so far: squared distance, facet, and where its corners are (the tree's slot,
/// or the facet itself for the brute-force search).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Candidate {
    pub(crate) d2: f64,
    pub(crate) facet: u32,
    pub(crate) slot: u32,
}

impl Candidate {
    /// Offers a facet: kept when it is within `max2` and better than the current best.
    #[inline]
    pub(crate) fn offer(best: &mut Option<Candidate>, d2: f64, facet: u32, slot: u32, max2: f64) {
        let better = match best {
            None => d2 <= max2,
            Some(b) => d2 < b.d2 || (d2 == b.d2 && facet < b.facet),
        };
        if better {
            *best = Some(Candidate { d2, facet, slot });
        }
    }

    /// The bound for pruning: the best squared distance, or `max2` while there is none.
    #[inline]
    pub(crate) fn bound(best: &Option<Candidate>, max2: f64) -> f64 {
        best.map_or(max2, |b| b.d2) * TIE_MARGIN
    }

    /// The hit, measured with the kernel on the candidate's `corners`.
    #[inline]
    pub(crate) fn finish(&self, [a, b, c]: &[Vec3; 3], q: &Query) -> Hit {
        Hit {
            facet: self.facet,
            closest: closest_point_on_triangle(a, b, c, &q.point),
        }
    }
}

/// Measures one `facet` against the query with the kernel (no tree, no degeneracy check); `None`
/// when the query excludes it.
///
/// # Panics
/// As [`Surface::corners`].
#[must_use]
pub fn measure(surface: &Surface, positions: &[Vec3], facet: u32, q: &Query) -> Option<Hit> {
    if q.excludes(surface, facet) {
        return None;
    }
    let [a, b, c] = surface.corners(facet, positions);
    Some(Hit {
        facet,
        closest: closest_point_on_triangle(&a, &b, &c, &q.point),
    })
}

impl Bvh {
    /// The closest facet to `q` within `max_distance` (`f64::INFINITY` for no limit), at the
    /// positions the tree was last built or updated with.
    ///
    /// # Panics
    /// If `surface` is not the one the tree was built on (its facets are read by number).
    #[must_use]
    pub fn closest(&self, surface: &Surface, q: &Query, max_distance: f64) -> Option<Hit> {
        self.surface.expect(surface, TREE);
        self.closest_candidate(surface, q, squared_limit(max_distance), None)
            .map(|c| self.finish(c, q))
    }

    /// [`Bvh::closest`] seeded with `hint`, a facet likely to be close to `q` (the answer of a
    /// neighbouring query, or of the same node last time). The exact squared distance to the hint
    /// bounds the search from the first node, so fewer boxes pass; the answer is the same as
    /// without the hint (the bound is inclusive and ties still go to the lower index). A hint that
    /// is out of range, degenerate or excluded is ignored.
    ///
    /// # Panics
    /// As [`Bvh::closest`].
    #[must_use]
    pub fn closest_with_hint(
        &self,
        surface: &Surface,
        q: &Query,
        hint: Option<u32>,
        max_distance: f64,
    ) -> Option<Hit> {
        self.surface.expect(surface, TREE);
        let seed = hint.and_then(|f| self.candidate(surface, q, f));
        self.closest_candidate(surface, q, squared_limit(max_distance), seed)
            .map(|c| self.finish(c, q))
    }

    /// `facet` as a candidate for `q`: `None` when it is out of range, degenerate (not in the tree)
    /// or excluded by the query.
    #[inline]
    pub(crate) fn candidate(&self, surface: &Surface, q: &Query, facet: u32) -> Option<Candidate> {
        let slot = *self.slot.get(facet as usize)?;
        if slot == NO_SLOT || q.excludes(surface, facet) || !q.is_finite() {
            return None;
        }
        let c = self.slot_corners(slot);
        Some(Candidate {
            d2: distance_squared_to_triangle(&c[0], &c[1], &c[2], &q.point),
            facet,
            slot,
        })
    }

    /// The best candidate, starting from `seed` (which tightens pruning from the first node).
    pub(crate) fn closest_candidate(
        &self,
        surface: &Surface,
        q: &Query,
        max2: f64,
        seed: Option<Candidate>,
    ) -> Option<Candidate> {
        if !q.is_finite() {
            return None;
        }
        let p = &q.point;
        let mut best = seed.filter(|c| c.d2 <= max2);
        // (child reference, squared distance to its box), in a per-thread buffer reused from query
        // to query, long enough for the deepest path (each level leaves at most three siblings).
        STACK.with_borrow_mut(|stack| {
            if stack.len() < self.stack_size {
                stack.resize(self.stack_size, (EMPTY, 0.0));
            }
            stack[0] = (self.root, 0.0);
            let mut top = 1;
            while top > 0 {
                top -= 1;
                let (child, d2_box) = stack[top];
                let bound = Candidate::bound(&best, max2);
                if d2_box > bound {
                    continue;
                }
                if let Some((first, count)) = as_leaf(child) {
                    if count > 0 {
                        self.offer_leaf(surface, q, first, count, max2, &mut best);
                    }
                    continue;
                }
                let node = &self.nodes[child as usize];
                // Children within the bound, farthest pushed first so the nearest is popped next;
                // every slot is written and the top only advances for an accepted child, so the
                // push has no branch. Empty slots are infinitely far, and so is a real child whose
                // squared distance overflowed (a query beyond about 10¹⁵⁴): the slot's reference,
                // not its distance, tells them apart.
                for (d, c) in farthest_first(node.child_distances_squared(p), node.child) {
                    stack[top] = (c, d);
                    top += usize::from(d <= bound && c != EMPTY);
                }
            }
        });
        best
    }

    /// The hit of a candidate of this tree, measured with the kernel.
    #[inline]
    pub(crate) fn finish(&self, c: Candidate, q: &Query) -> Hit {
        c.finish(&self.slot_corners(c.slot), q)
    }

    /// Offers the facets of the leaf `first..first + count` (evaluated together, see
    /// [`lanes`]) to `best`.
    #[inline]
    pub(crate) fn offer_leaf(
        &self,
        surface: &Surface,
        q: &Query,
        first: usize,
        count: usize,
        max2: f64,
        best: &mut Option<Candidate>,
    ) {
        for (first, count) in lanes::groups(first, count) {
            let d2 = lanes::measure_leaf(self.leaf_rows(first), count, &q.point).d2;
            // Only a facet at most as far as the best so far can win (a tie is decided by the
            // index): the others are passed over without a branch each or a look-up of their index.
            let limit = best.map_or(max2, |b| b.d2);
            let mut near = d2.simd_le(lanes::V::splat(limit)).to_bitmask() & ((1 << count) - 1);
            let d2 = d2.as_array();
            while near != 0 {
                let k = near.trailing_zeros() as usize;
                near &= near - 1;
                let facet = self.order[first + k];
                if !q.excludes(surface, facet) {
                    Candidate::offer(best, d2[k], facet, index(first + k), max2);
                }
            }
        }
    }

    /// Offers the facets of the leaf `first..first + count` (evaluated together, see [`lanes`])
    /// to the lane-wise `best`, as the gathered leaf number `leaf`.
    #[inline(always)]
    pub(crate) fn take_leaf(
        &self,
        surface: &Surface,
        q: &Query,
        (first, count): (usize, usize),
        leaf: u32,
        best: &mut lanes::LaneBest,
    ) {
        // The leaf's groups (`lanes::groups`) without an iterator, which cost 4 % of a coherent
        // query here.
        let [head, rest] = lanes::halves(first, count);
        self.take_group(surface, q, head, leaf, best);
        if rest.1 > 0 {
            self.take_group(surface, q, rest, leaf, best);
        }
    }

    /// [`Bvh::take_leaf`] for one group of the leaf (see [`lanes::groups`]).
    #[inline(always)]
    fn take_group(
        &self,
        surface: &Surface,
        q: &Query,
        (first, count): (usize, usize),
        leaf: u32,
        best: &mut lanes::LaneBest,
    ) {
        let rows = self.leaf_rows(first);
        let mut m = lanes::measure_leaf(rows, count, &q.point);
        if q.exclude.is_some() {
            // An excluded facet's lane is NaN, which is never taken.
            let mut d = m.d2.to_array();
            for (k, d) in d.iter_mut().enumerate().take(count) {
                if q.excludes(surface, self.order[first + k]) {
                    *d = f64::NAN;
                }
            }
            m.d2 = lanes::V::new(d);
        }
        best.take_leaf(rows, (first, count), &m, leaf);
    }

    /// Every facet within `radius` of `q`, sorted by distance then facet index.
    ///
    /// # Panics
    /// As [`Bvh::closest`].
    #[must_use]
    pub fn within(&self, surface: &Surface, q: &Query, radius: f64) -> Vec<Hit> {
        self.surface.expect(surface, TREE);
        let mut hits = Vec::new();
        if !q.is_finite() {
            return hits;
        }
        let r2 = squared_limit(radius);
        let bound = r2 * TIE_MARGIN;
        let mut stack = vec![self.root];
        while let Some(child) = stack.pop() {
            if let Some((first, count)) = as_leaf(child) {
                // The leaf's facets measured together (bit for bit the scalar kernel's squared
                // distances), the closest point computed for those within only.
                for (g, n) in lanes::groups(first, count) {
                    let m = lanes::measure_leaf(self.leaf_rows(g), n, &q.point);
                    let d2 = m.d2.to_array();
                    for (k, &d2) in d2.iter().enumerate().take(n) {
                        let facet = self.order[g + k];
                        if d2 <= r2 && !q.excludes(surface, facet) {
                            let c = self.slot_corners(index(g + k));
                            hits.push(Hit {
                                facet,
                                closest: closest_point_on_triangle(&c[0], &c[1], &c[2], &q.point),
                            });
                        }
                    }
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            for (k, d2) in node
                .child_distances_squared(&q.point)
                .into_iter()
                .enumerate()
            {
                if d2 <= bound {
                    stack.push(node.child[k]);
                }
            }
        }
        sort_hits(&mut hits);
        hits
    }

    /// [`Bvh::closest`] for many queries in parallel; the result is independent of the thread
    /// count.
    ///
    /// The queries are cut into chunks of [`HINT_CHUNK`]; within a chunk, packets of consecutive
    /// queries share one traversal ([`crate::search::packet`]) and each query is hinted with the
    /// previous answer ([`Bvh::closest_with_hint`]). This speeds up a spatially coherent batch
    /// (neighbouring nodes one after the other) and leaves every answer unchanged. A large batch
    /// whose consecutive queries are far apart is answered in Z-order and the answers put back in
    /// the given order.
    ///
    /// # Panics
    /// As [`Bvh::closest`] ([`Bvh::closest_all_into`] returns the error instead).
    #[must_use]
    pub fn closest_all(
        &self,
        surface: &Surface,
        queries: &[Query],
        max_distance: f64,
    ) -> Vec<Option<Hit>> {
        self.surface.expect(surface, TREE);
        let mut out = vec![None; queries.len()];
        self.answer_all(surface, queries, max_distance, &mut out);
        out
    }

    /// [`Bvh::closest_all`] written into `out`, one entry per query: a solver that searches at
    /// every iteration reuses one buffer instead of allocating (and faulting in) a new one each
    /// time, which costs as much as the search for millions of queries.
    ///
    /// # Errors
    /// [`SurfaceError::OtherSurface`] if `surface` is not the one the tree was built on;
    /// [`SurfaceError::AnswerCount`] if `out` does not have one entry per query.
    pub fn closest_all_into(
        &self,
        surface: &Surface,
        queries: &[Query],
        max_distance: f64,
        out: &mut [Option<Hit>],
    ) -> Result<(), SurfaceError> {
        self.surface.check(surface, TREE)?;
        check_answers(queries.len(), out.len())?;
        self.answer_all(surface, queries, max_distance, out);
        Ok(())
    }

    /// Answers `queries` into `out` (of the same length), chunk by chunk in parallel.
    fn answer_all(
        &self,
        surface: &Surface,
        queries: &[Query],
        max_distance: f64,
        out: &mut [Option<Hit>],
    ) {
        let max2 = squared_limit(max_distance);
        if !self.coherent(queries) {
            self.closest_reordered(surface, queries, max2, out);
            return;
        }
        out.par_chunks_mut(HINT_CHUNK)
            .zip(queries.par_chunks(HINT_CHUNK))
            .for_each(|(hits, qs)| self.closest_chunk(surface, qs, hits, max2));
    }
}

/// Checks that an answer buffer has one entry per query.
///
/// # Errors
/// [`SurfaceError::AnswerCount`] when it does not.
pub(crate) fn check_answers(queries: usize, answers: usize) -> Result<(), SurfaceError> {
    if answers != queries {
        return Err(SurfaceError::AnswerCount { queries, answers });
    }
    Ok(())
}

/// The four `(distance, child)` pairs sorted by decreasing distance (a five-exchange sorting
/// network, branch-free).
#[inline]
pub(crate) fn farthest_first(d: [f64; 4], child: [Child; 4]) -> [(f64, Child); 4] {
    let mut v = [
        (d[0], child[0]),
        (d[1], child[1]),
        (d[2], child[2]),
        (d[3], child[3]),
    ];
    for (i, j) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
        let (a, b) = (v[i], v[j]);
        let swap = a.0 < b.0;
        v[i] = if swap { b } else { a };
        v[j] = if swap { a } else { b };
    }
    v
}

/// Sorts hits by distance, then facet index.
pub fn sort_hits(hits: &mut [Hit]) {
    hits.sort_by(|a, b| {
        a.closest
            .distance
            .total_cmp(&b.closest.distance)
            .then(a.facet.cmp(&b.facet))
    });
}

/// A search distance as the squared distances are compared with it: `d²`, or `−1` for a negative
/// `d`, so that nothing is within a negative distance (as nothing is within NaN, which stays NaN;
/// squaring would have made `−0.05` search as far as `0.05`).
#[must_use]
#[inline]
pub(crate) fn squared_limit(d: f64) -> f64 {
    if d < 0.0 { -1.0 } else { d * d }
}

/// The closest facet by checking every facet: the reference the tree is tested against, and the
/// O(nodes × facets) search the benchmark compares with. Degenerate facets are skipped, as in the
/// tree, and candidates are compared exactly as the tree compares them.
///
/// # Panics
/// If `positions` holds no position for a node of the surface (the tree's entry points return
/// [`SurfaceError::PositionCount`] instead).
#[must_use]
pub fn brute_force_closest(
    surface: &Surface,
    positions: &[Vec3],
    q: &Query,
    max_distance: f64,
) -> Option<Hit> {
    if !q.is_finite() {
        return None;
    }
    let max2 = squared_limit(max_distance);
    let mut best = None;
    for f in 0..surface.len() {
        let facet = index(f);
        let c = surface.corners(facet, positions);
        if q.excludes(surface, facet) || Facet::new(c[0], c[1], c[2]).is_err() {
            continue;
        }
        let d2 = distance_squared_to_triangle(&c[0], &c[1], &c[2], &q.point);
        Candidate::offer(&mut best, d2, facet, facet, max2);
    }
    best.map(|c| c.finish(&surface.corners(c.facet, positions), q))
}
