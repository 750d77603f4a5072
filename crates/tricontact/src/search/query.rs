//! Queries: the closest facet to a point, and every facet within a distance.
//!
//! # Closest facet
//! Depth-first traversal with an explicit stack, nearer child first. A subtree is pruned when the
//! squared distance to its box exceeds the best squared distance so far (with a relative margin of
//! 1e-12, so that exact ties are never pruned). Candidates are compared by the branch-free
//! [`distance_squared_to_triangle`] on the corner copies the tree keeps in leaf order; only the
//! winner is measured with the kernel's [`closest_point_on_triangle`], which says where its closest
//! point lies (face, edge, vertex) and gives the reported distance.
//!
//! # Ties and determinism
//! A candidate is better when its squared distance is smaller, or equal with a smaller facet index.
//! The best candidate under this total order does not depend on the traversal order, so the answer
//! equals the brute-force one exactly and is the same for any number of threads. A node at a
//! vertex shared by six facets gets the lowest-numbered of them.
//!
//! # Self-contact
//! A query may name its own node (`exclude`): facets that contain it are skipped, so a node never
//! pairs with a facet it belongs to.

use rayon::prelude::*;

use crate::closest::{ClosestPoint, closest_point_on_triangle, distance_squared_to_triangle};
use crate::facet::Facet;
use crate::linalg::Vec3;
use crate::search::bvh::{Bvh, index};
use crate::search::node::as_leaf;
use crate::search::surface::Surface;

thread_local! {
    /// The traversal stack of [`Bvh::closest`], kept per thread so a query allocates nothing.
    static STACK: std::cell::RefCell<Vec<(u32, f64)>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Relative margin on squared distances below which a box is never pruned.
const TIE_MARGIN: f64 = 1.0 + 1e-12;

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

    /// `true` when the query skips `facet` (it contains the query's own node).
    #[must_use]
    #[inline]
    pub fn excludes(&self, surface: &Surface, facet: u32) -> bool {
        self.exclude
            .is_some_and(|n| surface.facets()[facet as usize].contains(&n))
    }
}

/// The best candidate so far: squared distance, facet, and the corners to finish it with.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Candidate {
    pub(crate) d2: f64,
    pub(crate) facet: u32,
    pub(crate) corners: [Vec3; 3],
}

impl Candidate {
    /// Offers a facet: kept when it is within `max2` and better than the current best.
    #[inline]
    pub(crate) fn offer(
        best: &mut Option<Candidate>,
        d2: f64,
        facet: u32,
        corners: &[Vec3; 3],
        max2: f64,
    ) {
        let better = match best {
            None => d2 <= max2,
            Some(b) => d2 < b.d2 || (d2 == b.d2 && facet < b.facet),
        };
        if better {
            *best = Some(Candidate {
                d2,
                facet,
                corners: *corners,
            });
        }
    }

    /// The bound for pruning: the best squared distance, or `max2` while there is none.
    #[inline]
    pub(crate) fn bound(best: &Option<Candidate>, max2: f64) -> f64 {
        best.map_or(max2, |b| b.d2) * TIE_MARGIN
    }

    /// The hit, measured with the kernel.
    #[inline]
    pub(crate) fn finish(&self, q: &Query) -> Hit {
        let [a, b, c] = &self.corners;
        Hit {
            facet: self.facet,
            closest: closest_point_on_triangle(a, b, c, &q.point),
        }
    }
}

/// Measures one `facet` against the query with the kernel (no tree, no degeneracy check); `None`
/// when the query excludes it.
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
    #[must_use]
    pub fn closest(&self, surface: &Surface, q: &Query, max_distance: f64) -> Option<Hit> {
        self.closest_candidate(surface, q, max_distance * max_distance, None)
            .map(|c| c.finish(q))
    }

    /// The best candidate, starting from `seed` (which tightens pruning from the first node).
    pub(crate) fn closest_candidate(
        &self,
        surface: &Surface,
        q: &Query,
        max2: f64,
        seed: Option<Candidate>,
    ) -> Option<Candidate> {
        let p = &q.point;
        let mut best = seed.filter(|c| c.d2 <= max2);
        // (child reference, squared distance to its box), in a per-thread buffer reused from query
        // to query.
        STACK.with_borrow_mut(|stack| {
            stack.clear();
            stack.push((self.root, 0.0f64));
            while let Some((child, d2_box)) = stack.pop() {
                if d2_box > Candidate::bound(&best, max2) {
                    continue;
                }
                if let Some((first, count)) = as_leaf(child) {
                    for s in first..first + count {
                        let facet = self.order[s];
                        if q.excludes(surface, facet) {
                            continue;
                        }
                        let c = &self.corners[s];
                        let d2 = distance_squared_to_triangle(&c[0], &c[1], &c[2], p);
                        Candidate::offer(&mut best, d2, facet, c, max2);
                    }
                    continue;
                }
                let node = &self.nodes[child as usize];
                let d = node.child_distances_squared(p);
                let bound = Candidate::bound(&best, max2);
                // Push the children within the bound with the nearest last, so it is popped next.
                // Empty slots are infinitely far; an unbounded query must still skip them.
                let nearest = nearest_slot(&d);
                for k in (0..4)
                    .filter(|&k| k != nearest)
                    .chain(std::iter::once(nearest))
                {
                    if d[k] <= bound && d[k] < f64::INFINITY {
                        stack.push((node.child[k], d[k]));
                    }
                }
            }
        });
        best
    }

    /// Every facet within `radius` of `q`, sorted by distance then facet index.
    #[must_use]
    pub fn within(&self, surface: &Surface, q: &Query, radius: f64) -> Vec<Hit> {
        let mut hits = Vec::new();
        let r2 = radius * radius;
        let bound = r2 * TIE_MARGIN;
        let mut stack = vec![self.root];
        while let Some(child) = stack.pop() {
            if let Some((first, count)) = as_leaf(child) {
                for s in first..first + count {
                    let facet = self.order[s];
                    let c = &self.corners[s];
                    if !q.excludes(surface, facet)
                        && distance_squared_to_triangle(&c[0], &c[1], &c[2], &q.point) <= r2
                    {
                        hits.push(Hit {
                            facet,
                            closest: closest_point_on_triangle(&c[0], &c[1], &c[2], &q.point),
                        });
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
    #[must_use]
    pub fn closest_all(
        &self,
        surface: &Surface,
        queries: &[Query],
        max_distance: f64,
    ) -> Vec<Option<Hit>> {
        queries
            .par_iter()
            .with_min_len(256)
            .map(|q| self.closest(surface, q, max_distance))
            .collect()
    }
}

/// The slot of the smallest of four distances (the first on ties).
#[inline]
fn nearest_slot(d: &[f64; 4]) -> usize {
    let a = if d[1] < d[0] { 1 } else { 0 };
    let b = if d[3] < d[2] { 3 } else { 2 };
    if d[b] < d[a] { b } else { a }
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

/// The closest facet by checking every facet: the reference the tree is tested against, and the
/// O(nodes × facets) search the benchmark compares with. Degenerate facets are skipped, as in the
/// tree, and candidates are compared exactly as the tree compares them.
#[must_use]
pub fn brute_force_closest(
    surface: &Surface,
    positions: &[Vec3],
    q: &Query,
    max_distance: f64,
) -> Option<Hit> {
    let max2 = max_distance * max_distance;
    let mut best = None;
    for f in 0..surface.len() {
        let facet = index(f);
        let c = surface.corners(facet, positions);
        if q.excludes(surface, facet) || Facet::new(c[0], c[1], c[2]).is_err() {
            continue;
        }
        let d2 = distance_squared_to_triangle(&c[0], &c[1], &c[2], &q.point);
        Candidate::offer(&mut best, d2, facet, &c, max2);
    }
    best.map(|c| c.finish(q))
}
