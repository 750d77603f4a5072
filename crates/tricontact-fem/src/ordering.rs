//! Geometric nested-dissection ordering of the equations.
//!
//! The node set is split recursively at the coordinate median along its
//! longest bounding-box axis into halves `L` and `R`; the nodes of `L` with
//! a neighbour in `R` form the separator `S`. The order is
//! `ND(L \ S), ND(R), S` — separators last — down to blocks of at most
//! 64 nodes, which keep their input order. Equations follow their nodes
//! (free components in order), extra unknowns come last. For 3D meshes this
//! gives far less Cholesky fill than minimum degree.

use crate::assembly::{DofMap, NO_EQ};

const LEAF: usize = 64;

/// Nested-dissection order of `nodes` (each listed once) given coordinates
/// and node adjacency.
#[must_use]
pub fn nested_dissection(coords: &[[f64; 3]], adj: &[Vec<usize>], nodes: Vec<usize>) -> Vec<usize> {
    let mut side = vec![0u8; coords.len()];
    let mut out = Vec::with_capacity(nodes.len());
    dissect(coords, adj, nodes, &mut side, &mut out);
    out
}

fn dissect(
    coords: &[[f64; 3]],
    adj: &[Vec<usize>],
    mut nodes: Vec<usize>,
    side: &mut [u8],
    out: &mut Vec<usize>,
) {
    if nodes.len() <= LEAF {
        out.extend_from_slice(&nodes);
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
        out.extend_from_slice(&right);
        out.extend_from_slice(&sep);
        return;
    }
    dissect(coords, adj, left, side, out);
    dissect(coords, adj, right, side, out);
    out.extend_from_slice(&sep);
}

/// Equation permutation `new → old` from a nested dissection of the nodes
/// that carry equations (`adj` is the node adjacency of the body elements).
#[must_use]
pub fn equation_order(coords: &[[f64; 3]], adj: &[Vec<usize>], dm: &DofMap) -> Vec<usize> {
    let nodes: Vec<usize> = (0..coords.len())
        .filter(|&a| (0..3).any(|i| dm.eq[3 * a + i] != NO_EQ))
        .collect();
    let order = nested_dissection(coords, adj, nodes);
    let mut perm = Vec::with_capacity(dm.n_eq);
    for a in order {
        for i in 0..3 {
            let e = dm.eq[3 * a + i];
            if e != NO_EQ {
                perm.push(e);
            }
        }
    }
    for d in dm.n_nodal..dm.eq.len() {
        if dm.eq[d] != NO_EQ {
            perm.push(dm.eq[d]);
        }
    }
    perm
}

#[cfg(test)]
mod tests {
    use super::*;

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
