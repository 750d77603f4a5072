//! A bounding-volume hierarchy over the facets of a surface (a linear BVH).
//!
//! # Build
//! 1. Each facet's box (its three nodes, inflated by the search distance `r`) and its validity
//!    (non-degenerate, see [`crate::Facet::new`]) are computed in parallel.
//! 2. Valid facets are sorted by the Morton code of their box centre (parallel sort; ties by facet
//!    index, so the order is deterministic).
//! 3. The sorted list is split in halves recursively down to leaves of at most [`LEAF_SIZE`]
//!    facets. Nodes are stored depth-first: the left child follows its parent, the parent stores the
//!    right child's index. Subtree sizes are known in closed form, so both halves are laid out in
//!    parallel into disjoint slices.
//! 4. Boxes are filled by one reverse sweep (children always follow their parent).
//!
//! # Refit and rebuild
//! When nodes move, [`Bvh::update`] recomputes facet boxes and sweeps the boxes again (a refit,
//! topology unchanged). A refit keeps every query exact, but the tree loosens as facets travel; the
//! measure is `Σ half-area of the internal boxes`, and when it exceeds [`REBUILD_RATIO`] times its
//! value at the last build, or a facet changes validity, the tree is rebuilt.

use rayon::prelude::*;

use crate::facet::Facet;
use crate::linalg::Vec3;
use crate::search::aabb::Aabb;
use crate::search::morton::morton_code;
use crate::search::surface::{Surface, SurfaceError};

/// Most facets per leaf.
pub const LEAF_SIZE: usize = 4;

/// A refit whose box area grows past this factor of the area at build triggers a rebuild.
pub const REBUILD_RATIO: f64 = 1.5;

/// Below this many facets a subtree is laid out sequentially.
const PARALLEL_GRAIN: usize = 8192;

/// A node: a leaf holds `count > 0` facets from `order[first..]`; an internal node has `count = 0`,
/// its left child at the next index and its right child at `first`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    pub(crate) aabb: Aabb,
    pub(crate) first: u32,
    pub(crate) count: u32,
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
    pub(crate) order: Vec<u32>,
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
        let (boxes, degenerate) = facet_boxes(surface, positions, inflation);
        Ok(Self::from_boxes(&boxes, degenerate, inflation))
    }

    fn from_boxes(boxes: &[Aabb], degenerate: Vec<bool>, inflation: f64) -> Self {
        let bounds = boxes
            .par_iter()
            .zip(degenerate.par_iter())
            .filter(|(_, d)| !**d)
            .map(|(b, _)| Aabb::EMPTY.union_point(&b.center()))
            .reduce(|| Aabb::EMPTY, |a, b| a.union(&b));
        let mut keys: Vec<(u64, u32)> = boxes
            .par_iter()
            .enumerate()
            .filter(|(f, _)| !degenerate[*f])
            .map(|(f, b)| (morton_code(&b.center(), &bounds), index(f)))
            .collect();
        keys.par_sort_unstable();
        let order: Vec<u32> = keys.into_iter().map(|(_, f)| f).collect();
        let mut nodes = vec![
            Node {
                aabb: Aabb::EMPTY,
                first: 0,
                count: 0,
            };
            node_count(order.len()).max(1)
        ];
        if !order.is_empty() {
            layout(&mut nodes, 0, 0, order.len());
        }
        let mut bvh = Self {
            nodes,
            order,
            degenerate,
            inflation,
            built_area: 0.0,
        };
        bvh.sweep(boxes);
        bvh.built_area = bvh.internal_area();
        bvh
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
        let (boxes, degenerate) = facet_boxes(surface, positions, self.inflation);
        if degenerate != self.degenerate {
            *self = Self::from_boxes(&boxes, degenerate, self.inflation);
            return Ok(Update::Rebuilt);
        }
        self.sweep(&boxes);
        if self.internal_area() > REBUILD_RATIO * self.built_area {
            *self = Self::from_boxes(&boxes, degenerate, self.inflation);
            return Ok(Update::Rebuilt);
        }
        Ok(Update::Refit)
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

    /// The number of tree nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Fills every box bottom-up from the facet boxes.
    fn sweep(&mut self, boxes: &[Aabb]) {
        if self.order.is_empty() {
            self.nodes[0].aabb = Aabb::EMPTY;
            return;
        }
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            let aabb = if node.count > 0 {
                let start = node.first as usize;
                self.order[start..start + node.count as usize]
                    .iter()
                    .fold(Aabb::EMPTY, |acc, &f| acc.union(&boxes[f as usize]))
            } else {
                self.nodes[i + 1]
                    .aabb
                    .union(&self.nodes[node.first as usize].aabb)
            };
            self.nodes[i].aabb = aabb;
        }
    }

    fn internal_area(&self) -> f64 {
        self.nodes
            .iter()
            .filter(|n| n.count == 0)
            .map(|n| n.aabb.half_area())
            .sum()
    }
}

/// Boxes (inflated) and degeneracy of every facet at `positions`.
fn facet_boxes(surface: &Surface, positions: &[Vec3], inflation: f64) -> (Vec<Aabb>, Vec<bool>) {
    (0..surface.len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|f| {
            let [a, b, c] = surface.corners(index(f), positions);
            let valid = Facet::new(a, b, c).is_ok();
            (Aabb::of_points(&[a, b, c]).inflate(inflation), !valid)
        })
        .unzip()
}

/// Lays out the subtree over `order[lo..hi]` into `nodes`, whose first entry has global index
/// `base`.
fn layout(nodes: &mut [Node], base: usize, lo: usize, hi: usize) {
    let m = hi - lo;
    if m <= LEAF_SIZE {
        nodes[0] = Node {
            aabb: Aabb::EMPTY,
            first: index(lo),
            count: index(m),
        };
        return;
    }
    let mid = lo + m / 2;
    let left_count = node_count(m / 2);
    let (head, rest) = nodes.split_at_mut(1);
    let (left, right) = rest.split_at_mut(left_count);
    head[0] = Node {
        aabb: Aabb::EMPTY,
        first: index(base + 1 + left_count),
        count: 0,
    };
    if m > PARALLEL_GRAIN {
        rayon::join(
            || layout(left, base + 1, lo, mid),
            || layout(right, base + 1 + left_count, mid, hi),
        );
    } else {
        layout(left, base + 1, lo, mid);
        layout(right, base + 1 + left_count, mid, hi);
    }
}

/// Nodes of the subtree over `m` facets split in halves down to [`LEAF_SIZE`]: with
/// `f(m) = 1` for `m ≤ LEAF_SIZE` and `f(m) = 1 + f(⌊m/2⌋) + f(⌈m/2⌉)` otherwise, the pair
/// `(f(m), f(m + 1))` follows from the pair at `⌊m/2⌋` in O(log m).
pub(crate) fn node_count(m: usize) -> usize {
    fn pair(m: usize) -> (usize, usize) {
        if m < LEAF_SIZE {
            return (1, 1);
        }
        if m == LEAF_SIZE {
            return (1, 3);
        }
        let (fa, fb) = pair(m / 2);
        if m.is_multiple_of(2) {
            (1 + 2 * fa, 1 + fa + fb)
        } else {
            (1 + fa + fb, 1 + 2 * fb)
        }
    }
    if m == 0 { 0 } else { pair(m).0 }
}

/// Facet and node indices are `u32`; [`Surface::new`] bounds the facet count.
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

    fn naive(m: usize) -> usize {
        if m <= LEAF_SIZE {
            1
        } else {
            1 + naive(m / 2) + naive(m - m / 2)
        }
    }

    #[test]
    fn node_count_matches_recursion() {
        for m in 1..5000 {
            assert_eq!(node_count(m), naive(m), "m = {m}");
        }
    }
}
