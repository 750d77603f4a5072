//! Making the neighbourhood lists: one traversal of the tree per query finds every facet within
//! the query's closest distance plus the skin; each list is stored as a record of one cache line
//! (the point, the reach, the first [`NEAR`] + 1 facets) and further entries (facet, distance
//! rounded down, direction). See the parent module for what the lists certify.

use rayon::prelude::*;

use super::{Entry, Head, NONE, Neighbourhoods};
use crate::closest::closest_point_and_distance_squared;
use crate::facet::DEGENERACY_TOLERANCE;
use crate::linalg::Vec3;
use crate::search::bvh::{Bvh, TREE};
use crate::search::direction::Direction;
use crate::search::lanes;
use crate::search::layout::index;
use crate::search::node::{Child, as_leaf, round_down};
use crate::search::query::{HINT_CHUNK, Query, TIE_MARGIN, farthest_first};
use crate::search::screen::NEAR;
use crate::search::surface::{Surface, SurfaceError};

/// Below this distance, relative to the magnitude of the coordinates, a listed facet's direction
/// is not stored (zero; its rounding error could exceed
/// [`DIRECTION_ERROR`](crate::search::direction::DIRECTION_ERROR)) and its distance is taken as
/// zero.
pub(super) const DIRECTION_FLOOR: f64 = 1e-6;

/// One chunk's lists (see [`Neighbourhoods::chunk_lists`]).
struct ChunkLists {
    /// The records, `start` counted from the chunk's first further entry.
    heads: Vec<Head>,
    /// The further entries.
    entries: Vec<Entry>,
    /// The smallest robustness of the listed facets.
    robust: f64,
    /// The listed facets, records' and further entries together.
    listed: usize,
}

/// The robustness of every facet is computed once, in a table, when the queries are at least
/// `1 / TABLE_COVER` of the facets (each facet is then in many lists); otherwise per listed facet.
const TABLE_COVER: usize = 8;

/// The largest offset into the further entries: offsets are `u32`.
const MAX_OFFSET: usize = u32::MAX as usize;

/// `at` as an offset into the further entries, `None` beyond `limit` (at most [`MAX_OFFSET`]).
fn list_offset(at: usize, limit: usize) -> Option<u32> {
    if at > limit {
        return None;
    }
    u32::try_from(at).ok()
}

impl Neighbourhoods {
    /// Lists, for each query, the facets within its closest distance plus `skin` (in the model's
    /// length unit: about twice the motion expected before the lists are made again).
    ///
    /// `bvh` must be built or updated at `positions`.
    ///
    /// # Errors
    /// [`SurfaceError::OtherSurface`] if `bvh` was built on another surface;
    /// [`SurfaceError::PositionCount`] if `positions` misses nodes of the surface;
    /// [`SurfaceError::ListsTooLong`] if the lists exceed 2³² entries;
    /// [`SurfaceError::BadLength`] for a skin that is negative, NaN or infinite (a NaN skin made
    /// empty lists that certified wrong answers).
    pub fn new(
        bvh: &Bvh,
        surface: &Surface,
        positions: &[Vec3],
        queries: &[Query],
        skin: f64,
    ) -> Result<Self, SurfaceError> {
        if !(skin >= 0.0 && skin.is_finite()) {
            return Err(SurfaceError::BadLength {
                name: "skin",
                value: skin,
            });
        }
        Self::within_offsets(bvh, surface, positions, queries, skin, MAX_OFFSET)
    }

    /// [`Neighbourhoods::new`] with list offsets of at most `limit` (at most [`MAX_OFFSET`]; a
    /// test makes lists too long for a small limit).
    fn within_offsets(
        bvh: &Bvh,
        surface: &Surface,
        positions: &[Vec3],
        queries: &[Query],
        skin: f64,
        limit: usize,
    ) -> Result<Self, SurfaceError> {
        bvh.surface.check(surface, TREE)?;
        surface.check_positions(positions)?;
        // Each facet's robustness once (a facet is in about a dozen lists) when the queries cover
        // much of the surface; for a few queries on a large surface, per listed facet.
        let table: Option<Vec<f64>> = (TABLE_COVER * queries.len() >= surface.len()).then(|| {
            (0..surface.len())
                .into_par_iter()
                .with_min_len(4096)
                .map(|f| robustness(&surface.corners(index(f), positions)))
                .collect()
        });
        let robustness_of = |f: u32| match &table {
            Some(t) => t[f as usize],
            None => robustness(&surface.corners(f, positions)),
        };
        // Chunks in parallel, each query hinted with the previous one's closest facet.
        let chunks: Vec<Result<ChunkLists, usize>> = queries
            .par_chunks(HINT_CHUNK)
            .map(|chunk| {
                Self::chunk_lists(bvh, surface, positions, &robustness_of, chunk, skin, limit)
            })
            .collect();
        let listed: usize = chunks
            .iter()
            .map(|c| c.as_ref().map_or_else(|&n| n, |c| c.listed))
            .sum();
        let too_long = || SurfaceError::ListsTooLong { entries: listed };
        let chunks: Vec<ChunkLists> = chunks
            .into_iter()
            .collect::<Result<_, _>>()
            .map_err(|_| too_long())?;
        let total = chunks.iter().map(|c| c.entries.len()).sum();
        let mut entries = Vec::with_capacity(total);
        let mut heads = Vec::with_capacity(queries.len() + 1);
        let mut robust = f64::INFINITY;
        for chunk in chunks {
            let offset = entries.len();
            for mut head in chunk.heads {
                head.start =
                    list_offset(offset + head.start as usize, limit).ok_or_else(too_long)?;
                heads.push(head);
            }
            entries.extend_from_slice(&chunk.entries);
            robust = robust.min(chunk.robust);
        }
        let empty = Entry {
            facet: 0,
            distance: f32::INFINITY,
            direction: Direction::ZERO,
        };
        heads.push(Head {
            point: Vec3::zeros(),
            reach: 0.0,
            facet: NONE,
            near: [empty; NEAR],
            after: f32::INFINITY,
            start: list_offset(entries.len(), limit).ok_or_else(too_long)?,
        });
        Ok(Self {
            reference: positions[..surface.node_count()].to_vec(),
            surface: surface.key(),
            heads,
            entries,
            degenerate: bvh.degenerate_facets(),
            robust,
        })
    }

    /// The lists of one chunk of queries (see [`Neighbourhoods::new`]), made with one set of
    /// buffers, `robustness(f)` giving facet `f`'s robustness. `Err` with the number of listed
    /// facets so far when the chunk's further entries need an offset beyond `limit`.
    fn chunk_lists(
        bvh: &Bvh,
        surface: &Surface,
        positions: &[Vec3],
        robustness: &impl Fn(u32) -> f64,
        chunk: &[Query],
        skin: f64,
        limit: usize,
    ) -> Result<ChunkLists, usize> {
        let mut out = ChunkLists {
            heads: Vec::with_capacity(chunk.len()),
            entries: Vec::new(),
            robust: f64::INFINITY,
            listed: 0,
        };
        let (mut list, mut stack) = (Vec::new(), Vec::new());
        let mut hint = None;
        for q in chunk {
            let reach = bvh.neighbourhood(surface, q, hint, skin, &mut list, &mut stack);
            hint = list.first().map(|&(_, f)| f).or(hint);
            for &(_, f) in &list {
                out.robust = out.robust.min(robustness(f));
            }
            out.listed += list.len();
            let start = list_offset(out.entries.len(), limit).ok_or(out.listed)?;
            let head = record(surface, positions, q, reach, &list, start, &mut out.entries);
            out.heads.push(head);
        }
        Ok(out)
    }
}

/// The record of query `q` whose list (facets by increasing squared distance, at `positions`) has
/// the reach `reach`; its entries after the record's are appended to `rest`, from `start`.
fn record(
    surface: &Surface,
    positions: &[Vec3],
    q: &Query,
    reach: f64,
    list: &[(f64, u32)],
    start: u32,
    rest: &mut Vec<Entry>,
) -> Head {
    let first = list.first().map_or(0, |&(_, f)| f);
    let empty = Entry {
        facet: first,
        distance: f32::INFINITY,
        direction: Direction::ZERO,
    };
    let entry = |k: usize| {
        list.get(k)
            .map_or(empty, |&(d2, f)| entry(surface, positions, q, f, d2))
    };
    let head = Head {
        point: q.point,
        reach: round_down(reach),
        facet: list.first().map_or(NONE, |&(_, f)| f),
        near: std::array::from_fn(|k| entry(1 + k)),
        after: list
            .get(1 + NEAR)
            .map_or(f32::INFINITY, |&(d2, _)| round_down(d2.sqrt())),
        start,
    };
    rest.extend((1 + NEAR..list.len()).map(entry));
    head
}

/// The list entry of `facet` for query `q` at `positions`, `d2` its squared distance from the tree.
/// Within the direction floor the entry has no direction and the distance zero, which no bound can
/// exclude (a facet the query was almost on is measured).
pub(super) fn entry(
    surface: &Surface,
    positions: &[Vec3],
    q: &Query,
    facet: u32,
    d2: f64,
) -> Entry {
    let [a, b, c] = surface.corners(facet, positions);
    let (closest, _) = closest_point_and_distance_squared(&a, &b, &c, &q.point);
    let d = closest.distance;
    let floor = DIRECTION_FLOOR * (q.point.amax() + closest.point.amax());
    let (distance, direction) = if d > floor {
        let n = (q.point - closest.point) / d;
        (round_down(d2.sqrt()), Direction::encode(&n))
    } else {
        (0.0, Direction::ZERO)
    };
    Entry {
        facet,
        distance,
        direction,
    }
}

impl Bvh {
    /// Every facet within `skin` of the closest distance `d` to `q`, into `found` as `(squared
    /// distance, facet)` sorted by distance then index; returns the reach `d + skin` (`+∞`
    /// without any facet). One traversal: a box is pruned when it is farther than the best
    /// distance so far plus `skin`. `found` and `stack` are buffers (cleared first).
    fn neighbourhood(
        &self,
        surface: &Surface,
        q: &Query,
        hint: Option<u32>,
        skin: f64,
        found: &mut Vec<(f64, u32)>,
        stack: &mut Vec<(Child, f64)>,
    ) -> f64 {
        let mut best = hint
            .and_then(|f| self.candidate(surface, q, f))
            .map_or(f64::INFINITY, |c| c.d2);
        let bound = |best: f64| (best.sqrt() + skin).powi(2) * TIE_MARGIN;
        found.clear();
        stack.clear();
        stack.push((self.root, 0.0));
        while let Some((child, d2_box)) = stack.pop() {
            if d2_box > bound(best) {
                continue;
            }
            if let Some((first, count)) = as_leaf(child) {
                if count == 0 {
                    continue;
                }
                for (first, count) in lanes::groups(first, count) {
                    let d2 = lanes::measure_leaf(self.leaf_rows(first), count, &q.point)
                        .d2
                        .to_array();
                    for (k, &d2) in d2.iter().enumerate().take(count) {
                        let facet = self.order[first + k];
                        if !q.excludes(surface, facet) && d2 <= bound(best) {
                            best = best.min(d2);
                            found.push((d2, facet));
                        }
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
            found.clear();
            return f64::INFINITY;
        }
        let reach = best.sqrt() + skin;
        found.retain(|&(d2, _)| d2 <= reach * reach);
        // A total order (a facet is found once), so an unstable sort gives the one result.
        found.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        reach
    }
}

/// A node motion below which the facet `(a, b, c)` cannot become degenerate: moving each node by at
/// most `ρ` changes each edge by at most `2ρ`, so twice the area `|w|` falls by at most
/// `2ρ(|e₁| + |e₂|) + 4ρ²` and the longest edge grows by at most `2ρ`. `ρ = 0.2 |w| / (|e₁| + |e₂|)`
/// is kept when, with these changes, `|w|` still exceeds twice [`DEGENERACY_TOLERANCE`] times the
/// longest edge squared and `|w|²` stays a normal number; otherwise `0`.
pub(super) fn robustness([a, b, c]: &[Vec3; 3]) -> f64 {
    let (e1, e2, e3) = (b - a, c - a, c - b);
    let w = e1.cross(&e2).norm();
    let (l1, l2) = (e1.norm(), e2.norm());
    let longest = l1.max(l2).max(e3.norm());
    let rho = 0.2 * w / (l1 + l2);
    let low = w - 2.0 * rho * (l1 + l2) - 4.0 * rho * rho;
    let long = longest + 2.0 * rho;
    let keeps = low > 2.0 * DEGENERACY_TOLERANCE * long * long
        && low * low >= 4.0 * f64::MIN_POSITIVE
        && (low * low).is_finite();
    if keeps && rho.is_finite() { rho } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::facet::Facet;
    use crate::search::scenes::{near_surface, torus, uniform};

    /// The surface of `facets` over `nodes`, its tree, and one query per facet within 0.1 of it.
    fn scene(nodes: &[Vec3], facets: &[[u32; 3]]) -> (Surface, Bvh, Vec<Query>) {
        let surface = Surface::new(facets.to_vec(), nodes.len()).unwrap();
        let bvh = Bvh::build(&surface, nodes, 0.0).unwrap();
        let queries = near_surface(nodes, facets, 0.1, 2)
            .into_iter()
            .map(Query::point)
            .collect();
        (surface, bvh, queries)
    }

    /// Lists whose offsets would exceed the limit (2³² − 1; here a small one, since the real one
    /// takes 50 GB of entries) are refused with the count of listed facets, whether the limit is
    /// passed within a chunk or only by the lists put together; lists that just fit are made.
    #[test]
    fn lists_beyond_the_offset_limit_are_refused() {
        let (nodes, facets) = torus(40, 20, 2.0, 0.6);
        let (surface, bvh, queries) = scene(&nodes, &facets);
        assert!(queries.len() > HINT_CHUNK, "two chunks");
        let make =
            |limit| Neighbourhoods::within_offsets(&bvh, &surface, &nodes, &queries, 0.1, limit);
        let full = make(MAX_OFFSET).unwrap();
        let further = full.entries.len();
        assert!(further > 1000, "{further} further entries");
        let fits = make(further).unwrap();
        assert_eq!((fits.len(), fits.entries.len()), (full.len(), further));
        for limit in [further - 1, 10] {
            match make(limit) {
                Err(SurfaceError::ListsTooLong { entries }) => {
                    assert!(
                        entries > limit && entries <= full.len(),
                        "{entries} for {limit}"
                    );
                }
                other => panic!("limit {limit}: {:?}", other.map(|l| l.len())),
            }
        }
    }

    /// The lists' robustness is the smallest of their facets', whether it comes from the table
    /// (queries covering the surface) or is computed per listed facet (a few queries); on a
    /// torus whose node positions are jittered, so that the facets differ.
    #[test]
    fn the_robustness_is_that_of_the_listed_facets_by_either_path() {
        let (mut nodes, facets) = torus(40, 20, 2.0, 0.6);
        let mut r = uniform(17);
        for p in &mut nodes {
            *p += Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * 0.05;
        }
        let (surface, bvh, all) = scene(&nodes, &facets);
        let few: Vec<Query> = all.iter().step_by(4 * TABLE_COVER).copied().collect();
        assert!(
            TABLE_COVER * few.len() < surface.len() && TABLE_COVER * all.len() >= surface.len()
        );
        for queries in [&all, &few] {
            let lists = Neighbourhoods::new(&bvh, &surface, &nodes, queries, 0.05).unwrap();
            let (heads, entries) = (&lists.heads[..queries.len()], &lists.entries);
            let listed = heads
                .iter()
                .filter(|h| h.facet != NONE)
                .map(|h| h.facet)
                .chain(
                    heads
                        .iter()
                        .flat_map(|h| h.near.iter().filter(|e| e.listed()).map(|e| e.facet)),
                )
                .chain(entries.iter().map(|e| e.facet));
            let expected = listed
                .map(|f| robustness(&surface.corners(f, &nodes)))
                .fold(f64::INFINITY, f64::min);
            assert!(expected > 0.0 && expected < f64::INFINITY);
            assert_eq!(
                lists.robust.to_bits(),
                expected.to_bits(),
                "{} queries",
                queries.len()
            );
        }
    }

    /// Random facets (slivers among them), each node moved by just under the facet's robustness
    /// in the direction that shrinks the area most among random tries: still valid.
    #[test]
    fn facets_moved_by_less_than_their_robustness_stay_valid() {
        let mut r = uniform(12);
        let mut v = || Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5);
        let (mut positive, mut total) = (0, 0);
        for k in 0..20_000 {
            let flat = 10f64.powi(-(k % 13));
            let (a, b) = (v(), v());
            let c = a + 0.4 * (b - a) + flat * v();
            let rho = robustness(&[a, b, c]);
            total += 1;
            if rho == 0.0 {
                continue;
            }
            positive += 1;
            assert!(Facet::new(a, b, c).is_ok());
            for _ in 0..8 {
                let mut push = || {
                    let d = v();
                    d * (0.999 * rho / d.norm())
                };
                let moved = [a + push(), b + push(), c + push()];
                assert!(
                    Facet::new(moved[0], moved[1], moved[2]).is_ok(),
                    "{a:?} {b:?} {c:?} by {rho}"
                );
            }
        }
        // Facets that are not slivers have a robustness.
        assert!(positive * 2 > total, "{positive} of {total}");
        assert_eq!(
            robustness(&[Vec3::zeros(), Vec3::x(), 2.0 * Vec3::x()]),
            0.0
        );
    }
}
