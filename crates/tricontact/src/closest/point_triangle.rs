//! Closest point of a facet to a node, and which feature (face, edge, vertex) it lies on.
//!
//! The facet's plane is split into seven Voronoi regions: the face, three edge slabs and three
//! vertex wedges. With `a, b, c = x_i, x_j, x_k` and `p = x_l`, the region follows from the six dot
//! products of the edges `ab`, `ac` with `p − a`, `p − b`, `p − c`, tested in a fixed order (vertices
//! before the edges that contain them, edges before the face), so a node exactly on a region boundary
//! is always assigned the lower-dimensional feature, deterministically. The closest point and its
//! barycentric coordinates are returned with the feature.
//!
//! The sub-areas that decide the edges and the face are, by Lagrange's identity, both products of
//! those dot products (`d1 d4 − d3 d2`, …: cheap) and triple products with the normal
//! `n·(ab × ap)`, … (exact to `ε / sin` where the products are exact to `ε / sin²`, `sin` that of
//! the angle at `a`). A facet with `sin² < 10⁻⁴` (`THIN`) takes the triple products: on a valid
//! sliver of sine 10⁻⁸ the products had put a point lying on the facet 2.5 % of its size away,
//! farther than a corner, and the search missed the contact; with the triple products the error
//! stays within 13 `ε / sin` of the facet's size (the precision to which its plane is known).
//!
//! Edges are numbered from their first node: edge 0 = i–j, edge 1 = j–k, edge 2 = k–i.

use crate::facet::Facet;
use crate::linalg::Vec3;

/// The feature of a facet on which a closest point lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Feature {
    /// The interior of the face.
    Face,
    /// Edge `e`, from local node `e` to local node `(e + 1) % 3`.
    Edge(usize),
    /// Local node `a` (0 = i, 1 = j, 2 = k).
    Vertex(usize),
}

impl Feature {
    /// The local nodes of the feature (one, two or three of 0, 1, 2).
    #[must_use]
    pub fn nodes(self) -> &'static [usize] {
        match self {
            Feature::Face => &[0, 1, 2],
            Feature::Edge(0) => &[0, 1],
            Feature::Edge(1) => &[1, 2],
            Feature::Edge(_) => &[2, 0],
            Feature::Vertex(0) => &[0],
            Feature::Vertex(1) => &[1],
            Feature::Vertex(_) => &[2],
        }
    }
}

/// The closest point of a facet to a node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    /// The feature the closest point lies on.
    pub feature: Feature,
    /// Barycentric coordinates `[N_i, N_j, N_k]` of the closest point (all in `[0, 1]`).
    pub barycentric: [f64; 3],
    /// The closest point.
    pub point: Vec3,
    /// Distance from the node to the closest point.
    pub distance: f64,
}

/// The closest point of `facet` to node `p`, with its feature.
#[must_use]
#[inline]
pub fn closest_point(facet: &Facet, p: &Vec3) -> ClosestPoint {
    let [a, b, c] = facet.nodes();
    closest_point_on_triangle(a, b, c, p)
}

/// The closest point of the triangle `(a, b, c)` to node `p`, with its feature, without building a
/// [`Facet`]. For a degenerate triangle (two corners coinciding, or all three on a line) the result
/// is finite but need not be the closest point of the segment or point it collapses to;
/// [`Facet::new`] refuses such triangles and the search skips them (with a report). A triangle
/// whose edges are all below [`TINY`] (which [`Facet::new`] refuses too) is measured scaled to
/// unit size: products of four of its lengths would underflow to zero and pick a wrong region.
#[must_use]
#[inline]
pub fn closest_point_on_triangle(a: &Vec3, b: &Vec3, c: &Vec3, p: &Vec3) -> ClosestPoint {
    let (ab, ac) = (b - a, c - a);
    let size = ab.amax().max(ac.amax());
    if size < TINY && size > 0.0 {
        let scaled = region_relative(&(ab / size), &(ac / size), &((p - a) / size));
        if scaled.1.iter().all(|v| v.is_finite()) {
            return at_region(a, b, c, p, scaled).0;
        }
    }
    closest_point_and_distance_squared(a, b, c, p).0
}

/// Largest edge component below which [`closest_point_on_triangle`] measures a triangle scaled to
/// unit size: below the smallest facet [`Facet::new`] accepts (`|w|²` a normal number needs edges
/// of about 10⁻⁷⁷ or more), so no search tree holds such a triangle and the search's kernel
/// ([`closest_point_and_distance_squared`], [`distance_squared_to_triangle`], bit for bit the
/// lanes') needs no such case.
pub const TINY: f64 = 1e-78;

/// [`closest_point_on_triangle`] and the squared distance, bit for bit the value of
/// [`distance_squared_to_triangle`] (the closest point's `distance` is its square root), from one
/// Voronoi-region computation: the search's kernel. A triangle below [`TINY`], which the search
/// never holds, is not rescaled here (see [`closest_point_on_triangle`]).
#[must_use]
#[inline]
pub fn closest_point_and_distance_squared(
    a: &Vec3,
    b: &Vec3,
    c: &Vec3,
    p: &Vec3,
) -> (ClosestPoint, f64) {
    at_region(a, b, c, p, region(a, b, c, p))
}

/// The closest point `a N_a + b N_b + c N_c` of the region `(feature, [N_a, N_b, N_c])` of `p`,
/// with its distance, and the squared distance.
#[inline]
fn at_region(
    a: &Vec3,
    b: &Vec3,
    c: &Vec3,
    p: &Vec3,
    (feature, barycentric): (Feature, [f64; 3]),
) -> (ClosestPoint, f64) {
    let point = a * barycentric[0] + b * barycentric[1] + c * barycentric[2];
    let d2 = (p - point).norm_squared();
    let closest = ClosestPoint {
        feature,
        barycentric,
        point,
        distance: d2.sqrt(),
    };
    (closest, d2)
}

/// The Voronoi region of `p` and the barycentric coordinates of its closest point.
///
/// The region tests use products of four lengths, which overflow (or underflow to `0/0`) for
/// extreme coordinates; the barycentric coordinates are invariant under scaling, so such a case is
/// recomputed on the relative vectors scaled to unit size.
#[inline]
fn region(a: &Vec3, b: &Vec3, c: &Vec3, p: &Vec3) -> (Feature, [f64; 3]) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let r = region_relative(&ab, &ac, &ap);
    if r.1.iter().all(|v| v.is_finite()) {
        return r;
    }
    let scale = ab.amax().max(ac.amax()).max(ap.amax());
    if !(scale.is_finite() && scale > 0.0) {
        return (Feature::Vertex(0), [1.0, 0.0, 0.0]);
    }
    let (ab, ac, ap) = (ab / scale, ac / scale, ap / scale);
    let r = region_relative(&ab, &ac, &ap);
    if r.1.iter().all(|v| v.is_finite()) {
        r
    } else {
        (Feature::Vertex(0), [1.0, 0.0, 0.0])
    }
}

/// [`region`] on `ab = b − a`, `ac = c − a`, `ap = p − a`.
#[inline]
fn region_relative(ab: &Vec3, ac: &Vec3, ap: &Vec3) -> (Feature, [f64; 3]) {
    let (bp, cp) = (ap - ab, ap - ac);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (Feature::Vertex(0), [1.0, 0.0, 0.0]);
    }
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (Feature::Vertex(1), [0.0, 1.0, 0.0]);
    }
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (Feature::Vertex(2), [0.0, 0.0, 1.0]);
    }
    // Twice the signed areas of the sub-triangles opposite a, b and c, scaled by |w|.
    let [va, vb, vc] = if is_thin([d1, d2, d3, d4, d6]) {
        sub_areas_by_normal(ab, ac, ap)
    } else {
        [d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2]
    };
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let t = d1 / (d1 - d3);
        return (Feature::Edge(0), [1.0 - t, t, 0.0]);
    }
    if va <= 0.0 && d4 >= d3 && d5 >= d6 {
        let t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (Feature::Edge(1), [0.0, 1.0 - t, t]);
    }
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let t = d2 / (d2 - d6);
        return (Feature::Edge(2), [1.0 - t, 0.0, t]);
    }
    let inv = 1.0 / (va + vb + vc);
    (Feature::Face, [va * inv, vb * inv, vc * inv])
}

/// Below this `sin²` of the angle at `a` (`1 − (ab·ac)² / (|ab|² |ac|²)`), a facet is thin: its
/// sub-areas are computed from its normal ([`sub_areas_by_normal`]).
pub(crate) const THIN: f64 = 1e-4;

/// Whether the facet is thin (see [`THIN`]), from the region's dot products: `|ab|² = d1 − d3`,
/// `|ac|² = d2 − d6` and `ab·ac = d2 − d4`. The products `d1 d4 − d3 d2` and the like are the
/// sub-areas times `|w|²` up to a rounding of `ε |ab|² |ac|²`, that is `ε / sin²` of their size:
/// all of it once the sine nears 10⁻⁸. The same operations serve the lanes (`search::lanes`), so
/// that both choose alike, bit for bit.
#[inline(always)]
pub(crate) fn is_thin([d1, d2, d3, d4, d6]: [f64; 5]) -> bool {
    let (ab2, ac2, abac) = (d1 - d3, d2 - d6, d2 - d4);
    let lengths = ab2 * ac2;
    let (gram, floor) = (lengths - abac * abac, THIN * lengths);
    // A NaN counts as thin (and is recomputed): the lanes test `!(gram ≥ floor)`.
    gram < floor || gram.is_nan() || floor.is_nan()
}

/// Twice the signed sub-areas opposite `a`, `b` and `c`, times `|w|`, as triple products with the
/// normal `w = ab × ac`: `n·(bp × cp)`, `n·(ap × ac)`, `n·(ab × ap)` (equal to the products of dot
/// products by Lagrange's identity). The cross products of nearly parallel edges are exact to
/// `ε |ab| |ac|`, so the sub-areas are exact to `ε / sin` of their size instead of `ε / sin²`.
#[inline(never)]
fn sub_areas_by_normal(ab: &Vec3, ac: &Vec3, ap: &Vec3) -> [f64; 3] {
    let n = ab.cross(ac);
    let (bp, cp) = (ap - ab, ap - ac);
    [
        n.dot(&bp.cross(&cp)),
        n.dot(&ap.cross(ac)),
        n.dot(&ab.cross(ap)),
    ]
}

/// Squared distance from `p` to the triangle `(a, b, c)`: the quantity the contact search compares
/// for every candidate facet. The same Voronoi-region computation as
/// [`closest_point_on_triangle`], without building the feature or taking the square root.
#[must_use]
#[inline]
pub fn distance_squared_to_triangle(a: &Vec3, b: &Vec3, c: &Vec3, p: &Vec3) -> f64 {
    let (_, [na, nb, nc]) = region(a, b, c, p);
    (p - (a * na + b * nb + c * nc)).norm_squared()
}
