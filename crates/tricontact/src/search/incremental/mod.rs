//! Incremental search: the closest facets again after the nodes moved a little, without the tree.
//!
//! # Neighbourhood lists
//! A full search ([`Neighbourhoods::new`]) records, for each query, its point `p₀`, its closest
//! distance `d₀`, and every facet within the reach `ρ = d₀ + skin` with its distance `d₀(f)` then
//! (sorted by it; stored in `f32`, rounded down) and the direction `n̂(f)` from its closest point
//! to `p₀` (four bytes, `search::direction`), together with the surface's node positions
//! `x₀`. One traversal per query finds them: a box is pruned when it is farther than the best
//! distance so far plus the skin (queries in parallel chunks, each hinted with the previous one's
//! answer). A query's point, reach, first three listed facets and the distance of the fourth fill
//! one 64-byte record, which is all most queries read.
//!
//! # Certificate
//! Later, with node positions `x` and query point `p`, let `δ = maxₙ |xₙ − x₀ₙ|` over the
//! surface's nodes and `m = |p − p₀| + δ`. Every point of a facet is a convex combination of its
//! nodes, so it moved by at most `δ`, and the distance from the query to any facet changed by at
//! most `m`: `d(f) ≥ d₀(f) − m`. A facet that is not listed was farther than `ρ`, so it is now
//! farther than `ρ − m`; when the best distance `b` found satisfies `b < ρ − m`, the best listed
//! facet is the closest of all. The query measures its first listed facet, then goes down its list
//! in increasing `d₀(f)` until `d₀(f) − m` exceeds `b`: the facets left are farther than `b`.
//!
//! A facet near the first in `d₀` (a point far off a flat patch is almost as far from the
//! neighbouring facets) is measured only if a sharper bound cannot exclude it. For a convex set `K`
//! and any unit vector `n`, the distance from `q` to `K` is at least `n·q − h(n)`, where
//! `h(n) = max_{y∈K} n·y` is the support of `K` in the direction `n`; for `n = n̂(f)`, the
//! direction from the facet's closest point to `p₀` then, this is an equality at `p₀`:
//! `d₀(f) = n̂·p₀ − h₀(n̂)`. A triangle's support is that of its corners, so after its nodes moved
//! by `mₙ = xₙ − x₀ₙ` it rose by at most `r(f) = maxₙ∈f n̂·mₙ`, the rise; hence
//!
//! `d(f) ≥ d₀(f) − r(f) + n̂(f)·(p − p₀)`.
//!
//! Only the motion along `n̂` counts: a facet sliding, turning or stretching in its own plane
//! loosens nothing, and when the surface moves smoothly the rise is nearly the change the measured
//! first facet went through, so close competitors are excluded without measuring them (on the
//! benchmark's torus after a motion of 0.01 element sizes: 1.07 facets measured per query at 10⁶
//! facets, against 1.10 with directions to 7·10⁻³, 1.15 with the largest node motion relative to
//! the facet's first node in place of the rise along `n̂`, and 2.0 with the Lipschitz bound
//! alone). The stored `d₀(f)` is rounded down and `n̂` decoded within `ε = DIRECTION_ERROR`
//! (1.2·10⁻³): the decoded direction changes `n̂·(p − p₀)` by at most `ε |p − p₀|` and the rise by
//! at most `ε maxₙ |mₙ| ≤ ε δ`, so the bound is widened by `ε m`, one number for all of a query's
//! facets, and a listed facet's bound needs of its nodes only the three products `n̂·mₙ`. (The
//! bound is the same for any translation `T` subtracted from `p − p₀` and from every `mₙ`; an
//! earlier form took the motion of the facet's first node and widened by
//! `ε (|p − p₀ − T|₁ + maxₙ |mₙ − T|₁)` per facet, sharper only where the query points move with
//! the surface, and slower: see `docs/search-benchmarks.md`.) The widening also covers the
//! rounding of the terms in the motions, and a margin of 10⁻⁹ of the coordinates' magnitude the
//! rounding in the others. Where `p₀` was within 10⁻⁶ of that magnitude of a listed facet,
//! its direction is not reliable (rounding) and is not stored: the entry keeps the distance `0`
//! and no direction, which no bound can exclude, so that facet is measured. (Zero is a
//! subgradient only where the distance is zero: a query that was `10⁻⁷` from a facet and moves
//! onto it must find it, a test.)
//!
//! Candidates are measured with the kernel the tree uses ([`crate::distance_squared_to_triangle`],
//! bit for bit) and compared in the same total order (distance, then facet index), so the answer
//! is the tree's, exactly.
//!
//! # Order of work
//! Each node's motion `x − x₀` is computed once for the new positions ([`Neighbourhoods::moved`],
//! the counterpart of a tree's refit), with `δ`, the longest, in the same pass, into a buffer the
//! calling thread keeps from call to call; the bounds read it (one array instead of the positions
//! and the reference positions, and no subtraction per facet). Queries go in chunks of 1024 (in
//! parallel; 2–4 % faster than 256 on an Intel Xeon with 2 MB of second-level cache a core, no
//! different on the AMD machines); within a chunk, a group at a time (one per lane: eight with
//! AVX-512, four otherwise), their first listed facets are measured together (`search::lanes`) and
//! written as the answers, and each query is screened: every facet the bounds cannot exclude is put
//! aside (all exclusions are against the first facet's distance; measuring others can only lower
//! it). The queries whose lists must be walked beyond the record then walk them, their first
//! further entries read all together so that their fetches from memory overlap. The facets put
//! aside are then measured a vector of lanes at a time, and a better one replaces the answer. A
//! query whose first listed facet is missing (empty list, or excluded by the query) goes through
//! the same tests one facet at a time; a query at NaN or infinity has no answer, as in the tree.
//! What the chunk's end reads is asked for early (the lines of a walk's first and sixth further
//! entries as soon as the query is found to walk, the corners of a facet when it is put aside), the
//! answers' lines are asked for with the intent to write them (`prefetchw`) four groups ahead, and
//! the records 32 queries ahead.
//!
//! On the 10⁶-facet torus after a motion of 0.01 element sizes, 11.9 % of the queries need more
//! than their first facet (0.07 facets put aside per query; 6.7 % walk, 85 % of them through
//! exactly three further entries: six facets about as far, as around a node of this mesh), and a
//! call took about 33 ns a query on one core of an AMD EPYC (Zen 4, measured before the chunks of
//! 1024 and the records asked for ahead) and takes 29 on an Intel Xeon (there 1.2 for the motions
//! and 27 for the query after them when timed apart, and about 25 for the one call with the
//! queries not certified at once left unanswered, a timing-only variant). The measurements behind
//! each choice above, and the alternatives measured and not kept (among them bounds for a group of
//! queries or for a whole list that read no motion per listed facet, and the record's listed facets
//! measured instead of screened), are in `docs/search-benchmarks.md` ("The incremental search, as
//! measured").
//!
//! A query whose answer is not certified falls back to the tree, which [`Moved::closest_all`]
//! (and [`Neighbourhoods::closest_all`]) updates first, once, only if some query needs it: the
//! certified queries never touch the tree.
//! [`IncrementalStats`] counts fallbacks and measured facets. When the nodes have moved by about
//! half the skin, lists fail and should be made again.
//!
//! # Lists rather than a walk over adjacent facets
//! Walking from the facet found last time to nearer facets that share a node with it
//! ([`Surface::neighbours`]) ends on a facet nearer than its neighbours, which certifies nothing:
//! another sheet (two plates, the far side of a thin part), or any part of the surface the walk
//! does not reach, can be nearer. The lists carry a certificate (the reach), and their order (by
//! distance then) lets most queries stop after their first facet. Measured on the benchmark's
//! torus after a motion of 0.01 element sizes, one core: such a walk (from the previous answer,
//! the scalar kernel on the facet and its neighbours, until none is nearer) measured 13.2 facets
//! per query and took 220–235 ns per query at 10⁵ and 10⁶ facets (its answers all equal to the
//! tree's on this smooth motion, none certified); at the lanes' cost per facet (a leaf of eight
//! in about 35 ns) its 13.2 facets alone would take about 58 ns. The lists took 42–52 ns,
//! certified, in the same runs (`search_loop walk` and `search_loop incremental`, examples of
//! this crate).
//!
//! [`Surface::neighbours`]: crate::search::Surface::neighbours
//!
//! # Degenerate facets
//! A query whose best listed facet is degenerate now is not certified (it falls back to the tree,
//! which leaves degenerate facets out); degeneracy is checked on the winner only. The lists keep
//! the smallest node motion that could make one of their facets degenerate (`robustness`): a
//! call that moved the nodes less checks none; otherwise the first listed facets are cleared by a
//! lane test with room for rounding (`lanes::clearly_valid`) and the others by
//! [`crate::Facet::new`]. Facets that were degenerate when the lists were made are in no list;
//! every query measures those that are valid now.

mod answer;
mod lists;
mod moved;

pub use moved::Moved;

use rayon::prelude::*;

use crate::linalg::Vec3;
use crate::search::bvh::Update;
use crate::search::direction::Direction;
use crate::search::screen::NEAR;
use crate::search::surface::SurfaceKey;

/// What one call of [`Moved::closest_all`] (or [`Neighbourhoods::closest_all`]) did.
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

/// One listed facet after the first.
#[derive(Debug, Clone, Copy)]
struct Entry {
    /// The facet (for an empty place of a [`Head`], its first listed facet).
    facet: u32,
    /// Its distance then, rounded down to `f32` (zero within
    /// [`DIRECTION_FLOOR`](lists::DIRECTION_FLOOR), `+∞` for an empty place in a [`Head`]).
    distance: f32,
    /// The direction from its closest point then to the query point then (or zero).
    direction: Direction,
}

impl Entry {
    /// `false` for an empty place of a [`Head`].
    #[inline]
    fn listed(&self) -> bool {
        self.distance < f32::INFINITY
    }
}

/// What a call reads of a query, in one cache line: its point and reach then, its first listed
/// facet (the closest then) and the next [`NEAR`], the distance of the one after, and where the
/// rest of its list starts.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Head {
    /// The query point when the lists were made.
    point: Vec3,
    /// The radius within which the list holds every facet, rounded down (`+∞` without any facet).
    reach: f32,
    /// The first listed facet, [`NONE`] for an empty list.
    facet: u32,
    /// The next listed facets (past the end of the list: empty places).
    near: [Entry; NEAR],
    /// The distance then of the listed facet after those (`+∞` past the end).
    after: f32,
    /// The rest of the list is `entries[start..]` up to the next head's `start`.
    start: u32,
}

const _: () = assert!(
    std::mem::size_of::<Head>() == 64 && std::mem::size_of::<Entry>() == 12,
    "a record is one cache line, an entry twelve bytes"
);

/// What the lists name themselves in
/// [`SurfaceError::OtherSurface`](crate::search::SurfaceError::OtherSurface).
const LISTS: &str = "set of neighbourhood lists";

/// The facet of an empty list.
const NONE: u32 = u32::MAX;

/// Per-query neighbourhood lists from a full search, for the incremental search.
#[derive(Debug, Clone)]
pub struct Neighbourhoods {
    /// Surface node positions when the lists were made (one per node of the surface).
    reference: Vec<Vec3>,
    /// The surface the lists were made on (so every listed facet is one of its facets).
    surface: SurfaceKey,
    /// One per query, and a last one that only closes the entries.
    heads: Vec<Head>,
    entries: Vec<Entry>,
    /// Facets degenerate when the lists were made.
    degenerate: Vec<u32>,
    /// A node motion below which no listed facet can have become degenerate (see
    /// [`robustness`](lists::robustness)): a call whose largest motion is below it checks no
    /// facet for degeneracy.
    robust: f64,
}

impl Neighbourhoods {
    /// The number of listed facets, all queries together (the lists take 64 bytes per query and
    /// 12 per facet beyond the first three of each).
    #[must_use]
    pub fn len(&self) -> usize {
        let near =
            |h: &Head| usize::from(h.facet != NONE) + h.near.iter().filter(|e| e.listed()).count();
        self.entries.len() + self.heads.iter().map(near).sum::<usize>()
    }

    /// The memory the lists take, in bytes (query records, further entries, reference positions).
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.heads.len() * std::mem::size_of::<Head>()
            + self.entries.len() * std::mem::size_of::<Entry>()
            + self.reference.len() * std::mem::size_of::<Vec3>()
            + self.degenerate.len() * 4
    }

    /// `true` when no query lists any facet.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The number of queries the lists were made for.
    fn queries(&self) -> usize {
        self.heads.len() - 1
    }

    /// The largest distance any surface node moved since the lists were made (NaN if a position
    /// is NaN).
    #[must_use]
    pub fn motion(&self, positions: &[Vec3]) -> f64 {
        longest(
            self.reference
                .par_iter()
                .zip(positions.par_iter())
                .with_min_len(4096)
                .map(|(a, b)| b - a),
        )
    }
}

/// The largest length of `moves` (NaN if one is NaN), `0` for none.
fn longest(moves: impl ParallelIterator<Item = Vec3>) -> f64 {
    moves
        .map(|m| m.norm_squared())
        .reduce(|| 0.0, longer)
        .sqrt()
}

/// The larger of two squared lengths, NaN if either is.
#[inline(always)]
fn longer(a: f64, b: f64) -> f64 {
    if a > b || a.is_nan() { a } else { b }
}
