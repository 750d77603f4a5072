//! A bounding-volume hierarchy over the facets of a surface (a linear BVH with child boxes).
//!
//! # Build
//! 1. Each facet's centroid and validity (non-degenerate, see [`crate::Facet::new`]) are computed
//!    in parallel.
//! 2. Valid facets are sorted by the Morton code of their centroid (parallel sort; ties by facet
//!    index, so the order is deterministic). Leaf boxes are the facets' boxes inflated by the
//!    search distance `r`.
//! 3. Each range of the sorted list is split where the highest Morton bit that differs across the
//!    range changes (a binary search), so the two halves are the two halves of a Z-order cell and
//!    their boxes barely overlap; a range of identical codes is split in the middle. Splitting
//!    stops at leaves of at most [`LEAF_SIZE`] facets. (Splitting at the middle index instead was
//!    measured 3–10× slower to query: a middle index often straddles a jump of the Z curve.)
//! 4. Internal nodes are stored depth-first and each holds the boxes of its **two children**, in
//!    `f32` rounded outwards, in one 56-byte record: a traversal step reads one cache line and
//!    decides on both children at once. Leaves are not nodes: a child reference with the top bit
//!    set names `count` facets from `order[first..]`. The top levels are built in parallel
//!    (`rayon::join`), each half into its own list, then joined with child indices shifted.
//! 5. The corner positions of every facet are copied in leaf order, so a query reads a leaf's
//!    facets from one contiguous block, and the boxes are filled bottom-up from those copies
//!    (a parallel recursion over subtrees, which are contiguous runs of nodes).
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
use crate::search::morton::morton_code;
use crate::search::surface::{Surface, SurfaceError};

/// Most facets per leaf (at most 7: the count is stored in three bits).
pub const LEAF_SIZE: usize = 4;

/// A refit whose box area grows past this factor of the area at build triggers a rebuild.
pub const REBUILD_RATIO: f64 = 1.5;

/// The slot of a facet that is not in the tree.
pub(crate) const NO_SLOT: u32 = u32::MAX;

/// Below this many facets a subtree is laid out sequentially.
const PARALLEL_GRAIN: usize = 1 << 16;

/// Top bit of a child reference: the child is a leaf.
const LEAF_FLAG: u32 = 1 << 31;

/// A child reference: an internal node index, or a leaf `LEAF_FLAG | count << 28 | first`.
pub(crate) type Child = u32;

/// A leaf reference holding `count` facets from `order[first..]`.
#[inline]
fn leaf(first: usize, count: usize) -> Child {
    LEAF_FLAG | (index(count) << 28) | index(first)
}

/// `Some((first, count))` for a leaf reference.
#[inline]
pub(crate) fn as_leaf(child: Child) -> Option<(usize, usize)> {
    (child & LEAF_FLAG != 0)
        .then_some(((child & 0x0fff_ffff) as usize, ((child >> 28) & 7) as usize))
}

/// An internal node: the boxes of its two children (outward-rounded `f32`) and the references.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    lo: [[f32; 3]; 2],
    hi: [[f32; 3]; 2],
    pub(crate) child: [Child; 2],
}

impl Node {
    const fn new(child: [Child; 2]) -> Self {
        Self {
            lo: [[f32::INFINITY; 3]; 2],
            hi: [[f32::NEG_INFINITY; 3]; 2],
            child,
        }
    }

    /// Squared distances from `p` to both child boxes (zero inside), written out with plain
    /// comparisons: this is the innermost loop of every query.
    #[inline]
    pub(crate) fn child_distances_squared(&self, p: &Vec3) -> [f64; 2] {
        let gap = |lo: f32, hi: f32, x: f64| {
            let below = f64::from(lo) - x;
            let above = x - f64::from(hi);
            let d = if below > above { below } else { above };
            if d > 0.0 { d * d } else { 0.0 }
        };
        std::array::from_fn(|k| {
            gap(self.lo[k][0], self.hi[k][0], p.x)
                + gap(self.lo[k][1], self.hi[k][1], p.y)
                + gap(self.lo[k][2], self.hi[k][2], p.z)
        })
    }

    /// Stores `b` as the box of child `k`, rounded outwards to `f32`.
    fn set_child_box(&mut self, k: usize, b: &Aabb) {
        for d in 0..3 {
            self.lo[k][d] = round_down(b.min[d]);
            self.hi[k][d] = round_up(b.max[d]);
        }
    }
}

/// The largest `f32` not above `x`.
#[allow(clippy::cast_possible_truncation)]
fn round_down(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) > x { y.next_down() } else { y }
}

/// The smallest `f32` not below `x`.
#[allow(clippy::cast_possible_truncation)]
fn round_up(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x { y.next_up() } else { y }
}

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
    /// Corner positions of `order[s]` at slot `s`.
    pub(crate) corners: Vec<[Vec3; 3]>,
    /// Slot of each facet in `order`, [`NO_SLOT`] for a degenerate facet.
    pub(crate) slot: Vec<u32>,
    pub(crate) degenerate: Vec<bool>,
    inflation: f64,
    built_area: f64,
}

impl Bvh {
    /// Builds the hierarchy of `surface` at `positions`, facet boxes inflated by `inflation`
    /// (the search distance, in the model's length unit; `0` is fine for closest-facet queries).
    ///
    /// # Errors
    /// [`SurfaceError::PositionCount`] if `positions` misses nodes of the surface.
    pub fn build(
        surface: &Surface,
        positions: &[Vec3],
        inflation: f64,
    ) -> Result<Self, SurfaceError> {
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
        let mut keys: Vec<(u64, u32)> = centers
            .par_iter()
            .enumerate()
            .filter(|(f, _)| !degenerate[*f])
            .map(|(f, c)| (morton_code(c, &bounds), index(f)))
            .collect();
        keys.par_sort_unstable();
        let (root, nodes) = layout(&keys, 0, keys.len());
        let order: Vec<u32> = keys.into_par_iter().map(|(_, f)| f).collect();
        let mut slot = vec![NO_SLOT; surface.len()];
        for (s, &f) in order.iter().enumerate() {
            slot[f as usize] = index(s);
        }
        let corners = order
            .par_iter()
            .with_min_len(4096)
            .map(|&f| surface.corners(f, positions))
            .collect();
        let mut bvh = Self {
            nodes,
            root,
            order,
            corners,
            slot,
            degenerate,
            inflation,
            built_area: 0.0,
        };
        bvh.built_area = bvh.sweep();
        bvh
    }

    /// Copies the facets' corner positions into leaf order.
    fn copy_corners(&mut self, surface: &Surface, positions: &[Vec3]) {
        self.corners
            .par_iter_mut()
            .zip(self.order.par_iter())
            .with_min_len(4096)
            .for_each(|(c, &f)| *c = surface.corners(f, positions));
    }

    /// Moves the tree to new `positions`: a refit, or a rebuild when the refit quality degrades or
    /// a facet's validity changed.
    ///
    /// # Errors
    /// [`SurfaceError::PositionCount`] if `positions` misses nodes of the surface.
    pub fn update(
        &mut self,
        surface: &Surface,
        positions: &[Vec3],
    ) -> Result<Update, SurfaceError> {
        surface.check_positions(positions)?;
        let (centers, degenerate) = facet_centers(surface, positions);
        if degenerate == self.degenerate {
            self.copy_corners(surface, positions);
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

    /// The number of internal tree nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Fills every child box bottom-up from the corner copies (leaf boxes inflated by the search
    /// distance), in parallel over subtrees; returns the refit-quality measure (sum of the
    /// children's half-areas).
    fn sweep(&mut self) -> f64 {
        let Self {
            nodes,
            root,
            corners,
            inflation,
            ..
        } = self;
        sweep_subtree(nodes, 0, *root, corners, *inflation).1
    }
}

/// The box of the leaf `corners[first..first + count]`.
fn leaf_box(corners: &[[Vec3; 3]], first: usize, count: usize, inflation: f64) -> Aabb {
    corners[first..first + count]
        .iter()
        .fold(Aabb::EMPTY, |acc, c| acc.union(&Aabb::of_points(c)))
        .inflate(inflation)
}

/// Sweeps the subtree rooted at `child`, whose internal nodes are `nodes` (global indices from
/// `base`, depth-first, so a subtree is a contiguous run); returns its box and area measure.
fn sweep_subtree(
    nodes: &mut [Node],
    base: usize,
    child: Child,
    corners: &[[Vec3; 3]],
    inflation: f64,
) -> (Aabb, f64) {
    if let Some((first, count)) = as_leaf(child) {
        return (leaf_box(corners, first, count, inflation), 0.0);
    }
    debug_assert_eq!(child as usize, base);
    let (head, rest) = nodes.split_at_mut(1);
    let [left, right] = head[0].child;
    // The left subtree runs up to the right child's index (if the right child is a node).
    let split = as_leaf(right).map_or(right as usize - base - 1, |_| rest.len());
    let (lnodes, rnodes) = rest.split_at_mut(split);
    let (lbase, rbase) = (base + 1, base + 1 + split);
    let ((lb, la), (rb, ra)) = if lnodes.len() + rnodes.len() > 4096 {
        rayon::join(
            || sweep_subtree(lnodes, lbase, left, corners, inflation),
            || sweep_subtree(rnodes, rbase, right, corners, inflation),
        )
    } else {
        (
            sweep_subtree(lnodes, lbase, left, corners, inflation),
            sweep_subtree(rnodes, rbase, right, corners, inflation),
        )
    };
    head[0].set_child_box(0, &lb);
    head[0].set_child_box(1, &rb);
    (lb.union(&rb), la + ra + lb.half_area() + rb.half_area())
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

/// The subtree over `keys[lo..hi]`: its reference and its internal nodes, depth-first, with node
/// indices relative to the first of them.
fn layout(keys: &[(u64, u32)], lo: usize, hi: usize) -> (Child, Vec<Node>) {
    if hi - lo <= PARALLEL_GRAIN {
        let mut nodes = Vec::with_capacity(2 * (hi - lo) / LEAF_SIZE + 1);
        let root = push_subtree(&mut nodes, keys, lo, hi);
        return (root, nodes);
    }
    let mid = split(keys, lo, hi);
    let ((lc, left), (rc, right)) = rayon::join(|| layout(keys, lo, mid), || layout(keys, mid, hi));
    let offset = index(1 + left.len());
    // Internal references are relative to their half's first node.
    let shift = |by: u32| move |c: Child| if as_leaf(c).is_some() { c } else { c + by };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    nodes.push(Node::new([shift(1)(lc), shift(offset)(rc)]));
    let moved = |by: u32| {
        move |mut n: Node| {
            n.child = n.child.map(shift(by));
            n
        }
    };
    nodes.extend(left.into_iter().map(moved(1)));
    nodes.extend(right.into_iter().map(moved(offset)));
    (0, nodes)
}

/// Appends the internal nodes of the subtree over `keys[lo..hi]` to `nodes`, sequentially;
/// returns its reference (indices relative to `nodes`).
fn push_subtree(nodes: &mut Vec<Node>, keys: &[(u64, u32)], lo: usize, hi: usize) -> Child {
    if hi - lo <= LEAF_SIZE {
        return leaf(lo, hi - lo);
    }
    let at = nodes.len();
    nodes.push(Node::new([0, 0]));
    let mid = split(keys, lo, hi);
    let left = push_subtree(nodes, keys, lo, mid);
    let right = push_subtree(nodes, keys, mid, hi);
    nodes[at].child = [left, right];
    index(at)
}

/// Where `keys[lo..hi]` (sorted, at least two) splits: the first key whose highest differing bit
/// is set, or the middle for identical codes.
fn split(keys: &[(u64, u32)], lo: usize, hi: usize) -> usize {
    let (first, last) = (keys[lo].0, keys[hi - 1].0);
    if first == last {
        return lo + (hi - lo) / 2;
    }
    let bit = 1u64 << (63 - (first ^ last).leading_zeros());
    lo + keys[lo..hi].partition_point(|k| k.0 & bit == 0)
}

/// Facet and node indices are `u32`; [`Surface::new`] bounds the facet count to 2²⁸.
#[inline]
pub(crate) fn index(i: usize) -> u32 {
    debug_assert!(u32::try_from(i).is_ok());
    #[allow(clippy::cast_possible_truncation)]
    let v = i as u32;
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_follows_the_highest_differing_bit() {
        let keys: Vec<(u64, u32)> = [0b0001u64, 0b0011, 0b0100, 0b0110, 0b0111]
            .iter()
            .zip(0..)
            .map(|(&k, i)| (k, i))
            .collect();
        assert_eq!(split(&keys, 0, 5), 2);
        assert_eq!(split(&keys, 2, 5), 3);
        let same = vec![(7u64, 0u32), (7, 1), (7, 2), (7, 3)];
        assert_eq!(split(&same, 0, 4), 2);
    }

    #[test]
    fn layout_reaches_every_node_once_and_every_facet_once() {
        // Large enough for the parallel top levels (PARALLEL_GRAIN).
        let mut keys: Vec<(u64, u32)> = (0..300_000u32)
            .map(|i| (u64::from(i).pow(2) % 99_991, i))
            .collect();
        keys.sort_unstable();
        let (root, nodes) = layout(&keys, 0, keys.len());
        let mut seen = vec![0u8; keys.len()];
        let mut reached = vec![0u8; nodes.len()];
        let mut stack = vec![root];
        while let Some(c) = stack.pop() {
            match as_leaf(c) {
                Some((first, count)) => {
                    assert!((1..=LEAF_SIZE).contains(&count));
                    seen[first..first + count].iter_mut().for_each(|s| *s += 1);
                }
                None => {
                    reached[c as usize] += 1;
                    stack.extend(nodes[c as usize].child);
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        assert!(reached.iter().all(|&r| r == 1));
    }

    #[test]
    fn boxes_round_outwards() {
        for x in [0.1f64, -0.1, 1e10 + 0.3, -3.7e-5, 0.0] {
            assert!(f64::from(round_down(x)) <= x && f64::from(round_up(x)) >= x);
        }
    }
}
