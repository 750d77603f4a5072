//! Incremental search: the closest facets again after the nodes moved a little, without the tree.
//!
//! # Neighbourhood lists
//! A full search ([`Neighbourhoods::new`]) records, for each query, its point `p₀`, its closest
//! distance `d₀`, and every facet within the reach `ρ = d₀ + skin` with its distance `d₀(f)` then
//! (sorted by it; stored in `f32`, rounded down), together with the surface's node positions `x₀`.
//! One traversal per query finds both: a box is pruned when it is farther than the best distance
//! so far plus the skin (queries in parallel chunks, each hinted with the previous one's answer).
//!
//! # Certificate
//! Later, with node positions `x` and query point `p`, let `δ = maxₙ |xₙ − x₀ₙ|` over the
//! surface's nodes and `m = |p − p₀| + δ`. Every point of a facet is a convex combination of its
//! nodes, so it moved by at most `δ`, and the distance from the query to any facet changed by at
//! most `m`: `d(f) ≥ d₀(f) − m`. The query measures its listed facets in increasing `d₀(f)` until
//! `d₀(f) − m` exceeds the best distance `b` found: the facets left are farther than `b`. A facet
//! that is not listed was farther than `ρ`, so it is now farther than `ρ − m`; when `b < ρ − m` the
//! best measured facet is the closest of all. Candidates are measured with the kernel the tree
//! uses ([`crate::distance_squared_to_triangle`]) and compared in the same total order
//! (distance, then facet index), so the answer is the tree's, exactly. A margin of 10⁻⁹ of the
//! coordinates' magnitude absorbs rounding in these bounds.
//!
//! A query whose answer is not certified falls back to the tree, which
//! [`Neighbourhoods::closest_all`] updates first, once, only if some query needs it: the certified
//! queries never touch the tree.
//! [`IncrementalStats`] counts fallbacks and measured facets. When the nodes have moved by about
//! half the skin, lists fail and should be made again.
//!
//! # Degenerate facets
//! A query whose best listed facet is degenerate now is not certified (it falls back to the tree,
//! which leaves degenerate facets out); degeneracy is checked on the winner only. Facets that were
//! degenerate when the lists were made are in no list; every query measures those that are valid
//! now.
//!
//! # Cost
//! A measured facet costs one Voronoi-region computation, which gives both the squared distance
//! the order compares and the closest point reported; only the winner is checked for degeneracy,
//! and answers are written in place. Measuring the listed facets four at a time with the tree's
//! branch-free kernel was slower (173 against 96 ns per query on the 10⁴-facet torus): it measures
//! more of them, and the scalar kernel returns early in vertex regions. Measuring in rounds
//! across the queries of a chunk instead (each round takes every unfinished query's next listed
//! facet, four (query, facet) pairs per lane evaluation, closest points bit for bit the scalar
//! kernel's) was slower too: 139 against 111 ns per query on the 10⁵-facet torus after a motion
//! of 0.01 h, and 136 ns with the rounds measured by the scalar kernel — the bookkeeping of the
//! rounds costs more than the lanes save on two facets per query.

use rayon::prelude::*;

use crate::closest::{ClosestPoint, closest_point_and_distance_squared};
use crate::facet::Facet;
use crate::linalg::Vec3;
use crate::search::bvh::{Bvh, Update};
use crate::search::lanes;
use crate::search::node::{as_leaf, round_down};
use crate::search::query::{HINT_CHUNK, TIE_MARGIN, check_answers, farthest_first};
use crate::search::query::{Hit, Query};
use crate::search::surface::{Surface, SurfaceError};

/// Relative margin of the certificate, on the magnitude of the coordinates and distances.
const MARGIN: f64 = 1e-9;

/// Queries answered in one sequential run of [`Neighbourhoods::closest_all_into`].
const CHUNK: usize = 256;

/// What one call of [`Neighbourhoods::closest_all`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct IncrementalStats {
    /// Queries answered.
    pub queries: usize,
    /// Queries whose answer was not certified by their list and fell back to the tree.
    pub fallbacks: usize,
    /// Facets measured from the lists (all queries together).
    pub measured: usize,
    /// What the tree update before the fallbacks did (`None`: no fallback, tree untouched).
    pub update: Option<Update>,
}

/// Per-query neighbourhood lists from a full search, for the incremental search.
#[derive(Debug, Clone)]
pub struct Neighbourhoods {
    /// Surface node positions when the lists were made.
    reference: Vec<Vec3>,
    /// Query points then.
    points: Vec<Vec3>,
    /// Per query: the radius within which its list holds every facet (`+∞` without any facet).
    reach: Vec<f64>,
    /// Per query: its entries are `facets[start[i]..start[i + 1]]` (and `distances`).
    start: Vec<usize>,
    facets: Vec<u32>,
    /// Distances then, rounded down to `f32`, increasing within each list.
    distances: Vec<f32>,
    /// Facets degenerate when the lists were made.
    degenerate: Vec<u32>,
}

/// The best candidate of an incremental query so far.
#[derive(Clone, Copy)]
struct Best {
    d2: f64,
    facet: u32,
    closest: ClosestPoint,
}

/// `Ok` when a query's answer was certified (and written), else `Err(best facet found)`, with the
/// number of facets measured.
type Outcome = (Result<(), Option<u32>>, usize);

impl Neighbourhoods {
    /// Lists, for each query, the facets within its closest distance plus `skin` (in the model's
    /// length unit: about twice the motion expected before the lists are made again).
    ///
    /// `bvh` must be built or updated at `positions`.
    ///
    /// # Errors
    /// [`SurfaceError::PositionCount`] if `positions` misses nodes of the surface.
    pub fn new(
        bvh: &Bvh,
        surface: &Surface,
        positions: &[Vec3],
        queries: &[Query],
        skin: f64,
    ) -> Result<Self, SurfaceError> {
        surface.check_positions(positions)?;
        // Chunks in parallel, each query hinted with the previous one's closest facet.
        let lists: Vec<(f64, Vec<(f64, u32)>)> = queries
            .par_chunks(HINT_CHUNK)
            .flat_map_iter(|chunk| {
                let mut hint = None;
                chunk.iter().map(move |q| {
                    let (reach, list) = bvh.neighbourhood(surface, q, hint, skin);
                    hint = list.first().map(|&(_, f)| f).or(hint);
                    (reach, list)
                })
            })
            .collect();
        let mut start = Vec::with_capacity(queries.len() + 1);
        start.push(0);
        let total: usize = lists.iter().map(|(_, l)| l.len()).sum();
        let (mut facets, mut distances) = (Vec::with_capacity(total), Vec::with_capacity(total));
        for (_, list) in &lists {
            facets.extend(list.iter().map(|&(_, f)| f));
            distances.extend(list.iter().map(|&(d2, _)| round_down(d2.sqrt())));
            start.push(facets.len());
        }
        Ok(Self {
            reference: positions[..surface.node_count()].to_vec(),
            points: queries.iter().map(|q| q.point).collect(),
            reach: lists.iter().map(|(r, _)| *r).collect(),
            start,
            facets,
            distances,
            degenerate: bvh.degenerate_facets(),
        })
    }

    /// The number of listed facets, all queries together (the lists' memory is 8 bytes each).
    #[must_use]
    pub fn len(&self) -> usize {
        self.facets.len()
    }

    /// `true` when no query lists any facet.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.facets.is_empty()
    }

    /// The largest distance any surface node moved since the lists were made.
    #[must_use]
    pub fn motion(&self, positions: &[Vec3]) -> f64 {
        self.reference
            .par_iter()
            .zip(positions.par_iter())
            .with_min_len(4096)
            .map(|(a, b)| (b - a).norm())
            .reduce(|| 0.0, f64::max)
    }

    /// The closest facet to each query (the same queries, in the same order, as when the lists
    /// were made; their points may have moved) at node `positions`, within `max_distance`: equal
    /// to [`Bvh::closest_all`] at these positions. Queries the lists cannot certify fall back to
    /// `bvh`, which is updated to `positions` first (once, and only then).
    ///
    /// # Errors
    /// [`SurfaceError::PositionCount`] if `positions` misses nodes of the surface;
    /// [`SurfaceError::QueryCount`] if the number of queries changed.
    pub fn closest_all(
        &self,
        bvh: &mut Bvh,
        surface: &Surface,
        positions: &[Vec3],
        queries: &[Query],
        max_distance: f64,
    ) -> Result<(Vec<Option<Hit>>, IncrementalStats), SurfaceError> {
        let mut hits = vec![None; queries.len()];
        let stats =
            self.closest_all_into(bvh, surface, positions, queries, max_distance, &mut hits)?;
        Ok((hits, stats))
    }

    /// [`Neighbourhoods::closest_all`] written into `hits`, one entry per query (a buffer reused
    /// from call to call, see [`Bvh::closest_all_into`]).
    ///
    /// # Errors
    /// As [`Neighbourhoods::closest_all`], and [`SurfaceError::AnswerCount`] if `hits` does not
    /// have one entry per query.
    pub fn closest_all_into(
        &self,
        bvh: &mut Bvh,
        surface: &Surface,
        positions: &[Vec3],
        queries: &[Query],
        max_distance: f64,
        hits: &mut [Option<Hit>],
    ) -> Result<IncrementalStats, SurfaceError> {
        surface.check_positions(positions)?;
        if queries.len() != self.points.len() {
            return Err(SurfaceError::QueryCount {
                expected: self.points.len(),
                given: queries.len(),
            });
        }
        check_answers(queries.len(), hits.len())?;
        let delta = self.motion(positions);
        let valid: Vec<u32> = self
            .degenerate
            .iter()
            .copied()
            .filter(|&f| !is_degenerate(&surface.corners(f, positions)))
            .collect();
        let max2 = max_distance * max_distance;
        // Answers are written in place; the (rare) uncertified queries are collected with their
        // best facet as the tree's hint. Chunks in parallel, a plain loop within each (rayon's
        // adaptors per query cost about 10 of 128 ns on the 10⁵-facet torus).
        let (measured, fallbacks) = hits
            .par_chunks_mut(CHUNK)
            .zip(queries.par_chunks(CHUNK))
            .enumerate()
            .map(|(c, (hits, queries))| {
                let (mut measured, mut fallbacks) = (0, Vec::new());
                for (k, (hit, q)) in hits.iter_mut().zip(queries).enumerate() {
                    let i = c * CHUNK + k;
                    let (outcome, n) =
                        self.answer((i, q), surface, positions, (delta, max2), &valid, hit);
                    measured += n;
                    if let Err(hint) = outcome {
                        fallbacks.push((i, hint));
                    }
                }
                (measured, fallbacks)
            })
            .reduce(
                || (0, Vec::new()),
                |(m1, mut f1), (m2, f2)| {
                    f1.extend(f2);
                    (m1 + m2, f1)
                },
            );
        let mut stats = IncrementalStats {
            queries: queries.len(),
            measured,
            ..IncrementalStats::default()
        };
        if !fallbacks.is_empty() {
            stats.fallbacks = fallbacks.len();
            stats.update = Some(bvh.update(surface, positions)?);
            let tree = &*bvh;
            let redone: Vec<Option<Hit>> = fallbacks
                .par_iter()
                .map(|&(i, hint)| tree.closest_with_hint(surface, &queries[i], hint, max_distance))
                .collect();
            for ((i, _), hit) in fallbacks.iter().zip(redone) {
                hits[*i] = hit;
            }
        }
        Ok(stats)
    }

    /// Query `i` from its list, given the motion `δ` and the squared search distance: a certified
    /// answer is written into `hit` (returning the answer by value, one copy more, was measured
    /// 4 % slower); see [`Outcome`].
    fn answer(
        &self,
        (i, q): (usize, &Query),
        surface: &Surface,
        positions: &[Vec3],
        (delta, max2): (f64, f64),
        valid: &[u32],
        hit: &mut Option<Hit>,
    ) -> Outcome {
        let p0 = &self.points[i];
        let m = (q.point - p0).norm() + delta;
        let reach = self.reach[i];
        let tol =
            MARGIN * (q.point.amax() + p0.amax() + if reach.is_finite() { reach } else { 0.0 });
        let range = self.start[i]..self.start[i + 1];
        let mut best: Option<Best> = None;
        let mut measured = 0;
        for (&f, &d0) in self.facets[range.clone()]
            .iter()
            .zip(&self.distances[range])
        {
            if best.is_some_and(|b| f64::from(d0) - m > b.closest.distance + tol) {
                break;
            }
            offer(&mut best, surface, positions, q, f);
            measured += 1;
        }
        for &f in valid {
            offer(&mut best, surface, positions, q, f);
        }
        measured += valid.len();
        // Facets not listed are farther than `limit` now; a degenerate winner is not certified.
        let limit = reach - m - tol;
        let b = best.map_or(f64::INFINITY, |b| b.closest.distance);
        let certified = (b < limit || max2.sqrt() < limit)
            && best.is_none_or(|b| !is_degenerate(&surface.corners(b.facet, positions)));
        if !certified {
            return (Err(best.map(|b| b.facet)), measured);
        }
        *hit = best.filter(|b| b.d2 <= max2).map(|b| Hit {
            facet: b.facet,
            closest: b.closest,
        });
        (Ok(()), measured)
    }
}

impl Bvh {
    /// Every facet within `skin` of the closest distance `d` to `q`, as `(squared distance, facet)`
    /// sorted by distance then index, and the reach `d + skin` (`+∞` without any facet). One
    /// traversal: a box is pruned when it is farther than the best distance so far plus `skin`.
    fn neighbourhood(
        &self,
        surface: &Surface,
        q: &Query,
        hint: Option<u32>,
        skin: f64,
    ) -> (f64, Vec<(f64, u32)>) {
        let mut best = hint
            .and_then(|f| self.candidate(surface, q, f))
            .map_or(f64::INFINITY, |c| c.d2);
        let bound = |best: f64| (best.sqrt() + skin).powi(2) * TIE_MARGIN;
        let mut found = Vec::new();
        let mut stack = vec![(self.root, 0.0)];
        while let Some((child, d2_box)) = stack.pop() {
            if d2_box > bound(best) {
                continue;
            }
            if let Some((first, count)) = as_leaf(child) {
                if count == 0 {
                    continue;
                }
                let corners = &self.corners[first..first + count];
                let d2 = lanes::distances_squared(corners, &q.point).to_array();
                for (k, &d2) in d2.iter().enumerate().take(count) {
                    let facet = self.order[first + k];
                    if !q.excludes(surface, facet) && d2 <= bound(best) {
                        best = best.min(d2);
                        found.push((d2, facet));
                    }
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let limit = bound(best);
            for (d, c) in farthest_first(node.child_distances_squared(&q.point), node.child) {
                if d <= limit && d < f64::INFINITY {
                    stack.push((c, d));
                }
            }
        }
        if best == f64::INFINITY {
            return (f64::INFINITY, Vec::new());
        }
        let reach = best.sqrt() + skin;
        found.retain(|&(d2, _)| d2 <= reach * reach);
        found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        (reach, found)
    }
}

/// Offers `facet` at `positions` to `best`, in the tree's order (distance, then index); skipped
/// when the query excludes it.
fn offer(best: &mut Option<Best>, surface: &Surface, positions: &[Vec3], q: &Query, facet: u32) {
    if q.excludes(surface, facet) {
        return;
    }
    let [a, b, c] = surface.corners(facet, positions);
    let (closest, d2) = closest_point_and_distance_squared(&a, &b, &c, &q.point);
    let better = match best {
        None => true,
        Some(b) => d2 < b.d2 || (d2 == b.d2 && facet < b.facet),
    };
    if better {
        *best = Some(Best { d2, facet, closest });
    }
}

/// `true` when the facet is degenerate (the tree leaves such facets out).
fn is_degenerate([a, b, c]: &[Vec3; 3]) -> bool {
    Facet::new(*a, *b, *c).is_err()
}
