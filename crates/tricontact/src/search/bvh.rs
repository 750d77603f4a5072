//! A bounding-volume hierarchy over the facets of a surface (a linear BVH).
//!
//! # Build
//! 1. Each facet's box (its three nodes, inflated by the search distance `r`) and its validity
//!    (non-degenerate, see [`crate::Facet::new`]) are computed in parallel.
//! 2. Valid facets are sorted by the Morton code of their box centre (parallel sort; ties by facet
//!    index, so the order is deterministic).
//! 3. Each range of the sorted list is split where the highest Morton bit that differs across the
//!    range changes (a binary search), so the two halves are the two halves of a Z-order cell and
//!    their boxes barely overlap; a range of identical codes is split in the middle. Splitting
//!    stops at leaves of at most [`LEAF_SIZE`] facets. Nodes are stored depth-first: the left child
//!    follows its parent, the parent stores the right child's index. The top levels are built in
//!    parallel (`rayon::join`), each half into its own list, and joined with the right half's child
//!    indices shifted. (Splitting at the middle index instead, which fixes subtree sizes, was
//!    measured 3–10× slower to query: a middle index often straddles a jump of the Z curve.)
//! 4. Boxes are filled by one reverse sweep (children always follow their parent).
//! 5. The corner positions of every facet are copied in leaf order, so a query reads the facets of a
//!    leaf from one contiguous block instead of gathering nodes through indices.
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

/// The slot of a facet that is not in the tree.
pub(crate) const NO_SLOT: u32 = u32::MAX;

/// Below this many facets a subtree is laid out sequentially.
const PARALLEL_GRAIN: usize = 1 << 16;

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
        let (boxes, degenerate) = facet_boxes(surface, positions, inflation);
        Ok(Self::from_boxes(
            surface, positions, &boxes, degenerate, inflation,
        ))
    }

    fn from_boxes(
        surface: &Surface,
        positions: &[Vec3],
        boxes: &[Aabb],
        degenerate: Vec<bool>,
        inflation: f64,
    ) -> Self {
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
        let nodes = if keys.is_empty() {
            vec![Node {
                aabb: Aabb::EMPTY,
                first: 0,
                count: 0,
            }]
        } else {
            layout(&keys, 0, keys.len())
        };
        let order: Vec<u32> = keys.into_iter().map(|(_, f)| f).collect();
        let mut slot = vec![NO_SLOT; surface.len()];
        for (s, &f) in order.iter().enumerate() {
            slot[f as usize] = index(s);
        }
        let mut bvh = Self {
            nodes,
            order,
            corners: Vec::new(),
            slot,
            degenerate,
            inflation,
            built_area: 0.0,
        };
        bvh.copy_corners(surface, positions);
        bvh.sweep(boxes);
        bvh.built_area = bvh.internal_area();
        bvh
    }

    /// Copies the facets' corner positions into leaf order.
    fn copy_corners(&mut self, surface: &Surface, positions: &[Vec3]) {
        self.corners.resize(self.order.len(), [Vec3::zeros(); 3]);
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
        let (boxes, degenerate) = facet_boxes(surface, positions, self.inflation);
        if degenerate == self.degenerate {
            self.sweep(&boxes);
            if self.internal_area() <= REBUILD_RATIO * self.built_area {
                self.copy_corners(surface, positions);
                return Ok(Update::Refit);
            }
        }
        *self = Self::from_boxes(surface, positions, &boxes, degenerate, self.inflation);
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

/// The subtree over `keys[lo..hi]`, depth-first, child indices relative to its root.
fn layout(keys: &[(u64, u32)], lo: usize, hi: usize) -> Vec<Node> {
    let mut nodes = Vec::with_capacity(2 * (hi - lo) / LEAF_SIZE + 1);
    if hi - lo > PARALLEL_GRAIN {
        let mid = split(keys, lo, hi);
        let (left, right) = rayon::join(|| layout(keys, lo, mid), || layout(keys, mid, hi));
        let offset = index(1 + left.len());
        nodes.push(Node {
            aabb: Aabb::EMPTY,
            first: offset,
            count: 0,
        });
        // Internal nodes' child indices are relative to their half's first node.
        let shift = |by: u32| {
            move |mut n: Node| {
                if n.count == 0 {
                    n.first += by;
                }
                n
            }
        };
        nodes.extend(left.into_iter().map(shift(1)));
        nodes.extend(right.into_iter().map(shift(offset)));
    } else {
        push_subtree(&mut nodes, keys, lo, hi);
    }
    nodes
}

/// Appends the subtree over `keys[lo..hi]` to `nodes`, sequentially.
fn push_subtree(nodes: &mut Vec<Node>, keys: &[(u64, u32)], lo: usize, hi: usize) {
    let at = nodes.len();
    if hi - lo <= LEAF_SIZE {
        nodes.push(Node {
            aabb: Aabb::EMPTY,
            first: index(lo),
            count: index(hi - lo),
        });
        return;
    }
    let mid = split(keys, lo, hi);
    nodes.push(Node {
        aabb: Aabb::EMPTY,
        first: 0,
        count: 0,
    });
    push_subtree(nodes, keys, lo, mid);
    nodes[at].first = index(nodes.len());
    push_subtree(nodes, keys, mid, hi);
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
    fn layout_is_depth_first_and_covers_every_facet_once() {
        // Large enough for the parallel top levels (PARALLEL_GRAIN).
        let keys: Vec<(u64, u32)> = (0..300_000u32)
            .map(|i| (u64::from(i).pow(2) % 99_991, i))
            .collect();
        let mut keys = keys;
        keys.sort_unstable();
        let nodes = layout(&keys, 0, keys.len());
        let mut seen = vec![false; keys.len()];
        for (i, n) in nodes.iter().enumerate() {
            if n.count > 0 {
                for s in n.first..n.first + n.count {
                    assert!(!seen[s as usize]);
                    seen[s as usize] = true;
                }
            } else {
                assert!(n.first as usize > i + 1 && (n.first as usize) < nodes.len());
            }
        }
        assert!(seen.iter().all(|&s| s));
        // Every node is reached exactly once from the root.
        let mut reached = vec![0u8; nodes.len()];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            reached[i] += 1;
            if nodes[i].count == 0 {
                stack.push(i + 1);
                stack.push(nodes[i].first as usize);
            }
        }
        assert!(reached.iter().all(|&r| r == 1));
    }
}
