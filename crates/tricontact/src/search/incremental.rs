//! Incremental search: start from the facet a node had last time and walk the surface.
//!
//! Within an increment nodes move little, so the facet closest to a node is usually the one it had
//! or a neighbour of it. The walk measures the current facet and every facet sharing a node with it
//! (the adjacency of [`Surface`]) and moves to the best of them — best in the same total order as
//! the tree query: nearer, then lower index — until none is better. It stops at a facet that is
//! best among its neighbours, which on a surface whose other parts are farther than the walk's
//! answer is the closest facet.
//!
//! The walk falls back to the full tree query when there is no previous facet, when the previous
//! facet is degenerate now or excluded, when the walk exceeds [`MAX_STEPS`], or when its answer is
//! beyond the search distance. The tree query is then seeded with the walk's answer, which tightens
//! its pruning. [`IncrementalStats`] counts the fallbacks.

use rayon::prelude::*;

use crate::closest::distance_squared_to_triangle;
use crate::search::bvh::{Bvh, NO_SLOT};
use crate::search::query::{Candidate, Hit, Query};
use crate::search::surface::Surface;

/// Most facets a walk may move through before falling back to the tree.
pub const MAX_STEPS: usize = 16;

/// How many incremental queries fell back to the tree.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct IncrementalStats {
    /// Queries answered.
    pub queries: usize,
    /// Queries that fell back to the full tree query.
    pub fallbacks: usize,
}

impl Bvh {
    /// Offers `facet` to the walk's best candidate, if it is in the tree and not excluded.
    #[inline]
    fn offer_facet(&self, surface: &Surface, q: &Query, facet: u32, best: &mut Option<Candidate>) {
        let slot = self.slot[facet as usize];
        if slot == NO_SLOT || q.excludes(surface, facet) {
            return;
        }
        let c = &self.corners[slot as usize];
        let d2 = distance_squared_to_triangle(&c[0], &c[1], &c[2], &q.point);
        Candidate::offer(best, d2, facet, c, f64::INFINITY);
    }

    /// The walk from `start`: the candidate it ends on, and whether it completed.
    fn walk(
        &self,
        surface: &Surface,
        q: &Query,
        start: u32,
        max2: f64,
    ) -> (Option<Candidate>, bool) {
        if start as usize >= surface.len() {
            return (None, false);
        }
        let mut best = None;
        self.offer_facet(surface, q, start, &mut best);
        let Some(mut current) = best else {
            return (None, false);
        };
        for _ in 0..MAX_STEPS {
            for &f in surface.neighbours(current.facet) {
                self.offer_facet(surface, q, f, &mut best);
            }
            match best {
                Some(b) if b.facet != current.facet => current = b,
                _ => return (Some(current), current.d2 <= max2),
            }
        }
        (best, false)
    }

    /// The closest facet to `q`, walking from `previous` (the facet it had last time); the flag
    /// says whether the query fell back to the tree.
    #[must_use]
    pub fn closest_from(
        &self,
        surface: &Surface,
        q: &Query,
        previous: Option<u32>,
        max_distance: f64,
    ) -> (Option<Hit>, bool) {
        let max2 = max_distance * max_distance;
        let seed = match previous {
            Some(start) => match self.walk(surface, q, start, max2) {
                (Some(c), true) => return (Some(c.finish(q)), false),
                (c, false) => c,
                (None, true) => None,
            },
            None => None,
        };
        let best = self.closest_candidate(surface, q, max2, seed);
        (best.map(|c| c.finish(q)), true)
    }

    /// [`Bvh::closest_from`] for many queries in parallel, with the fallback count.
    #[must_use]
    pub fn closest_all_from(
        &self,
        surface: &Surface,
        queries: &[Query],
        previous: &[Option<u32>],
        max_distance: f64,
    ) -> (Vec<Option<Hit>>, IncrementalStats) {
        let results: Vec<(Option<Hit>, bool)> = queries
            .par_iter()
            .zip(previous.par_iter())
            .with_min_len(256)
            .map(|(q, prev)| self.closest_from(surface, q, *prev, max_distance))
            .collect();
        let stats = IncrementalStats {
            queries: results.len(),
            fallbacks: results.iter().filter(|(_, fell_back)| *fell_back).count(),
        };
        (results.into_iter().map(|(h, _)| h).collect(), stats)
    }
}
