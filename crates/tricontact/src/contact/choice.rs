//! Which facet a slave node is constrained against: one constraint per node and pass.
//!
//! # The rule
//! Among the master facets within the search distance of the node (the tree's `within` query),
//! keep those the node **projects into** — every barycentric coordinate `N_a ≥ −tol` with
//! [`PROJECTION_TOLERANCE`] — and choose the one with the **smallest `|P|`**, ties to the lowest
//! facet index. The constraint is the node–facet gap `P` of the formulation on that facet.
//!
//! Why this rule:
//! * **Flat surface, shared edge or vertex.** The node projects into every facet sharing the edge
//!   or vertex (the tolerance absorbs round-off), all give the same `P`, and the lowest index wins:
//!   the node is neither missed nor counted twice. On the shared edge the shape functions of both
//!   facets agree, so the force does not depend on the choice; the tangent's term `P∇²P` (or
//!   `λ∇²P`) does, through the facet's `G_a`, and jumps where the choice changes facet (a caller
//!   iterating Newton should keep a node's facet across an edge within a hysteresis, as the
//!   solver does).
//! * **Sliding.** Crossing an edge of a flat region, `P` and the shape functions are continuous,
//!   so gap and force are continuous.
//! * **Convex edge or corner** (a ridge of the master body). A node inside the body near the ridge
//!   projects into the facets on both sides; the smaller `|P|` is the shallower penetration, the
//!   natural way out. A node outside, above the ridge, projects into neither: it gets no
//!   constraint, which is right, since it is outside. It cannot fall through: to get inside it
//!   passes through the region where it projects into a facet with `P` near zero.
//! * **Concave edge** (a valley). A node penetrating one flank near the valley projects into that
//!   flank only (its foot on the other flank's plane lies beyond the valley line), so the
//!   penetrated facet is chosen; for a node above both flanks either choice has `P > 0`. The
//!   exception is the wedge below the valley line between the flanks' inward normals there (its
//!   angle is the kink `κ` between the normals; at a penetration `|P|` it is `2|P| tan(κ/2)`
//!   wide): a node in it has its foot beyond the valley line on both flanks' planes and gets
//!   `None`. A caller that knows the node's previous facet can keep its plane, extended, while
//!   the node penetrates it (the solver does).
//!
//! The rule assumes penetrations small compared with the facet size, as contact enforcement keeps
//! them.
//!
//! # Self-contact: facing facets only
//! When the slave nodes lie on the master surface itself (one surface in contact with itself, or
//! several bodies' surfaces named as one), [`choose_facet_facing`] also takes the outward normal
//! `n` of the node's own surface and keeps only the facets that face it ([`faces`]):
//! `W·n̂ < −cos 60°`, within 60° of opposite. The facets around the node are excluded anyway;
//! this leaves out the rest of its own side of the surface, which a node near a bend of that side
//! can lie behind and project into (next to a box's edge, a node of one face projects onto the
//! edge of the face beyond, an element behind its plane), while two parts of the surface that
//! come into contact face each other (`W·n̂` near `−1`; a node on a box's edge or corner, whose
//! normal is the mean of its faces', meets a face square to one of them at `W·n̂ = −0.71` or
//! `−0.58`). A bound of zero (any facet turned away at all) would take or leave a face square to
//! the node's own from the round-off of a few millionths of a turn. The rule is otherwise the
//! same, and so is the search (a candidate left out by the normal is left out whatever the
//! reach).

use crate::linalg::Vec3;
use crate::node_facet::NodeFacet;
use crate::search::{Bvh, Query, Surface};

/// Tolerance on the barycentric coordinates for "the node projects into the facet": a node on a
/// shared edge or vertex projects into every facet sharing it despite round-off.
pub const PROJECTION_TOLERANCE: f64 = 1e-9;

/// A facet faces a node's own surface when its normal is within the angle whose cosine this is
/// of the opposite of the node's normal (60°): see [`faces`].
pub const FACING_COSINE: f64 = 0.5;

/// `true` when a facet of unit normal `w` faces a surface whose outward normal is `n` (of any
/// length): `w·n < −FACING_COSINE |n|`. `false` for a zero or non-finite `n`.
#[must_use]
#[inline]
pub fn faces(w: &Vec3, n: &Vec3) -> bool {
    w.dot(n) < -FACING_COSINE * n.norm()
}

/// Relative margin of the search's certificate (see [`choose_facet`]), on the extent of the master
/// surface and the magnitude of the coordinates.
const MARGIN: f64 = 1e-7;

/// The facet `slave` is constrained against, with the evaluated node–facet pair, or `None` when the
/// node projects into no facet within `radius`.
///
/// `bvh` must have been built or updated with `positions`. The slave node is excluded from its own
/// facets (self-contact).
///
/// # Search
/// The rule's candidates are the facets within `radius`, but the answer is found among far fewer.
/// For a facet `f` the node projects into, `|P_f|` is its distance `d_f` to the facet (the foot is
/// the closest point; within the projection tolerance, the foot lies outside by at most
/// `6·10⁻⁹` of the facet's size). So when the best facet among those within a reach `ρ` has
/// `|P| ≤ ρ − μ`, every facet beyond `ρ` has `|P_f| > ρ − μ/2` and can neither beat nor tie it:
/// the answer is that of all facets within `radius`. The margin `μ` is `MARGIN` (10⁻⁷) times the
/// extent of the surface plus the magnitudes of the coordinates of the node and of its closest
/// point on the surface, far above the tolerance's offset and the rounding of `P` and `d_f`. The reach starts at the distance to the closest facet
/// (plus `2μ`) and grows, by at least an eighth of `radius`, until that holds or it is `radius`.
/// On the fine Hertz example (a rigid flat meshed finer under the sphere than away from it, the
/// radius its longest edge) a node met 314 facets within `radius` on average.
///
/// # Panics
/// If `slave` has no position, or `bvh` was built on another surface ([`Bvh::within`]).
#[must_use]
pub fn choose_facet(
    surface: &Surface,
    bvh: &Bvh,
    positions: &[Vec3],
    slave: u32,
    radius: f64,
) -> Option<(u32, NodeFacet)> {
    choose(surface, bvh, positions, (slave, None), radius)
}

/// [`choose_facet`] among the facets that face the slave node's own surface, whose outward normal
/// at the node is `facing`: those that face it, [`faces`] (self-contact: see the module
/// documentation). `facing` need not be of unit length; a zero or non-finite one faces
/// nothing, and the node gets `None`.
///
/// # Panics
/// As [`choose_facet`].
#[must_use]
pub fn choose_facet_facing(
    surface: &Surface,
    bvh: &Bvh,
    positions: &[Vec3],
    slave: u32,
    radius: f64,
    facing: Vec3,
) -> Option<(u32, NodeFacet)> {
    choose(surface, bvh, positions, (slave, Some(facing)), radius)
}

/// [`choose_facet`], among the facets facing `facing` when it is given.
fn choose(
    surface: &Surface,
    bvh: &Bvh,
    positions: &[Vec3],
    (slave, facing): (u32, Option<Vec3>),
    radius: f64,
) -> Option<(u32, NodeFacet)> {
    let Some(&x) = positions.get(slave as usize) else {
        panic!(
            "slave node {slave} has no position: {} node positions were given",
            positions.len()
        );
    };
    let query = Query {
        point: x,
        exclude: Some(slave),
    };
    if !(radius.is_finite() && radius > 0.0) {
        return best_within(surface, bvh, positions, (&query, facing), radius);
    }
    let nearest = bvh.closest(surface, &query, radius)?;
    let margin = MARGIN * (bvh.extent() + x.amax() + nearest.closest.point.amax());
    let mut reach = nearest.closest.distance + 2.0 * margin;
    loop {
        reach = reach.min(radius);
        let best = best_within(surface, bvh, positions, (&query, facing), reach);
        let certified = best
            .as_ref()
            .is_some_and(|(_, pair)| pair.gap().abs() <= reach - margin);
        if certified || reach >= radius {
            return best;
        }
        reach += reach.max(radius / 8.0).max(2.0 * margin);
    }
}

/// The rule over the facets within `reach` of the query: those the node projects into (and that
/// face `facing`, when given), the smallest `|P|`, ties to the lowest facet index.
fn best_within(
    surface: &Surface,
    bvh: &Bvh,
    positions: &[Vec3],
    (query, facing): (&Query, Option<Vec3>),
    reach: f64,
) -> Option<(u32, NodeFacet)> {
    let mut best: Option<(u32, NodeFacet)> = None;
    for hit in bvh.within(surface, query, reach) {
        let [a, b, c] = surface.corners(hit.facet, positions);
        let Ok(pair) = NodeFacet::new(a, b, c, query.point) else {
            continue;
        };
        if !pair.projection.is_inside(PROJECTION_TOLERANCE) {
            continue;
        }
        if facing.is_some_and(|n| !faces(&pair.facet.normal(), &n)) {
            continue;
        }
        let better = best.as_ref().is_none_or(|(f, p)| {
            let (g, g_best) = (pair.gap().abs(), p.gap().abs());
            g < g_best || (g == g_best && hit.facet < *f)
        });
        if better {
            best = Some((hit.facet, pair));
        }
    }
    best
}
