//! Concave edges and corners of the master: the flank across the kink, which one constraint per
//! node leaves unheld.
//!
//! A slave node is constrained against one facet `F` (its plane `P_F`). Where `F` meets a
//! neighbouring facet `G` at a concave edge or corner (a valley, the floor and wall of a corner),
//! the master body is the union of the two half-spaces behind `F` and `G`, and a node held on
//! `F`'s plane may still lie behind `G`, with `P_G < 0`, its foot in `G` or near it (within
//! [`LOST_TOLERANCE`], as for a node that left its facet: in a corner a node can be behind both
//! flanks and project into neither). Near the kink, keeping the node out of that union takes both
//! constraints, `P_F ≥ 0` and `P_G ≥ 0`.
//!
//! The candidates `G` are the facets near the node, within twice `F`'s longest edge plus the
//! node's gap and within the search distance (the two flanks need not share nodes: a wall
//! meshed apart from its floor), concave to `F` (below), whose projection region the node is
//! near (within [`LOST_TOLERANCE`]).
//! * [`second_flank`] gives the facet of the second constraint, which every method enforces
//!   beside the first with finite sliding (see `contact/mod.rs`): among the candidates
//!   with a kink (the angle between the normals) of at least [`ENFORCED_KINK_DEGREES`], the one
//!   with the smallest `P_G` (with a hysteresis among tied ones). Below that kink, where a smooth
//!   curved master's facets meet, the one constraint serves, as before. One second constraint at
//!   most.
//! * [`flank_penetration`] measures, for the reports (`_max_penetration`, the run's summary), the
//!   deepest `−P_G` over the candidates the node is behind, whatever the kink, enforced or not.
//!
//! `F` and `G` are taken as concave when the corners of each that the other does not share all
//! lie in front of the other's plane, at least one by more than `10⁻⁹` of `F`'s longest edge
//! (round-off), none behind it by more than `10⁻³` of it (so every point of each is in front of
//! the other, but for that margin: the corner nodes of a wall meshed apart from its floor, which
//! start on the floor's plane, move off it as the parts deform; with `10⁻⁹` there too a node in
//! such a corner lost and regained its second constraint from one iteration to the next, and
//! Newton cycled): on a flat, convex or saddle-shaped surface `G` is never counted, so a node
//! inside the body near a ridge, which projects into both flanks, has only its own constraint,
//! and a node outside below a thin plate is not taken as behind the plate's far side.

use super::LOST_TOLERANCE;
use tricontact::search::{Bvh, Query, Surface};
use tricontact::{NodeFacet, Vec3};

/// The smallest kink, the angle between the normals of two concave facets, at which
/// [`second_flank`] enforces the second one. At 15° the V-groove of `examples/v-groove` (a kink
/// of 53°) converges with each method, and every other example's
/// solution is unchanged; an earlier trial that took every concave neighbour (0°, or 5°) made runs
/// that converge fail, the nearly flat kinks of a finely meshed curved surface counting (the
/// README's "Concave edges and corners").
pub const ENFORCED_KINK_DEGREES: f64 = 15.0;

/// `own`'s pair (its facet at the node) and its nodes, with those of `other`: every corner of
/// `other` not shared with `own` lies in front of `own`'s plane or behind it by at most `behind`,
/// and one lies in front by more than `ahead`: the whole of `other` is in front of `own`, but
/// for `behind`.
fn in_front(
    x: &[Vec3],
    (pair, own): (&NodeFacet, &[u32; 3]),
    other: &[u32; 3],
    (behind, ahead): (f64, f64),
) -> bool {
    let heights = other
        .iter()
        .filter(|a| !own.contains(a))
        .map(|&a| (x[a as usize] - pair.facet.nodes()[0]).dot(&pair.facet.normal()));
    let (low, high) = heights.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), z| {
        (l.min(z), h.max(z))
    });
    low >= -behind && high > ahead
}

/// `true` when `F` and `G` (their pairs at the node and their nodes) are concave to each other:
/// each lies wholly in front of the other's plane but for `10⁻³` of `F`'s longest edge, with a
/// corner in front by more than `10⁻⁹` of it.
fn concave(x: &[Vec3], f: (&NodeFacet, &[u32; 3]), g: (&NodeFacet, &[u32; 3])) -> bool {
    let size = f.0.facet.size();
    let margins = (1e-3 * size, 1e-9 * size);
    in_front(x, f, g.1, margins) && in_front(x, g, f.1, margins)
}

/// The facets `G` concave to node `s`'s facet `facet` near it (within twice `facet`'s longest
/// edge plus the node's gap, and within `radius`), with the node's pair on each and the cosine
/// of the kink (`W_F·W_G`), at positions `x` (`bvh` built on them). Facets containing the node
/// are left out (self-contact), and, with self-contact (`facing` the outward normal of the node's
/// own surface), those that do not face it ([`tricontact::contact::faces`]).
fn concave_neighbours<'a>(
    surface: &'a Surface,
    bvh: &'a Bvh,
    x: &'a [Vec3],
    (s, facet): (usize, u32),
    (radius, facing): (f64, Option<Vec3>),
) -> impl Iterator<Item = (u32, NodeFacet, f64)> + 'a {
    let pair_with = move |f: u32| {
        let [a, b, c] = surface.corners(f, x);
        NodeFacet::new(a, b, c, x[s]).ok()
    };
    let own = pair_with(facet).map(|pair| (pair, surface.facets()[facet as usize]));
    let hits = own.as_ref().map_or_else(Vec::new, |(pair, _)| {
        let reach = (2.0 * pair.facet.size() + pair.gap().abs()).min(radius);
        let query = Query {
            point: x[s],
            exclude: u32::try_from(s).ok(),
        };
        bvh.within(surface, &query, reach)
    });
    hits.into_iter().filter_map(move |hit| {
        let (f_pair, f_nodes) = own.as_ref()?;
        let g = hit.facet;
        if g == facet {
            return None;
        }
        let g_pair = pair_with(g)?;
        if facing.is_some_and(|n| !tricontact::contact::faces(&g_pair.facet.normal(), &n)) {
            return None;
        }
        let g_nodes = surface.facets()[g as usize];
        concave(x, (f_pair, f_nodes), (&g_pair, &g_nodes))
            .then(|| (g, g_pair, f_pair.facet.normal().dot(&g_pair.facet.normal())))
    })
}

/// Where the node's previous second flank is, how near (as a gap) another must come to displace
/// it: the previous flank, when it is still a candidate within `tolerance` of the smallest gap.
#[derive(Clone, Copy, Debug)]
pub struct Hysteresis {
    /// The facet of the node's second constraint at the previous evaluation.
    pub previous: Option<u32>,
    /// A gap (a length): candidates within it of the smallest gap count as tied.
    pub tolerance: f64,
}

/// The facet of node `s`'s second constraint, with its pair at `x`, where the node's own facet
/// is `facet` (see the module documentation): among the facets concave to `facet` near the node
/// (as [`flank_penetration`] takes them) with a kink of at least [`ENFORCED_KINK_DEGREES`], whose
/// projection the node is within [`LOST_TOLERANCE`] of, those with the smallest gap `P_G`
/// within `hysteresis.tolerance`; of these the previous second flank if it is one, else the one
/// the node projects deepest into (the largest smallest barycentric coordinate: coplanar facets
/// of the far flank have the same gap, and round-off must not choose among them, since `∇²P`
/// differs from facet to facet), ties to the lowest index. Open or not: the method decides
/// whether it closes. `None` when there is none. One second constraint at most: in a corner of
/// three concave planes (a floor and two walls) the third is not held, only measured.
#[must_use]
pub fn second_flank(
    surface: &Surface,
    bvh: &Bvh,
    x: &[Vec3],
    (s, facet): (usize, u32),
    (radius, hysteresis, facing): (f64, Hysteresis, Option<Vec3>),
) -> Option<(u32, NodeFacet)> {
    let cos_kink = ENFORCED_KINK_DEGREES.to_radians().cos();
    let candidates: Vec<(u32, NodeFacet)> =
        concave_neighbours(surface, bvh, x, (s, facet), (radius, facing))
            .filter(|(_, pair, cos)| *cos <= cos_kink && pair.projection.is_inside(LOST_TOLERANCE))
            .map(|(g, pair, _)| (g, pair))
            .collect();
    let smallest = candidates
        .iter()
        .map(|(_, pair)| pair.gap())
        .fold(f64::INFINITY, f64::min);
    let tied = candidates
        .into_iter()
        .filter(|(_, pair)| pair.gap() <= smallest + hysteresis.tolerance);
    let inside = |pair: &NodeFacet| {
        pair.projection
            .shape
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    };
    // Ordered: the previous second flank first, then the deepest inside, then the lowest index.
    tied.min_by(|(f, a), (g, b)| {
        let other = |h: &u32| Some(*h) != hysteresis.previous;
        other(f)
            .cmp(&other(g))
            .then(inside(b).total_cmp(&inside(a)))
            .then(f.cmp(g))
    })
}

/// The largest `−P_G` over the facets `G` near node `s` (within twice `facet`'s size plus the
/// node's gap, and within `radius`), concave to `facet`, that the node lies behind with its foot
/// within [`LOST_TOLERANCE`] of `G`, at positions `x` (`bvh` built on them); `0` when there is
/// none. With self-contact (`facing` the outward normal of the node's own surface), only facets
/// that face it count.
#[must_use]
pub fn flank_penetration(
    surface: &Surface,
    bvh: &Bvh,
    x: &[Vec3],
    (s, facet): (usize, u32),
    (radius, facing): (f64, Option<Vec3>),
) -> f64 {
    concave_neighbours(surface, bvh, x, (s, facet), (radius, facing))
        .filter(|(_, pair, _)| pair.gap() < 0.0 && pair.projection.is_inside(LOST_TOLERANCE))
        .fold(0.0f64, |deepest, (_, pair, _)| deepest.max(-pair.gap()))
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
        flank_penetration(&surface, &bvh, &x, (s, f), (1.0, None))
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

    /// The second flank of `node` on facet `f` of `facets`, at `x`.
    fn second(mut x: Vec<Vec3>, facets: Vec<[u32; 3]>, node: Vec3, f: u32) -> Option<u32> {
        x.push(node);
        let s = x.len() - 1;
        let surface = Surface::new(facets, x.len()).expect("surface");
        let bvh = Bvh::build(&surface, &x, 1.0).expect("tree");
        let none = Hysteresis {
            previous: None,
            tolerance: 0.0,
        };
        second_flank(&surface, &bvh, &x, (s, f), (1.0, none, None)).map(|(g, pair)| {
            let [a, b, c] = surface.corners(g, &x);
            let direct = NodeFacet::new(a, b, c, node).expect("pair");
            assert_eq!(pair.gap(), direct.gap());
            g
        })
    }

    #[test]
    fn the_second_flank_is_the_deepest_concave_neighbour_beyond_the_kink() {
        // Below the valley line (x = 0, z = 0) between the flanks z = |x|/2, on the left flank
        // (facet 0): behind both, its foot on the right flank's plane 0.016 past the line, within
        // 0.1 of facet 3 (facet 2, in the same plane, lies far from the foot).
        let (x, facets) = profile(1.0);
        let node = Vec3::new(-0.01, 0.5, -0.02);
        assert_eq!(second(x.clone(), facets.clone(), node, 0), Some(3));
        // High on the left flank, 0.01 below it: in front of the right flank's plane, its foot
        // there 0.36 past the line: none.
        assert_eq!(
            second(x.clone(), facets.clone(), Vec3::new(-0.6, 0.5, 0.29), 0),
            None
        );
        // A ridge, a flat surface and a kink of 5.7° (slopes ±0.05): none.
        for sign in [-1.0, 0.0, 0.1] {
            let (x, facets) = profile(sign);
            let below = Vec3::new(-0.01, 0.5, -0.02);
            assert_eq!(second(x, facets, below, 0), None, "profile {sign}");
        }
    }

    /// The valley of [`profile`] with slopes `±t` (a kink of `2 atan t`), a node on its left
    /// flank just past the valley line, behind both: its second flank, if any.
    fn second_at_slope(t: f64) -> Option<u32> {
        let (mut x, facets) = profile(1.0);
        for p in &mut x {
            p.z = t * p.x.abs();
        }
        second(x, facets, Vec3::new(0.01, 0.5, -0.02), 0)
    }

    #[test]
    fn the_second_flank_needs_a_kink_of_fifteen_degrees() {
        let slope = |degrees: f64| (degrees.to_radians() / 2.0).tan();
        assert_eq!(second_at_slope(slope(14.0)), None);
        assert_eq!(second_at_slope(slope(16.0)), Some(3));
    }

    /// A floor `F` (in `z = 0`) and a wall `G` rising at 45° from its edge `x = 0`, meshed
    /// apart, the wall's corner at `(0, 1)` moved `behind` below the floor's plane (as the corner
    /// nodes of parts meshed apart move as they deform): concave while that is within `10⁻³` of
    /// the floor's size (√2).
    #[test]
    fn a_corner_slightly_behind_the_other_plane_still_counts_as_concave() {
        let concave_with = |behind: f64| {
            let x = vec![
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(1.0, 0.5, 1.0),
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, -behind),
            ];
            let (floor, wall) = ([0u32, 1, 2], [4u32, 3, 5]);
            let pair = |f: [u32; 3]| {
                let [a, b, c] = f.map(|n| x[n as usize]);
                NodeFacet::new(a, b, c, Vec3::new(-0.1, 0.4, 0.5)).expect("pair")
            };
            concave(&x, (&pair(floor), &floor), (&pair(wall), &wall))
        };
        assert!(concave_with(0.0));
        assert!(concave_with(1e-3));
        assert!(!concave_with(2e-3));
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
