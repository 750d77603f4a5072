//! Tree topology from facets sorted along a Hilbert curve: binary splits, then collapsed to
//! four-wide nodes.
//!
//! # Splits
//! The leaves are given: runs of at most [`LEAF_SIZE`] consecutive sorted facets
//! (`search::leaves`). Each range of leaves is split where the highest code bit that differs
//! across the first codes of its leaves changes (a binary search), so the two halves are, up to
//! the leaves at the boundary, two halves of a grid cell (`search::hilbert`: the top bits of a code
//! name its cell) and their boxes barely overlap; a
//! range of identical codes is split in the middle. (Splitting at the middle index instead was
//! measured 3–10× slower to query, when the facets were in Z-order: a middle index often
//! straddled a jump of the Z curve.)
//!
//! Before the leaves were cut by `search::leaves`, the splits went on down to ranges of at most
//! eight facets, which left 5.2–5.4 facets a leaf on the benchmark's tori (of the eight lanes a
//! leaf is measured in). Cutting the leaves to least expanded box area fills them to 6.3 and made
//! coherent queries 8–9 % faster on the 10⁶-facet torus (`search_loop closest 1000`, best of
//! interleaved rounds: 330.6 vs 361.7 ns) and 3–4 % faster at 10⁵ and 10⁴ (321.4 vs 332.6, 296.4
//! vs 308.5); the build on two threads went from 111.8 to 116.2 ns per facet, on one from 171 to
//! 226, the refit from 55.3 to 51.6 (one core). Grouping the leaves into their parent nodes by the
//! same dynamic programming (runs of up to four leaves, margins of 0.5, 1 and 2 mean leaf
//! diagonals) instead of by the splits: within noise (353.0, 361.2 and 365.4 vs 358.5 ns at 10⁶,
//! best of four interleaved rounds).
//!
//! Leaf size. A leaf holds up to eight facets, measured together one per lane (`search::lanes`: in
//! one group of eight lanes where the build targets AVX-512, in groups of four otherwise). On an
//! AVX-512 machine, with leaves cut by the splits, leaves of up to four were 15 % slower to query
//! on the 10⁵-facet torus (medians of six interleaved runs; there an eight-lane measurement costs
//! what a four-lane one does), and leaves of up to five, six and seven lay in between. On an AVX2
//! machine (AMD EPYC, Zen 3), measured in groups of four, leaves of up to four answered 1–2 %
//! faster than leaves of eight (463 vs 471 ns at 10⁵ facets, 481 vs 492 at 10⁶) but were 15 %
//! slower to build and 17 % slower to refit (`search_loop build` and `refit`, 254 vs 224 and 66 vs
//! 57 ns per facet at 10⁶), and leaves of up to six were slower to query than either: eight
//! everywhere. With four facets per leaf, splitting ranges of five to eight facets after their
//! first four instead of at a Morton bit filled leaves to 3.1 and made coherent queries 1–2 %
//! faster, within run-to-run noise. With the leaves cut by `search::leaves` (a later session, the
//! same Zen 3 machine), leaves of up to four answered 7–10 % faster at 10⁵ facets (441–456 vs
//! 476–500 ns, five interleaved rounds of `search_loop closest 316 15`) and 1–11 % at 10⁶ (487–524
//! vs 510–550 ns), but refit 5–30 % slower (68–86 vs 63–68 ns per facet) and built no faster
//! (191–241 vs 197–225 ns per facet on two threads); in two interleaved runs of `search_bench` the
//! build at 10⁶ read 5.02 and 4.39 M facets/s against 5.49 and 5.05, below its target of 5 in one
//! run, and the coherent figure at 10⁶ did not separate them (1.85 and 1.90 vs 1.89 and 1.53 M/s
//! per core). A gain of that size does not reach the coherent target on that machine and would
//! cost the build its margin: eight stayed. The top levels are split in parallel
//! (`rayon::join`), each half into its own list, joined with shifted indices.
//!
//! # Collapse
//! Every internal node of the binary tree takes its children's children: up to four children per
//! node, half the depth, and four boxes tested together per step of a query. Nodes are stored
//! depth-first (a node, then the subtrees of its children in order), so every subtree is a
//! contiguous run of nodes — which lets the box sweep recurse in parallel over disjoint slices.

use crate::search::node::{Child, EMPTY, Node, WIDTH, as_leaf, leaf};

/// Most facets per leaf: one group of eight lanes, or two of four (`search::lanes`; a leaf's count
/// has four bits).
pub const LEAF_SIZE: usize = 8;

/// Below this many leaves a range is split sequentially.
const PARALLEL_GRAIN: usize = 1 << 13;

/// A binary node: its two children.
type Binary = [Child; 2];

/// The four-wide tree over sorted `keys` cut into leaves at `starts` (the first key of each leaf,
/// then `keys.len()`; see `search::leaves`): the root reference and the internal nodes.
pub(crate) fn layout(keys: &[(u64, u32)], starts: &[u32]) -> (Child, Vec<Node>) {
    let Some(leaves) = starts.len().checked_sub(1).filter(|&n| n > 0) else {
        return (leaf(0, 0), Vec::new());
    };
    let tree = Leaves { keys, starts };
    let (root, binary) = split_range(&tree, 0, leaves);
    let mut nodes = Vec::with_capacity(binary.len() / 2 + 1);
    let root = collapse(&binary, root, &mut nodes);
    (root, nodes)
}

/// The leaves the tree is built over: leaf `r` holds `keys[starts[r]..starts[r + 1]]`.
struct Leaves<'a> {
    keys: &'a [(u64, u32)],
    starts: &'a [u32],
}

impl Leaves<'_> {
    /// The code of leaf `r`'s first facet.
    fn key(&self, r: usize) -> u64 {
        self.keys[self.starts[r] as usize].0
    }

    /// Where the leaves `lo..hi` (at least two) split: by the first codes of the leaves.
    fn split(&self, lo: usize, hi: usize) -> usize {
        split_at_bit(|r| self.key(r), lo, hi)
    }
}

/// The binary subtree over the leaves `lo..hi`: its reference and its nodes, depth-first, with
/// node indices relative to the first of them.
fn split_range(tree: &Leaves, lo: usize, hi: usize) -> (Child, Vec<Binary>) {
    if hi - lo <= PARALLEL_GRAIN {
        let mut nodes = Vec::with_capacity(2 * (hi - lo));
        let root = push_range(&mut nodes, tree, lo, hi);
        return (root, nodes);
    }
    let mid = tree.split(lo, hi);
    let ((lc, left), (rc, right)) =
        rayon::join(|| split_range(tree, lo, mid), || split_range(tree, mid, hi));
    let offset = index(1 + left.len());
    // Internal references are relative to their half's first node.
    let shift = |by: u32| move |c: Child| if as_leaf(c).is_some() { c } else { c + by };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    nodes.push([shift(1)(lc), shift(offset)(rc)]);
    nodes.extend(left.into_iter().map(|n| n.map(shift(1))));
    nodes.extend(right.into_iter().map(|n| n.map(shift(offset))));
    (0, nodes)
}

/// Appends the binary subtree over the leaves `lo..hi` to `nodes`; returns its reference.
fn push_range(nodes: &mut Vec<Binary>, tree: &Leaves, lo: usize, hi: usize) -> Child {
    if hi - lo == 1 {
        let (first, end) = (tree.starts[lo], tree.starts[lo + 1]);
        return leaf(first, end - first);
    }
    let at = nodes.len();
    nodes.push([EMPTY; 2]);
    let mid = tree.split(lo, hi);
    let left = push_range(nodes, tree, lo, mid);
    let right = push_range(nodes, tree, mid, hi);
    nodes[at] = [left, right];
    index(at)
}

/// Where the range `lo..hi` (at least two, sorted by `key`) splits: the first index whose key has
/// the highest differing bit of the range set, or the middle for identical keys.
pub(crate) fn split_at_bit(key: impl Fn(usize) -> u64, lo: usize, hi: usize) -> usize {
    let (first, last) = (key(lo), key(hi - 1));
    if first == last {
        return lo + (hi - lo) / 2;
    }
    let bit = 1u64 << (63 - (first ^ last).leading_zeros());
    let (mut a, mut b) = (lo, hi);
    while a < b {
        let m = a + (b - a) / 2;
        if key(m) & bit == 0 {
            a = m + 1;
        } else {
            b = m;
        }
    }
    a
}

/// Appends the four-wide version of the binary subtree `child` to `out`, depth-first; returns its
/// reference.
fn collapse(binary: &[Binary], child: Child, out: &mut Vec<Node>) -> Child {
    if as_leaf(child).is_some() {
        return child;
    }
    let mut children = [EMPTY; WIDTH];
    let mut n = 0;
    for c in binary[child as usize] {
        if as_leaf(c).is_some() {
            children[n] = c;
            n += 1;
        } else {
            for g in binary[c as usize] {
                children[n] = g;
                n += 1;
            }
        }
    }
    let at = out.len();
    out.push(Node::new([EMPTY; WIDTH]));
    for c in &mut children[..n] {
        *c = collapse(binary, *c, out);
    }
    out[at].child = children;
    index(at)
}

/// The number of internal nodes on the longest path down from `root`. Children are stored after
/// their parent, so one backward pass sees every child before its parent.
pub(crate) fn depth(nodes: &[Node], root: Child) -> usize {
    if as_leaf(root).is_some() {
        return 0;
    }
    let mut depth = vec![0usize; nodes.len()];
    for i in (0..nodes.len()).rev() {
        depth[i] = 1 + nodes[i]
            .child
            .iter()
            .filter(|&&c| as_leaf(c).is_none())
            .map(|&c| depth[c as usize])
            .max()
            .unwrap_or(0);
    }
    depth[root as usize]
}

/// Node and slot indices are `u32`; [`crate::search::Surface::new`] bounds the facet count to 2²⁷.
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
        let split = |keys: &[(u64, u32)], lo, hi| split_at_bit(|i| keys[i].0, lo, hi);
        assert_eq!(split(&keys, 0, 5), 2);
        assert_eq!(split(&keys, 2, 5), 3);
        let same = vec![(7u64, 0u32), (7, 1), (7, 2), (7, 3)];
        assert_eq!(split(&same, 0, 4), 2);
    }

    #[test]
    fn every_node_and_every_facet_is_reached_once_and_subtrees_are_contiguous() {
        // Large enough for the parallel top levels (PARALLEL_GRAIN).
        let mut keys: Vec<(u64, u32)> = (0..300_000u32)
            .map(|i| (u64::from(i).pow(2) % 99_991, i))
            .collect();
        keys.sort_unstable();
        // Leaves of seven, and a last shorter one.
        let starts: Vec<u32> = (0..keys.len())
            .step_by(7)
            .chain([keys.len()])
            .map(index)
            .collect();
        let (root, nodes) = layout(&keys, &starts);
        let mut seen = vec![0u8; keys.len()];
        let mut reached = vec![0u8; nodes.len()];
        let mut stack = vec![root];
        while let Some(c) = stack.pop() {
            match as_leaf(c) {
                Some((first, count)) => {
                    assert!(count <= LEAF_SIZE);
                    seen[first..first + count].iter_mut().for_each(|s| *s += 1);
                }
                None => {
                    reached[c as usize] += 1;
                    let node = &nodes[c as usize];
                    // Internal children follow their parent, in increasing order.
                    let internal: Vec<u32> = node
                        .child
                        .iter()
                        .copied()
                        .filter(|&g| as_leaf(g).is_none())
                        .collect();
                    assert!(internal.windows(2).all(|w| w[0] < w[1]));
                    assert!(internal.first().is_none_or(|&g| g == c + 1));
                    stack.extend(node.child);
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        assert!(reached.iter().all(|&r| r == 1));
        // The depth bounds the traversal stack: at least log₄ of the leaf count.
        let d = depth(&nodes, root);
        assert!((8..40).contains(&d), "depth {d}");
        assert_eq!(depth(&nodes, leaf(0, 3)), 0);
        // Every node has at least two children; the collapse gives many four (the others sit
        // above leaves).
        let used = |n: &Node| n.child.iter().filter(|&&c| c != EMPTY).count();
        assert!(nodes.iter().all(|n| used(n) >= 2));
        let four = nodes.iter().filter(|n| used(n) == 4).count();
        assert!(
            four * 4 > nodes.len(),
            "{four} of {} nodes have four children",
            nodes.len()
        );
    }
}
