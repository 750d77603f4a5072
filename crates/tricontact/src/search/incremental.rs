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
//! facet is degenerate now, when the walk exceeds [`MAX_STEPS`], or when its answer is beyond the
//! search distance. The tree query is then seeded with the walk's answer, which tightens its pruning.
//! [`IncrementalStats`] counts the fallbacks.

use rayon::prelude::*;

use crate::linalg::Vec3;
use crate::search::bvh::Bvh;
use crate::search::query::{Hit, Query, keep, measure};
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

/// The walk from `start`; `None` asks for the fallback.
fn walk(
    bvh: &Bvh,
    surface: &Surface,
    positions: &[Vec3],
    q: &Query,
    start: u32,
    max_distance: f64,
) -> (Option<Hit>, bool) {
    if start as usize >= surface.len() || bvh.degenerate[start as usize] {
        return (None, false);
    }
    let mut best = measure(surface, positions, start, q);
    let Some(mut current) = best else {
        return (None, false);
    };
    for _ in 0..MAX_STEPS {
        for &f in surface.neighbours(current.facet) {
            if bvh.degenerate[f as usize] {
                continue;
            }
            if let Some(hit) = measure(surface, positions, f, q) {
                keep(&mut best, hit, f64::INFINITY);
            }
        }
        match best {
            Some(b) if b.facet != current.facet => current = b,
            _ => {
                let ok = current.closest.distance <= max_distance;
                return (ok.then_some(current), ok);
            }
        }
    }
    (best, false)
}

impl Bvh {
    /// The closest facet to `q`, walking from `previous` (the facet it had last time).
    #[must_use]
    pub fn closest_from(
        &self,
        surface: &Surface,
        positions: &[Vec3],
        q: &Query,
        previous: Option<u32>,
        max_distance: f64,
    ) -> (Option<Hit>, bool) {
        if let Some(start) = previous {
            let (hit, done) = walk(self, surface, positions, q, start, max_distance);
            if done {
                return (hit, false);
            }
            let mut seed = None;
            if let Some(h) = hit {
                keep(&mut seed, h, max_distance);
            }
            return (
                self.closest_seeded(surface, positions, q, max_distance, seed),
                true,
            );
        }
        (self.closest(surface, positions, q, max_distance), true)
    }

    /// [`Bvh::closest_from`] for many queries in parallel, with the fallback count.
    #[must_use]
    pub fn closest_all_from(
        &self,
        surface: &Surface,
        positions: &[Vec3],
        queries: &[Query],
        previous: &[Option<u32>],
        max_distance: f64,
    ) -> (Vec<Option<Hit>>, IncrementalStats) {
        let results: Vec<(Option<Hit>, bool)> = queries
            .par_iter()
            .zip(previous.par_iter())
            .with_min_len(256)
            .map(|(q, prev)| self.closest_from(surface, positions, q, *prev, max_distance))
            .collect();
        let stats = IncrementalStats {
            queries: results.len(),
            fallbacks: results.iter().filter(|(_, fell_back)| *fell_back).count(),
        };
        (results.into_iter().map(|(h, _)| h).collect(), stats)
    }
}
