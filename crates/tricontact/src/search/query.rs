//! Queries: the closest facet to a point, and every facet within a distance.
//!
//! # Closest facet
//! Depth-first traversal with an explicit stack, nearer child first. A subtree is pruned when the
//! squared distance to its box exceeds the best squared distance so far (with a relative margin of
//! 1e-12, so that exact ties are never pruned). Every candidate facet is measured with the kernel's
//! [`closest_point_on_triangle`], which also says where the closest point lies (face, edge,
//! vertex).
//!
//! # Ties and determinism
//! A hit is better when its distance is smaller, or equal with a smaller facet index. The best hit
//! under this total order does not depend on the traversal order, so the answer equals the brute
//! force one exactly and is the same for any number of threads. A node at a vertex shared by six
//! facets gets the lowest-numbered of them.
//!
//! # Self-contact
//! A query may name its own node (`exclude`): facets that contain it are skipped, so a node never
//! pairs with a facet it belongs to.

use rayon::prelude::*;

use crate::closest::{ClosestPoint, closest_point_on_triangle};
use crate::facet::Facet;
use crate::linalg::Vec3;
use crate::search::bvh::{Bvh, index};
use crate::search::surface::Surface;

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

impl Hit {
    /// `true` when `self` is better than `other`: nearer, or as near with a smaller index.
    #[must_use]
    #[inline]
    pub fn better_than(&self, other: &Hit) -> bool {
        self.closest.distance < other.closest.distance
            || (self.closest.distance == other.closest.distance && self.facet < other.facet)
    }
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
}

/// Measures one `facet` against the query (no tree, no degeneracy check); `None` when the query
/// excludes it.
#[must_use]
#[inline]
pub fn measure(surface: &Surface, positions: &[Vec3], facet: u32, q: &Query) -> Option<Hit> {
    if let Some(n) = q.exclude
        && surface.facets()[facet as usize].contains(&n)
    {
        return None;
    }
    let [a, b, c] = surface.corners(facet, positions);
    Some(Hit {
        facet,
        closest: closest_point_on_triangle(&a, &b, &c, &q.point),
    })
}

/// Keeps the better of `best` and `hit`, among hits within `max_distance`.
#[inline]
pub(crate) fn keep(best: &mut Option<Hit>, hit: Hit, max_distance: f64) {
    if hit.closest.distance <= max_distance && best.is_none_or(|b| hit.better_than(&b)) {
        *best = Some(hit);
    }
}

impl Bvh {
    /// The closest facet to `q` within `max_distance` (`f64::INFINITY` for no limit), at the
    /// positions the tree was last built or updated with.
    #[must_use]
    pub fn closest(
        &self,
        surface: &Surface,
        positions: &[Vec3],
        q: &Query,
        max_distance: f64,
    ) -> Option<Hit> {
        self.closest_seeded(surface, positions, q, max_distance, None)
    }

    /// [`Bvh::closest`] starting from a known hit (which tightens pruning from the first node).
    pub(crate) fn closest_seeded(
        &self,
        surface: &Surface,
        positions: &[Vec3],
        q: &Query,
        max_distance: f64,
        seed: Option<Hit>,
    ) -> Option<Hit> {
        if self.order.is_empty() {
            return None;
        }
        let mut best = seed.filter(|h| h.closest.distance <= max_distance);
        let bound2 = |best: &Option<Hit>| {
            let d = best.map_or(max_distance, |h| h.closest.distance);
            d * d * TIE_MARGIN
        };
        let mut stack = [0u32; 64];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if node.aabb.distance_squared(&q.point) > bound2(&best) {
                continue;
            }
            if node.count > 0 {
                let start = node.first as usize;
                for &f in &self.order[start..start + node.count as usize] {
                    if let Some(hit) = measure(surface, positions, f, q) {
                        keep(&mut best, hit, max_distance);
                    }
                }
                continue;
            }
            let (left, right) = (stack[top] + 1, node.first);
            let dl = self.nodes[left as usize].aabb.distance_squared(&q.point);
            let dr = self.nodes[right as usize].aabb.distance_squared(&q.point);
            let (near, far, d_far) = if dl <= dr {
                (left, right, dr)
            } else {
                (right, left, dl)
            };
            let bound = bound2(&best);
            if d_far <= bound {
                stack[top] = far;
                top += 1;
            }
            if dl.min(dr) <= bound {
                stack[top] = near;
                top += 1;
            }
        }
        best
    }

    /// Every facet within `radius` of `q`, sorted by distance then facet index.
    #[must_use]
    pub fn within(
        &self,
        surface: &Surface,
        positions: &[Vec3],
        q: &Query,
        radius: f64,
    ) -> Vec<Hit> {
        let mut hits = Vec::new();
        if self.order.is_empty() {
            return hits;
        }
        let bound = radius * radius * TIE_MARGIN;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let node = self.nodes[i as usize];
            if node.aabb.distance_squared(&q.point) > bound {
                continue;
            }
            if node.count > 0 {
                let start = node.first as usize;
                for &f in &self.order[start..start + node.count as usize] {
                    if let Some(hit) = measure(surface, positions, f, q)
                        && hit.closest.distance <= radius
                    {
                        hits.push(hit);
                    }
                }
            } else {
                stack.push(node.first);
                stack.push(i + 1);
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
        positions: &[Vec3],
        queries: &[Query],
        max_distance: f64,
    ) -> Vec<Option<Hit>> {
        queries
            .par_iter()
            .with_min_len(256)
            .map(|q| self.closest(surface, positions, q, max_distance))
            .collect()
    }
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
/// tree.
#[must_use]
pub fn brute_force_closest(
    surface: &Surface,
    positions: &[Vec3],
    q: &Query,
    max_distance: f64,
) -> Option<Hit> {
    let mut best = None;
    for f in 0..surface.len() {
        let [a, b, c] = surface.corners(index(f), positions);
        if Facet::new(a, b, c).is_err() {
            continue;
        }
        if let Some(hit) = measure(surface, positions, index(f), q) {
            keep(&mut best, hit, max_distance);
        }
    }
    best
}
