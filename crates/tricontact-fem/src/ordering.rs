//! Geometric nested-dissection ordering of the equations.
//!
//! The node set is split recursively at the coordinate median along its
//! longest bounding-box axis into halves `L` and `R`; the nodes of `L` with
//! a neighbour in `R` form the separator `S`. The order is
//! `ND(L \ S), ND(R), S` — separators last — down to blocks of at most
//! 64 nodes, which keep their input order. Equations follow their nodes
//! (free components in order); an extra unknown that belongs to a node (a
//! contact multiplier, to its slave node) follows the block (leaf or
//! separator) of that node (those marked late, a node's mostly inactive second
//! multiplier, after the block's others), the others come last. For 3D meshes this gives
//! far less Cholesky fill than minimum degree.
//!
//! A multiplier after its slave node keeps the saddle-point system
//! factorable by `LDLᵀ` without pivoting: when it is eliminated, the
//! displacements it constrains at that node already are, so its pivot is
//! `−bᵀK̃⁻¹b < 0` with `K̃` their (positive definite) Schur complement (for a
//! node's second multiplier, at a concave kink of the master, the pivot is
//! `−(b₂ᵀK̃⁻¹b₂ − (b₁ᵀK̃⁻¹b₂)²/b₁ᵀK̃⁻¹b₁)`, negative while the two rows are
//! independent); and it keeps the fill local. With all multipliers last, their Schur complement
//! `−B K⁻¹ Bᵀ` is a dense block of the size of the slave surface. Each
//! multiplier right after its own node instead splits the factor's
//! supernodes: measured 2.3× slower than multipliers last on the fine Hertz
//! mesh (1 089 multipliers); after their node's block, see the README.

use crate::assembly::{DofMap, NO_EQ};

const LEAF: usize = 64;

/// Nested-dissection order of `nodes` (each listed once) given coordinates
/// and node adjacency.
#[must_use]
pub fn nested_dissection(coords: &[[f64; 3]], adj: &[Vec<usize>], nodes: Vec<usize>) -> Vec<usize> {
    dissection_blocks(coords, adj, nodes).0
}

/// [`nested_dissection`] with the end of each block in the order (a leaf or a
/// separator), increasing, the last one the order's length.
fn dissection_blocks(
    coords: &[[f64; 3]],
    adj: &[Vec<usize>],
    nodes: Vec<usize>,
) -> (Vec<usize>, Vec<usize>) {
    let mut side = vec![0u8; coords.len()];
    let mut out = Vec::with_capacity(nodes.len());
    let mut ends = Vec::new();
    dissect(coords, adj, nodes, &mut side, (&mut out, &mut ends));
    (out, ends)
}

/// Appends a block of nodes to the order and records its end.
fn block(out: &mut Vec<usize>, ends: &mut Vec<usize>, nodes: &[usize]) {
    if !nodes.is_empty() {
        out.extend_from_slice(nodes);
        ends.push(out.len());
    }
}

fn dissect(
    coords: &[[f64; 3]],
    adj: &[Vec<usize>],
    mut nodes: Vec<usize>,
    side: &mut [u8],
    (out, ends): (&mut Vec<usize>, &mut Vec<usize>),
) {
    if nodes.len() <= LEAF {
        block(out, ends, &nodes);
        return;
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &a in &nodes {
        for i in 0..3 {
            lo[i] = lo[i].min(coords[a][i]);
            hi[i] = hi[i].max(coords[a][i]);
        }
    }
    let axis = (0..3)
        .max_by(|&i, &j| (hi[i] - lo[i]).total_cmp(&(hi[j] - lo[j])))
        .unwrap_or(0);
    let mid = nodes.len() / 2;
    nodes.select_nth_unstable_by(mid, |&a, &b| coords[a][axis].total_cmp(&coords[b][axis]));
    let right = nodes.split_off(mid);
    for &a in &right {
        side[a] = 2;
    }
    let (sep, left): (Vec<usize>, Vec<usize>) = nodes
        .into_iter()
        .partition(|&a| adj[a].iter().any(|&b| side[b] == 2));
    for &a in &right {
        side[a] = 0;
    }
    if left.is_empty() {
        // Degenerate split (e.g. all nodes coincide on the axis): stop here.
        block(out, ends, &right);
        block(out, ends, &sep);
        return;
    }
    dissect(coords, adj, left, side, (&mut *out, &mut *ends));
    dissect(coords, adj, right, side, (&mut *out, &mut *ends));
    block(out, ends, &sep);
}

/// Equation permutation `new → old` from a nested dissection of the nodes
/// that carry equations (`adj` is the node adjacency of the body elements).
/// `owners[k]` is the node extra unknown `k` belongs to: its equation follows
/// the block (leaf or separator) of that node, or comes last when it has none
/// (`None`, a node without equations, or `owners` shorter than the extra
/// unknowns). Within a block, the extras follow their nodes' order, those
/// marked `late[k]` after all the others (a node's second contact multiplier,
/// mostly inactive, a lone diagonal: between the others it split the factor's
/// supernodes).
#[must_use]
pub fn equation_order(
    coords: &[[f64; 3]],
    adj: &[Vec<usize>],
    dm: &DofMap,
    (owners, late): (&[Option<usize>], &[bool]),
) -> Vec<usize> {
    let has_eq = |a: usize| (0..3).any(|i| dm.eq[3 * a + i] != NO_EQ);
    let nodes: Vec<usize> = (0..coords.len()).filter(|&a| has_eq(a)).collect();
    // Per node, its extras: those of the block's first run, and the late ones.
    let mut owned: Vec<[Vec<usize>; 2]> = vec![[Vec::new(), Vec::new()]; coords.len()];
    let mut last = Vec::new();
    for d in dm.n_nodal..dm.eq.len() {
        let e = dm.eq[d];
        if e == NO_EQ {
            continue;
        }
        let k = d - dm.n_nodal;
        match owners.get(k).copied().flatten() {
            Some(a) if a < coords.len() && has_eq(a) => {
                owned[a][usize::from(late.get(k).copied().unwrap_or(false))].push(e);
            }
            _ => last.push(e),
        }
    }
    let (order, ends) = dissection_blocks(coords, adj, nodes);
    let mut perm = Vec::with_capacity(dm.n_eq);
    let mut start = 0;
    for end in ends {
        let nodes = &order[start..end];
        for &a in nodes {
            perm.extend((0..3).map(|i| dm.eq[3 * a + i]).filter(|&e| e != NO_EQ));
        }
        for run in 0..2 {
            for &a in nodes {
                perm.extend_from_slice(&owned[a][run]);
            }
        }
        start = end;
    }
    perm.extend(last);
    perm
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extra_unknowns_follow_their_nodes_block_or_come_last() {
        // 300 nodes on a line; node 150 fully prescribed, node 3's z prescribed.
        let n = 300;
        let coords: Vec<[f64; 3]> = (0..n).map(|k| [k as f64, 0.0, 0.0]).collect();
        let adj: Vec<Vec<usize>> = (0..n)
            .map(|k: usize| (k.saturating_sub(1)..(k + 2).min(n)).collect())
            .collect();
        let mut prescribed = vec![false; 3 * n];
        prescribed[450..453].fill(true);
        prescribed[11] = true;
        // Extras: one per tenth node (0, 10, …, 290, 150 among them), one of none, one more
        // that `owners` does not list.
        let owners: Vec<Option<usize>> = (0..n / 10).map(|k| Some(10 * k)).chain([None]).collect();
        let dm = DofMap::new(&vec![true; n], &prescribed, owners.len() + 1);
        let perm = equation_order(&coords, &adj, &dm, (&owners, &[]));
        let mut sorted = perm.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..dm.n_eq).collect::<Vec<_>>());
        let at = |e: usize| perm.iter().position(|&p| p == e).expect("ordered");
        let extra = |k: usize| dm.eq[3 * n + k];
        for (k, owner) in owners.iter().enumerate() {
            let Some(a) = *owner else { continue };
            if a == 150 {
                continue;
            }
            // After its node, within a block of at most `LEAF` nodes and their extras.
            let node = at(dm.eq[3 * a + 1]);
            assert!(at(extra(k)) > node, "extra {k}");
            assert!(at(extra(k)) - node <= 3 * LEAF + LEAF / 10 + 1, "extra {k}");
        }
        // Extras of a node without equations, of none, or unlisted: last, in their order.
        let last: Vec<usize> = [15, 30, 31].iter().map(|&k| extra(k)).collect();
        assert_eq!(&perm[perm.len() - 3..], &last[..]);
        // Nothing owned: all extras last.
        let plain = equation_order(&coords, &adj, &dm, (&[], &[]));
        let all: Vec<usize> = (0..=31).map(extra).collect();
        assert_eq!(&plain[plain.len() - 32..], &all[..]);
    }

    /// Two extra unknowns per node (a contact multiplier and a second one for a second flank),
    /// the second ones marked late: in each block the nodes' first extras, in the nodes' order,
    /// then their second ones, so that the mostly inactive second ones (a lone diagonal) do not
    /// split the first ones' supernodes (measured: `fem-bench --contact 80` took 22.6 s with
    /// each node's two together, 9.2–9.6 s so, 9.5–9.9 s with one extra per node).
    #[test]
    fn a_blocks_late_extras_follow_all_its_others() {
        let n = 300;
        let coords: Vec<[f64; 3]> = (0..n).map(|k| [k as f64, 0.0, 0.0]).collect();
        let adj: Vec<Vec<usize>> = (0..n)
            .map(|k: usize| (k.saturating_sub(1)..(k + 2).min(n)).collect())
            .collect();
        // Every node owns extra `a` and extra `n + a`.
        let owners: Vec<Option<usize>> = (0..2 * n).map(|k| Some(k % n)).collect();
        let late: Vec<bool> = (0..2 * n).map(|k| k >= n).collect();
        let dm = DofMap::new(&vec![true; n], &vec![false; 3 * n], owners.len());
        let perm = equation_order(&coords, &adj, &dm, (&owners, &late));
        let extra = |k: usize| dm.eq[3 * n + k];
        let is_node = |e: usize| e < 3 * n;
        // Runs of extras between blocks of node equations: the first extras of the run's
        // nodes, then the same nodes' second ones, in the same order.
        let mut runs = 0;
        let mut k = 0;
        while k < perm.len() {
            if is_node(perm[k]) {
                k += 1;
                continue;
            }
            let end = (k..perm.len())
                .find(|&i| is_node(perm[i]))
                .unwrap_or(perm.len());
            let run = &perm[k..end];
            let (first, second) = run.split_at(run.len() / 2);
            let owner = |e: &usize| (e - 3 * n) % n;
            assert!(first.iter().all(|e| e - 3 * n < n), "{run:?}");
            assert!(
                first.iter().map(owner).eq(second.iter().map(owner)),
                "{run:?}"
            );
            assert!(second.iter().all(|&e| e == extra(owner(&e) + n)));
            runs += 1;
            k = end;
        }
        assert!(runs > 1, "{runs} blocks");
        // None marked late: each node's extras together, in their order.
        let together = equation_order(&coords, &adj, &dm, (&owners, &[]));
        let at = |e: usize| together.iter().position(|&p| p == e).expect("ordered");
        for a in 0..n {
            assert_eq!(at(extra(a)) + 1, at(extra(n + a)), "node {a}");
        }
    }

    #[test]
    fn is_a_permutation_with_separators_last() {
        // 20 × 20 grid graph.
        let n = 20;
        let coords: Vec<[f64; 3]> = (0..n * n)
            .map(|k| [(k % n) as f64, (k / n) as f64, 0.0])
            .collect();
        let adj: Vec<Vec<usize>> = (0..n * n)
            .map(|k| {
                let (i, j) = (k % n, k / n);
                let mut v = vec![k];
                if i > 0 {
                    v.push(k - 1);
                }
                if i + 1 < n {
                    v.push(k + 1);
                }
                if j > 0 {
                    v.push(k - n);
                }
                if j + 1 < n {
                    v.push(k + n);
                }
                v
            })
            .collect();
        let order = nested_dissection(&coords, &adj, (0..n * n).collect());
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n * n).collect::<Vec<_>>());
        // The top separator is the middle grid line (x = 9 or y = 9, the
        // lower half's boundary), ordered last.
        let last: Vec<usize> = order[order.len() - n..].to_vec();
        assert!(
            last.iter().all(|&k| k % n == 9) || last.iter().all(|&k| k / n == 9),
            "{last:?}"
        );
    }
}
