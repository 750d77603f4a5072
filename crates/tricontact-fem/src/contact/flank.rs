//! Penetration of the flank across a concave edge: what one constraint per node leaves unheld.
//!
//! A slave node is constrained against one facet `F` (its plane `P_F`). Where `F` meets a
//! neighbouring facet `G` at a concave edge or corner (a valley, the floor and wall of a corner),
//! the master body is the union of the two half-spaces behind `F` and `G`, and a node held on
//! `F`'s plane may still lie behind `G`, with `P_G < 0`, its foot in `G` or near it (within
//! [`LOST_TOLERANCE`], as for a node that left its facet: in a corner a node can be behind both
//! flanks and project into neither). This module measures that depth, `−P_G`, for the reports
//! (`_max_penetration`, the run's summary); it enforces nothing (a second constraint per node at
//! concave kinks was measured and not kept: see `contact/mod.rs`).
//!
//! The candidates `G` are the facets near the node (the two flanks need not share nodes: a wall
//! meshed apart from its floor), within twice `F`'s longest edge plus the node's gap. `F` and
//! `G` are taken as concave when the corners of each that the other does not share all lie in
//! front of the other's plane, at least one by more than `10⁻⁹` of `F`'s longest edge (so every
//! point of each is in front of the other): on a flat, convex or saddle-shaped surface `G` is
//! never counted, so a node inside the body near a ridge, which projects into both flanks,
//! reports only its constrained gap, and a node outside below a thin plate is not taken as
//! behind the plate's far side.

use super::LOST_TOLERANCE;
use tricontact::search::{Bvh, Query, Surface};
use tricontact::{NodeFacet, Vec3};

/// The largest `−P_G` over the facets `G` near node `s` (within twice `facet`'s size plus the
/// node's gap, and within `radius`), concave to `facet`, that the node lies behind with its foot
/// within [`LOST_TOLERANCE`] of `G`, at positions `x` (`bvh` built on them); `0` when there is
/// none.
#[must_use]
pub fn flank_penetration(
    surface: &Surface,
    bvh: &Bvh,
    x: &[Vec3],
    (s, facet): (usize, u32),
    radius: f64,
) -> f64 {
    let nodes = |f: u32| surface.facets()[f as usize];
    let pair_with = |f: u32| {
        let [a, b, c] = surface.corners(f, x);
        NodeFacet::new(a, b, c, x[s]).ok()
    };
    let Some(f_pair) = pair_with(facet) else {
        return 0.0;
    };
    let f_nodes = nodes(facet);
    let margin = 1e-9 * f_pair.facet.size();
    // The corners of `other` not shared with `own` lie in front of `own`'s plane (within the
    // margin), at least one beyond it: the whole of `other` is in front of `own`.
    let rises = |pair: &NodeFacet, own: &[u32; 3], other: &[u32; 3]| {
        let heights = other
            .iter()
            .filter(|a| !own.contains(a))
            .map(|&a| (x[a as usize] - pair.facet.nodes()[0]).dot(&pair.facet.normal()));
        let (low, high) = heights.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), z| {
            (l.min(z), h.max(z))
        });
        low >= -margin && high > margin
    };
    let reach = (2.0 * f_pair.facet.size() + f_pair.gap().abs()).min(radius);
    let query = Query {
        point: x[s],
        exclude: u32::try_from(s).ok(),
    };
    let mut deepest = 0.0f64;
    for hit in bvh.within(surface, &query, reach) {
        let g = hit.facet;
        if g == facet {
            continue;
        }
        let Some(g_pair) = pair_with(g) else {
            continue;
        };
        let behind = g_pair.gap() < 0.0 && g_pair.projection.is_inside(LOST_TOLERANCE);
        let g_nodes = nodes(g);
        if behind && rises(&f_pair, &f_nodes, &g_nodes) && rises(&g_pair, &g_nodes, &f_nodes) {
            deepest = deepest.max(-g_pair.gap());
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two strips of two facets meeting at `x = 0`, `z = sign · |x| / 2` (a valley for `+1`, a
    /// ridge for `−1`, flat for `0`), normals up; facets 0–1 on the left, 2–3 on the right.
    fn profile(sign: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut x = Vec::new();
        for y in [0.0, 1.0] {
            for xx in [-1.0f64, 0.0, 1.0] {
                x.push(Vec3::new(xx, y, sign * xx.abs() / 2.0));
            }
        }
        let facets = vec![[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]];
        (x, facets)
    }

    /// The depth of `node`, held on facet `f`, behind another facet of `facets`.
    fn depth(mut x: Vec<Vec3>, facets: Vec<[u32; 3]>, node: Vec3, f: u32) -> f64 {
        x.push(node);
        let s = x.len() - 1;
        let surface = Surface::new(facets, x.len()).expect("surface");
        let bvh = Bvh::build(&surface, &x, 1.0).expect("tree");
        flank_penetration(&surface, &bvh, &x, (s, f), 1.0)
    }

    #[test]
    fn a_node_held_on_a_flank_past_a_valley_is_behind_the_other() {
        // On the left flank's plane z = −x/2, extended 0.05 past the valley line.
        let (x, facets) = profile(1.0);
        let d = depth(x, facets, Vec3::new(0.05, 0.5, -0.025), 0);
        let expected = 0.05 / 1.25f64.sqrt();
        assert!((d - expected).abs() < 1e-12, "{d} against {expected}");
        // On its own side of the valley line a node on the flank is in front of the other.
        let (x, facets) = profile(1.0);
        assert_eq!(depth(x, facets, Vec3::new(-0.05, 0.5, 0.025), 0), 0.0);
    }

    #[test]
    fn ridges_and_flat_surfaces_report_nothing() {
        // Inside near a ridge, on the left flank's plane: behind the right flank's plane too,
        // but the edge is convex.
        let (x, facets) = profile(-1.0);
        assert_eq!(depth(x, facets, Vec3::new(-0.05, 0.5, -0.025), 0), 0.0);
        let (x, facets) = profile(0.0);
        assert_eq!(depth(x, facets, Vec3::new(0.3, 0.5, -0.01), 2), 0.0);
    }

    /// A floor and a wall meshed apart (no shared node), as a corner: a node constrained by the
    /// floor, 0.01 into the wall and 0.02 below the floor, projects into neither (its foot on the
    /// wall is 0.02 below it, within the tolerance) and is 0.01 behind the wall.
    #[test]
    fn a_corner_of_separate_pieces_is_seen() {
        let x = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        // Floor normal +z; wall (nodes 4–7, apart from the floor's) normal +x.
        let facets = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        let d = depth(x, facets, Vec3::new(-0.01, 0.5, -0.02), 0);
        assert!((d - 0.01).abs() < 1e-12, "{d}");
    }

    /// Two facets sharing one node, one rising across the other's plane and one sinking (a
    /// saddle): neither lies wholly in front of the other, so a node on the first, near the
    /// shared node and behind the second's plane, is not counted.
    #[test]
    fn a_saddle_is_not_a_concave_corner() {
        let x = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-1.0, 0.0, 0.3),
            Vec3::new(0.0, -1.0, -0.3),
        ];
        // F = [0, 1, 2] in z = 0; G = [0, 3, 4] tilted: node 3 above F's plane, node 4 below.
        let facets = vec![[0, 1, 2], [0, 3, 4]];
        // Behind G's plane (its normal is along (0.3, −0.3, 1)), its foot within 0.1 of G.
        for node in [Vec3::new(0.01, 0.05, 0.0), Vec3::new(0.02, 0.06, -1e-4)] {
            assert_eq!(depth(x.clone(), facets.clone(), node, 0), 0.0, "{node:?}");
        }
    }

    /// A thin plate (top and bottom 0.01 apart, normals out): a node outside, just below the
    /// bottom facet it is constrained by, lies behind the top's plane, but the top is behind
    /// the bottom (not concave to it), so it is not counted.
    #[test]
    fn a_node_below_a_thin_plate_is_not_behind_its_top() {
        let x = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 0.01),
            Vec3::new(1.0, 0.0, 0.01),
            Vec3::new(0.0, 1.0, 0.01),
        ];
        // Bottom [0, 2, 1] (normal −z), top [3, 4, 5] (normal +z).
        let facets = vec![[0, 2, 1], [3, 4, 5]];
        assert_eq!(depth(x, facets, Vec3::new(0.2, 0.2, -0.001), 0), 0.0);
    }
}
