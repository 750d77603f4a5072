//! A bounding-volume hierarchy over the facets of a surface (a linear BVH with child boxes).
//!
//! # Build
//! 1. Each facet's centroid and validity (non-degenerate, see [`crate::Facet::new`]) are computed
//!    in parallel.
//! 2. Valid facets are sorted by the Hilbert code of their centroid (`search::hilbert`; parallel
//!    sort; ties by facet
//!    index, so the order is deterministic).
//! 3. The sorted facets are cut into leaves of at most eight consecutive ones, with boxes as small
//!    as the cut allows (`search::leaves`: dynamic programming over the facets' boxes, in
//!    parallel over grid cells). The topology above the leaves follows from their codes
//!    ([`crate::search::layout`]): binary splits at grid cell boundaries, collapsed to
//!    four-wide nodes, stored depth-first.
//! 4. The corner positions of every facet are stored leaf by leaf, coordinate by coordinate (the
//!    rows, in parallel over leaves), so a query reads each coordinate of a leaf's facets in one
//!    vector load; the boxes (`search::node`) are filled bottom-up from the rows, leaf boxes
//!    inflated by the search distance `r` (a parallel recursion over subtrees, which are
//!    contiguous runs of nodes).
//!
//! # Refit and rebuild
//! When nodes move, [`Bvh::update`] recomputes facet boxes and sweeps the boxes again (a refit,
//! topology unchanged). A refit keeps every query exact, but the tree loosens as facets travel; the
//! measure is the sum of the children's box half-areas, and when it exceeds [`REBUILD_RATIO`]
//! times its value at the last build, or a facet changes validity, the tree is rebuilt.

use rayon::prelude::*;

use crate::facet::Facet;
use crate::linalg::Vec3;
use crate::search::aabb::Aabb;
use crate::search::hilbert::sorted_keys;
use crate::search::lanes::{LANES, ROWS, groups, leaf_corners, write_leaf};
pub use crate::search::layout::LEAF_SIZE;
pub(crate) use crate::search::layout::index;
use crate::search::layout::{depth, layout};
use crate::search::leaves::leaf_starts;
use crate::search::node::{Child, Node, WIDTH, as_leaf};
use crate::search::surface::{Surface, SurfaceError, SurfaceKey};

/// A refit whose box area grows past this factor of the area at build triggers a rebuild.
pub const REBUILD_RATIO: f64 = 1.5;

/// What a tree names itself in [`SurfaceError::OtherSurface`].
pub(crate) const TREE: &str = "search tree";

/// The slot of a facet that is not in the tree.
pub(crate) const NO_SLOT: u32 = u32::MAX;

/// What [`Bvh::update`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Update {
    /// Boxes refitted, topology kept.
    Refit,
    /// Tree rebuilt (refit quality degraded, or a facet became degenerate or valid again).
    Rebuilt,
}

/// The hierarchy over one surface.
#[derive(Debug, Clone)]
pub struct Bvh {
    pub(crate) nodes: Vec<Node>,
    /// The root reference (a leaf for surfaces of at most [`LEAF_SIZE`] facets).
    pub(crate) root: Child,
    /// Facet indices in leaf order.
    pub(crate) order: Vec<u32>,
    /// The corners group by group (a leaf's groups of at most `LANES` facets, see
    /// [`groups`]), row-major: coordinate `r = 3v + d` of corner `v` of slot `first + k` of the
    /// group `(first, count)` at `ROWS first + r count + k`, row 9 the facet index (as `f64`,
    /// exact), then one vector of zeros (a group's last row is read whole).
    pub(crate) rows: Vec<f64>,
    /// The leaves `(first slot, count)` in slot order (they cover every slot once).
    pub(crate) leaves: Vec<(u32, u32)>,
    /// Each slot's lane in its group and the group's count.
    pub(crate) place: Vec<[u8; 2]>,
    /// Slot of each facet in `order`, [`NO_SLOT`] for a degenerate facet.
    pub(crate) slot: Vec<u32>,
    pub(crate) degenerate: Vec<bool>,
    /// Entries a query's traversal stack may need: three siblings left per level, plus one.
    pub(crate) stack_size: usize,
    /// The mean diagonal of the leaf boxes: the length below which consecutive queries are near.
    pub(crate) leaf_size: f64,
    inflation: f64,
    built_area: f64,
    /// The surface the tree was built on (every call checks that it is given that one).
    pub(crate) surface: SurfaceKey,
}

impl Bvh {
    /// Builds the hierarchy of `surface` at `positions`, facet boxes inflated by `inflation`
    /// (the search distance, in the model's length unit; `0` is fine for closest-facet queries).
    ///
    /// # Errors
    /// [`SurfaceError::PositionCount`] if `positions` misses nodes of the surface;
    /// [`SurfaceError::BadLength`] for a negative or NaN inflation (a negative one shrank the
    /// boxes and lost facets).
    pub fn build(
        surface: &Surface,
        positions: &[Vec3],
        inflation: f64,
    ) -> Result<Self, SurfaceError> {
        if inflation.is_nan() || inflation < 0.0 {
            return Err(SurfaceError::BadLength {
                name: "inflation",
                value: inflation,
            });
        }
        surface.check_positions(positions)?;
        let (centers, degenerate) = facet_centers(surface, positions);
        Ok(Self::from_centers(
            surface, positions, &centers, degenerate, inflation,
        ))
    }

    fn from_centers(
        surface: &Surface,
        positions: &[Vec3],
        centers: &[Vec3],
        degenerate: Vec<bool>,
        inflation: f64,
    ) -> Self {
        let bounds = centers
            .par_iter()
            .zip(degenerate.par_iter())
            .filter(|(_, d)| !**d)
            .map(|(c, _)| Aabb::EMPTY.union_point(c))
            .reduce(|| Aabb::EMPTY, |a, b| a.union(&b));
        // Degenerate facets keyed past every Hilbert code (63 bits), sorted last and cut.
        let mut keys = sorted_keys(centers.len(), &bounds, |f| {
            (!degenerate[f]).then_some(centers[f])
        });
        keys.truncate(keys.partition_point(|&(code, _)| code != u64::MAX));
        let starts = leaf_starts(&keys, inflation, |f| {
            Aabb::of_points(&surface.corners(f, positions))
        });
        let (root, nodes) = layout(&keys, &starts);
        let leaves = leaves_in_order(&nodes, root);
        let stack_size = 3 * depth(&nodes, root) + 1;
        let order: Vec<u32> = keys.into_par_iter().map(|(_, f)| f).collect();
        let mut slot = vec![NO_SLOT; surface.len()];
        for (s, &f) in order.iter().enumerate() {
            slot[f as usize] = index(s);
        }
        let place = leaf_places(&leaves, order.len());
        let mut bvh = Self {
            nodes,
            root,
            order,
            rows: Vec::new(),
            leaves,
            place,
            slot,
            degenerate,
            stack_size,
            leaf_size: 0.0,
            inflation,
            built_area: 0.0,
            surface: surface.key(),
        };
        bvh.fill_rows(surface, positions);
        bvh.built_area = bvh.sweep();
        bvh
    }

    /// Fills [`Bvh::rows`] with the corners of the facets at `positions`, leaf by leaf in
    /// parallel.
    fn fill_rows(&mut self, surface: &Surface, positions: &[Vec3]) {
        let Self {
            rows,
            leaves,
            order,
            ..
        } = self;
        let len = ROWS * order.len() + LANES;
        if rows.is_empty() {
            // Zeroed by the allocator (pages the system zeroes as the fill below first writes
            // them, on every thread) rather than written twice, once by one thread.
            *rows = vec![0.0; len];
        } else {
            rows.resize(len, 0.0);
        }
        // Each group's block of rows, cut off in slot order.
        let mut blocks = Vec::with_capacity(leaves.len());
        let mut rest = rows.as_mut_slice();
        for &(first, count) in leaves.iter() {
            for (first, count) in groups(first as usize, count as usize) {
                let (block, tail) = rest.split_at_mut(ROWS * count);
                blocks.push((block, first));
                rest = tail;
            }
        }
        blocks
            .into_par_iter()
            .with_min_len(512)
            .for_each(|(block, first)| {
                let count = block.len() / ROWS;
                for k in 0..count {
                    let facet = order[first + k];
                    write_leaf(block, count, k, &surface.corners(facet, positions), facet);
                }
            });
    }

    /// The rows of the group (see [`groups`]) whose first slot is `first`.
    #[inline]
    pub(crate) fn leaf_rows(&self, first: usize) -> &[f64] {
        &self.rows[ROWS * first..]
    }

    /// The corners of the facet at `slot`, from its leaf's rows.
    #[inline]
    pub(crate) fn slot_corners(&self, slot: u32) -> [Vec3; 3] {
        let s = slot as usize;
        let [lane, count] = self.place[s].map(usize::from);
        leaf_corners(self.leaf_rows(s - lane), count, lane)
    }

    /// Moves the tree to new `positions`: a refit, or a rebuild when the refit quality degrades or
    /// a facet's validity changed.
    ///
    /// # Errors
    /// [`SurfaceError::OtherSurface`] if `surface` is not the one the tree was built on;
    /// [`SurfaceError::PositionCount`] if `positions` misses nodes of the surface.
    pub fn update(
        &mut self,
        surface: &Surface,
        positions: &[Vec3],
    ) -> Result<Update, SurfaceError> {
        self.surface.check(surface, TREE)?;
        surface.check_positions(positions)?;
        let (centers, degenerate) = facet_centers(surface, positions);
        if degenerate == self.degenerate {
            self.fill_rows(surface, positions);
            if self.sweep() <= REBUILD_RATIO * self.built_area {
                return Ok(Update::Refit);
            }
        }
        *self = Self::from_centers(surface, positions, &centers, degenerate, self.inflation);
        Ok(Update::Rebuilt)
    }

    /// Facets skipped because they are degenerate at the current positions (coincident or collinear
    /// nodes): the report a caller shows the user.
    #[must_use]
    pub fn degenerate_facets(&self) -> Vec<u32> {
        (0..self.degenerate.len())
            .filter(|&f| self.degenerate[f])
            .map(index)
            .collect()
    }

    /// The diagonal of a box holding every facet of the tree (the root's child boxes as stored,
    /// inflated and rounded outwards; the facets themselves when the root is a leaf): at least
    /// the size of any facet, `0` without any.
    #[must_use]
    pub fn extent(&self) -> f64 {
        let empty = Aabb::EMPTY;
        let b = if let Some((first, count)) = as_leaf(self.root) {
            (first..first + count)
                .flat_map(|s| self.slot_corners(index(s)))
                .fold(empty, |b, p| b.union_point(&p))
        } else {
            let node = &self.nodes[self.root as usize];
            (0..WIDTH).fold(empty, |b, k| b.union(&node.child_box(k)))
        };
        let d = (b.max - b.min).norm();
        if d.is_finite() { d } else { 0.0 }
    }

    /// The number of internal tree nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Fills every child box bottom-up from the rows (leaf boxes inflated by the search
    /// distance), in parallel over subtrees, and the mean leaf diagonal; returns the refit-quality
    /// measure (sum of the children's half-areas).
    fn sweep(&mut self) -> f64 {
        let Self {
            nodes,
            root,
            rows,
            inflation,
            ..
        } = self;
        let measure = sweep_subtree(nodes, 0, *root, rows, *inflation).1;
        self.leaf_size = measure.mean_diagonal();
        measure.area
    }

    /// The box of the whole tree (`None` for a tree that is a single leaf, which has none stored).
    pub(crate) fn bounds(&self) -> Option<Aabb> {
        if as_leaf(self.root).is_some() {
            return None;
        }
        let node = &self.nodes[self.root as usize];
        Some((0..WIDTH).fold(Aabb::EMPTY, |b, k| b.union(&node.child_box(k))))
    }
}

/// What a sweep adds up: the refit-quality measure (the children's half-areas) and the leaf
/// boxes' diagonals, with their number.
#[derive(Debug, Clone, Copy, Default)]
struct Measure {
    area: f64,
    diagonals: f64,
    leaves: usize,
}

impl Measure {
    /// The measure with one more child box `b`, a leaf's or not.
    fn with_box(self, b: &Aabb, leaf: bool) -> Measure {
        Measure {
            area: self.area + b.half_area(),
            diagonals: self.diagonals + if leaf { (b.max - b.min).norm() } else { 0.0 },
            leaves: self.leaves + usize::from(leaf),
        }
    }

    fn plus(self, other: Measure) -> Measure {
        Measure {
            area: self.area + other.area,
            diagonals: self.diagonals + other.diagonals,
            leaves: self.leaves + other.leaves,
        }
    }

    /// The mean leaf diagonal (zero without leaves).
    fn mean_diagonal(&self) -> f64 {
        #[allow(clippy::cast_precision_loss)]
        let mean = if self.leaves == 0 {
            0.0
        } else {
            self.diagonals / self.leaves as f64
        };
        mean
    }
}

/// The box of the leaf `(first, count)` of the tree's `rows`, inflated by `inflation`: each
/// coordinate's bounds over the leaf's three rows of it (the corners of a facet in the tree are
/// finite).
fn leaf_box(rows: &[f64], first: usize, count: usize, inflation: f64) -> Aabb {
    let mut b = Aabb::EMPTY;
    for (first, count) in groups(first, count) {
        let block = &rows[ROWS * first..ROWS * (first + count)];
        for v in 0..3 {
            for d in 0..3 {
                for &x in &block[(3 * v + d) * count..(3 * v + d + 1) * count] {
                    b.min[d] = b.min[d].min(x);
                    b.max[d] = b.max[d].max(x);
                }
            }
        }
    }
    b.inflate(inflation)
}

/// Sweeps the subtree rooted at `child`, whose internal nodes are `nodes` (global indices from
/// `base`, depth-first, so every subtree is a contiguous run); returns its box and measure.
fn sweep_subtree(
    nodes: &mut [Node],
    base: usize,
    child: Child,
    rows: &[f64],
    inflation: f64,
) -> (Aabb, Measure) {
    if let Some((first, count)) = as_leaf(child) {
        if count == 0 {
            return (Aabb::EMPTY, Measure::default());
        }
        return (leaf_box(rows, first, count, inflation), Measure::default());
    }
    debug_assert_eq!(child as usize, base);
    let (head, mut rest) = nodes.split_at_mut(1);
    let refs = head[0].child;
    // Cut `rest` into the runs of the internal children, in order.
    let mut runs: Vec<(usize, &mut [Node], usize)> = Vec::with_capacity(WIDTH);
    let mut start = base + 1;
    let internal: Vec<usize> = (0..WIDTH).filter(|&k| as_leaf(refs[k]).is_none()).collect();
    for (i, &k) in internal.iter().enumerate() {
        let end = internal
            .get(i + 1)
            .map_or(start + rest.len(), |&n| refs[n] as usize);
        let (run, tail) = std::mem::take(&mut rest).split_at_mut(end - start);
        runs.push((k, run, start));
        rest = tail;
        start = end;
    }
    let parallel = nodes_len(&runs) > 2048;
    let swept: Vec<(usize, Aabb, Measure)> = if parallel {
        runs.into_par_iter()
            .map(|(k, run, b)| {
                let (bx, m) = sweep_subtree(run, b, refs[k], rows, inflation);
                (k, bx, m)
            })
            .collect()
    } else {
        runs.into_iter()
            .map(|(k, run, b)| {
                let (bx, m) = sweep_subtree(run, b, refs[k], rows, inflation);
                (k, bx, m)
            })
            .collect()
    };
    let mut total = Aabb::EMPTY;
    let mut measure = Measure::default();
    for (k, bx, m) in swept {
        head[0].set_child_box(k, &bx);
        total = total.union(&bx);
        measure = measure.plus(m).with_box(&bx, false);
    }
    for (k, &c) in refs.iter().enumerate() {
        if let Some((first, count)) = as_leaf(c)
            && count > 0
        {
            let bx = leaf_box(rows, first, count, inflation);
            head[0].set_child_box(k, &bx);
            total = total.union(&bx);
            measure = measure.with_box(&bx, true);
        }
    }
    (total, measure)
}

fn nodes_len(runs: &[(usize, &mut [Node], usize)]) -> usize {
    runs.iter().map(|(_, r, _)| r.len()).sum()
}

/// Each slot's `[lane in its group, the group's count]` (see [`groups`]), for `slots` slots
/// covered by `leaves`.
fn leaf_places(leaves: &[(u32, u32)], slots: usize) -> Vec<[u8; 2]> {
    let mut place = Vec::with_capacity(slots);
    for &(first, count) in leaves {
        for (_, count) in groups(first as usize, count as usize) {
            #[allow(clippy::cast_possible_truncation)]
            place.extend((0..count).map(|k| [k as u8, count as u8]));
        }
    }
    place
}

/// The non-empty leaves of the tree `(nodes, root)` as `(first slot, count)`, in slot order.
fn leaves_in_order(nodes: &[Node], root: Child) -> Vec<(u32, u32)> {
    let mut leaves: Vec<(u32, u32)> = std::iter::once(root)
        .chain(nodes.iter().flat_map(|n| n.child))
        .filter_map(as_leaf)
        .filter(|&(_, count)| count > 0)
        .map(|(first, count)| (index(first), index(count)))
        .collect();
    leaves.par_sort_unstable();
    leaves
}

/// Centroid and degeneracy of every facet at `positions`.
fn facet_centers(surface: &Surface, positions: &[Vec3]) -> (Vec<Vec3>, Vec<bool>) {
    (0..surface.len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|f| {
            let [a, b, c] = surface.corners(index(f), positions);
            ((a + b + c) / 3.0, Facet::new(a, b, c).is_err())
        })
        .unzip()
}
