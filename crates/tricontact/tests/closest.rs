//! Closest-point queries: point–vertex and point–edge derivatives against finite differences, and
//! the face/edge/vertex classification against an independent brute-force reference.

mod common;

use common::{CASES, REL_STEP, TOL, facet_size, fd_gradient, fd_jacobian, node, pair, rel_err};
use nalgebra::SVector;
use proptest::prelude::*;
use tricontact::closest::{
    closest_point_and_distance_squared, closest_point_on_triangle, distance_squared_to_triangle,
};
use tricontact::{Facet, Feature, Vec3, Vec12, closest_point, point_edge, point_vertex};

type Vec6 = SVector<f64, 6>;
type Vec9 = SVector<f64, 9>;

/// Coordinates of nodes `first..first + N/3` of a stacked pair… picked by index.
fn pick<const N: usize>(x: &Vec12, nodes: &[usize]) -> SVector<f64, N> {
    SVector::from_fn(|r, _| x[3 * nodes[r / 3] + r % 3])
}

/// Distance from `p` to segment `(a, b)`.
fn segment_distance(a: &Vec3, b: &Vec3, p: &Vec3) -> f64 {
    let e = b - a;
    let t = ((p - a).dot(&e) / e.norm_squared()).clamp(0.0, 1.0);
    (p - (a + t * e)).norm()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    #[test]
    fn point_vertex_derivatives(x in pair()) {
        let y: Vec6 = pick(&x, &[0, 3]);
        let size = facet_size(&x);
        prop_assume!((node(&x, 3) - node(&x, 0)).norm() > 0.05 * size);
        let f = |z: &Vec6| point_vertex(&common::node(z, 0), &common::node(z, 1)).unwrap();
        let h = REL_STEP * size;
        let exact = f(&y);
        prop_assert!(rel_err(&fd_gradient(|z| f(z).distance, &y, h), &exact.gradient) <= TOL);
        let err = rel_err(&fd_jacobian(|z| f(z).gradient, &y, h), &exact.hessian);
        prop_assert!(err <= TOL, "Hessian relative error {err:e}");
        prop_assert!(rel_err(&exact.hessian.transpose(), &exact.hessian) <= 1e-12);
    }

    #[test]
    fn point_edge_derivatives(x in pair()) {
        let y: Vec9 = pick(&x, &[0, 1, 3]);
        let size = facet_size(&x);
        let f = |z: &Vec9| point_edge(&common::node(z, 0), &common::node(z, 1), &common::node(z, 2));
        let exact = f(&y).unwrap();
        prop_assume!(exact.distance > 0.05 * size);
        let h = REL_STEP * size;
        let fd = fd_gradient(|z| f(z).unwrap().distance, &y, h);
        prop_assert!(rel_err(&fd, &exact.gradient) <= TOL);
        let fd = fd_jacobian(|z| f(z).unwrap().gradient, &y, h);
        let err = rel_err(&fd, &exact.hessian);
        prop_assert!(err <= TOL, "Hessian relative error {err:e}");
        prop_assert!(rel_err(&exact.hessian.transpose(), &exact.hessian) <= 1e-12);
        // The foot of the perpendicular is the closest point of the line.
        let (a, b, p) = (node(&x, 0), node(&x, 1), node(&x, 3));
        let foot = a + exact.parameter * (b - a);
        prop_assert!(((p - foot).norm() - exact.distance).abs() <= 1e-12 * size.max(p.norm()));
        prop_assert!(exact.direction.dot(&(b - a)).abs() <= 1e-10 * size);
    }

    #[test]
    fn closest_point_matches_brute_force(x in pair()) {
        let (a, b, c, p) = (node(&x, 0), node(&x, 1), node(&x, 2), node(&x, 3));
        let facet = Facet::new(a, b, c).unwrap();
        let cp = closest_point(&facet, &p);
        let proj = tricontact::project(&facet, &p).unwrap();
        let reference = if proj.is_inside(0.0) {
            proj.gap.abs()
        } else {
            segment_distance(&a, &b, &p).min(segment_distance(&b, &c, &p)).min(segment_distance(&c, &a, &p))
        };
        let size = facet_size(&x);
        let tol = 1e-10 * size.max(p.norm());
        prop_assert!((cp.distance - reference).abs() <= tol, "{} vs {}", cp.distance, reference);
        prop_assert!((cp.barycentric.iter().sum::<f64>() - 1.0).abs() <= 1e-12);
        prop_assert!(cp.barycentric.iter().all(|&n| (0.0..=1.0).contains(&n)));
        // The feature agrees with the kernel's own measure of distance to it.
        let on = |k: usize| node(&x, k);
        let feature_distance = match cp.feature {
            Feature::Face => proj.gap.abs(),
            Feature::Edge(e) => point_edge(&on(e), &on((e + 1) % 3), &p).map_or(0.0, |pe| pe.distance),
            Feature::Vertex(v) => (p - on(v)).norm(),
        };
        prop_assert!((feature_distance - cp.distance).abs() <= tol);
        // Barycentric coordinates vanish off the feature.
        for k in 0..3 {
            if !cp.feature.nodes().contains(&k) {
                prop_assert_eq!(cp.barycentric[k], 0.0);
            }
        }
        // One region computation gives the closest point and, bit for bit, the squared distance
        // the search compares.
        let (both, d2) = closest_point_and_distance_squared(&a, &b, &c, &p);
        prop_assert_eq!(both, cp);
        prop_assert_eq!(d2.to_bits(), distance_squared_to_triangle(&a, &b, &c, &p).to_bits());
        prop_assert_eq!(both.distance.to_bits(), d2.sqrt().to_bits());
    }
}

#[test]
fn nodes_on_vertices_and_edges_get_lower_dimensional_features() {
    let facet = Facet::new(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
    )
    .unwrap();
    let cases = [
        (Vec3::new(0.0, 0.0, 0.0), Feature::Vertex(0)),
        (Vec3::new(2.0, 0.0, 0.5), Feature::Vertex(1)),
        (Vec3::new(0.0, 2.0, -0.5), Feature::Vertex(2)),
        (Vec3::new(1.0, 0.0, 0.0), Feature::Edge(0)),
        (Vec3::new(1.0, 1.0, 0.3), Feature::Edge(1)),
        (Vec3::new(0.0, 0.5, 0.0), Feature::Edge(2)),
        (Vec3::new(1.0, -1.0, 0.0), Feature::Edge(0)),
        (Vec3::new(-1.0, -1.0, 0.0), Feature::Vertex(0)),
        (Vec3::new(0.5, 0.5, -0.2), Feature::Face),
    ];
    for (p, expected) in cases {
        let cp = closest_point(&facet, &p);
        assert_eq!(cp.feature, expected, "node {p:?}");
    }
    let cp = closest_point(&facet, &Vec3::new(1.0, -1.0, 0.0));
    assert!((cp.distance - 1.0).abs() < 1e-15);
    assert_eq!(cp.barycentric, [0.5, 0.5, 0.0]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    /// The search's branch-free squared distance agrees with the kernel's closest point.
    #[test]
    fn fast_squared_distance_matches_closest_point(x in pair()) {
        let (a, b, c, p) = (node(&x, 0), node(&x, 1), node(&x, 2), node(&x, 3));
        let d = closest_point(&Facet::new(a, b, c).unwrap(), &p).distance;
        let fast = tricontact::distance_squared_to_triangle(&a, &b, &c, &p).sqrt();
        let scale = facet_size(&x).max(p.norm());
        prop_assert!((fast - d).abs() <= 1e-12 * d.max(1e-4 * scale), "{fast} vs {d}");
    }
}

/// Thin but valid facets (slivers and right-angled needles, the sine of their smallest angle from
/// 10⁻² down to 10⁻¹⁰, corners in every order, at several positions and sizes): a point on the facet is found at distance zero to
/// rounding (`ε / sine` of the facet's size, the precision to which its plane is known), a point
/// above it at its height, and the closest point is never farther than the nearest corner. The Voronoi-region quantities as products of dot products lose everything once
/// that sine is below about 10⁻⁸ (a point on such a facet was put 2.5 % of its size away, farther
/// than a corner, and the search missed the contact).
#[test]
fn thin_facets_have_accurate_closest_points() {
    let mut r = tricontact::search::scenes::uniform(17);
    let mut worst = 0.0f64;
    let mut cases = 0;
    for i in 0..20_000 {
        let sine = 10f64.powf(-2.0 - 8.0 * r());
        let size = 10f64.powf(-3.0 + 6.0 * r());
        let centre = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * 10.0 * size;
        // A long edge along a random direction `e`, the third corner `sine` of the way off it.
        let e = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize();
        let f = e
            .cross(&Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5))
            .normalize();
        // A sliver (all three angles near 0 or π), or a needle with a right angle (`t = 0`).
        let t = if i % 4 == 3 { 0.0 } else { r() };
        let corners = [
            centre,
            centre + size * e,
            centre + size * (t * e + sine * f),
        ];
        let n = e.cross(&f);
        // Every labelling of the corners.
        let order = [
            [0, 1, 2],
            [1, 2, 0],
            [2, 0, 1],
            [0, 2, 1],
            [2, 1, 0],
            [1, 0, 2],
        ][i % 6];
        let [a, b, c] = order.map(|k| corners[k]);
        let Ok(facet) = Facet::new(a, b, c) else {
            continue;
        };
        cases += 1;
        let (u, v) = (r(), r());
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        let on = a + u * (b - a) + v * (c - a);
        let height = size * (r() - 0.5);
        for (p, want) in [(on, 0.0), (on + height * n, height.abs())] {
            let cp = closest_point(&facet, &p);
            let nearest = [a, b, c]
                .iter()
                .map(|x| (p - x).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                cp.distance <= nearest * (1.0 + 1e-12),
                "sine {sine:e}: {} farther than a corner ({nearest})",
                cp.distance
            );
            // The facet's plane itself is known to `ε / sine` of its size (its normal is a cross
            // product of nearly parallel edges): the error is held to a hundred times that.
            let error = (cp.distance - want).abs() / size;
            worst = worst.max(error * sine / f64::EPSILON);
            assert!(
                error <= 100.0 * f64::EPSILON / sine,
                "sine {sine:e}, size {size:e}: distance {} for {want} (error {error:e} of the size)",
                cp.distance
            );
            let (both, d2) = closest_point_and_distance_squared(&a, &b, &c, &p);
            assert_eq!(both, cp);
            assert_eq!(
                d2.to_bits(),
                distance_squared_to_triangle(&a, &b, &c, &p).to_bits()
            );
        }
    }
    assert!(cases > 15_000, "{cases} facets accepted");
    println!("thin facets: {cases} cases, worst distance error {worst:.1} ε / sine of the size");
}

/// A triangle so small that products of four of its lengths underflow to zero (sizes below about
/// 10⁻⁷⁸, which [`Facet::new`] refuses) still gets the right feature and closest point from
/// `closest_point_on_triangle`, which measures it scaled to unit size. At every scale the feature
/// and barycentric coordinates are the unit triangle's, and the distance too while its square is
/// a normal number.
#[test]
fn tiny_triangles_have_the_unit_triangles_closest_point() {
    let unit = [
        Vec3::zeros(),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    for p in [
        Vec3::new(0.2, 0.3, 0.1),
        Vec3::new(0.6, 0.6, -0.2),
        Vec3::new(-0.5, 0.5, 0.0),
    ] {
        let reference = closest_point_on_triangle(&unit[0], &unit[1], &unit[2], &p);
        for s in [1e-60, 1e-80, 1e-100, 1e-150, 1e-200, 1e-280] {
            let [a, b, c] = unit.map(|x| x * s);
            let cp = closest_point_on_triangle(&a, &b, &c, &(p * s));
            assert_eq!(cp.feature, reference.feature, "scale {s:e}, {p:?}");
            for (n, m) in cp.barycentric.iter().zip(reference.barycentric) {
                assert!((n - m).abs() < 1e-12, "scale {s:e}: {:?}", cp.barycentric);
            }
            if (s * s).is_normal() {
                let d = cp.distance;
                assert!(
                    (d / s - reference.distance).abs() < 1e-12,
                    "scale {s:e}: {d:e}"
                );
            }
        }
    }
}
