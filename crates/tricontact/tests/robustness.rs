//! Degenerate and extreme input: typed errors, never a panic or a NaN.

use proptest::prelude::*;
use tricontact::{
    Facet, GeometryError, NodeFacet, Vec3, closest_point, multiplier, penalty, point_edge,
    point_vertex,
};

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

/// A slave node so far from a tiny facet that `P |G_a|²` overflows: the pair exists (its gap and
/// shape functions are finite), and its shape-function gradients are an `Overflow`, as its
/// Hessian is, not NaN and infinities.
#[test]
fn shape_gradients_that_overflow_are_an_error() {
    let s = 1e-5;
    let pair = NodeFacet::new(
        v(0.0, 0.0, 0.0),
        v(s, 0.0, 0.0),
        v(0.0, s, 0.0),
        v(0.3 * s, 0.3 * s, 1e299),
    )
    .expect("a pair with a finite gap");
    assert!(pair.gap().is_finite());
    assert_eq!(pair.shape_gradients().err(), Some(GeometryError::Overflow));
    assert_eq!(pair.gap_hessian().err(), Some(GeometryError::Overflow));
    // At a sane distance, finite.
    let near = NodeFacet::new(
        v(0.0, 0.0, 0.0),
        v(s, 0.0, 0.0),
        v(0.0, s, 0.0),
        v(0.3 * s, 0.3 * s, s),
    )
    .expect("a pair");
    assert!(near.shape_gradients().is_ok());
}

/// Finite coordinates whose sums or squares overflow are an `Overflow`, not `NonFinite` (which
/// is for NaN or infinite input).
#[test]
fn finite_input_that_overflows_is_an_overflow() {
    let big = 1e308;
    let e = Facet::new(v(big, 0.0, 0.0), v(big, 1e200, 0.0), v(big, 0.0, 1e200)).err();
    assert_eq!(e, Some(GeometryError::Overflow));
    let e = point_vertex(&v(1e200, 0.0, 0.0), &v(-1e200, 0.0, 0.0)).err();
    assert_eq!(e, Some(GeometryError::Overflow));
    let e = point_edge(&v(-1e200, 0.0, 0.0), &v(1e200, 0.0, 0.0), &v(0.0, 1.0, 0.0)).err();
    assert_eq!(e, Some(GeometryError::Overflow));
    // NaN or infinite input stays `NonFinite`.
    let e = point_vertex(&v(f64::NAN, 0.0, 0.0), &v(1.0, 0.0, 0.0)).err();
    assert_eq!(e, Some(GeometryError::NonFinite));
    let e = point_edge(
        &v(0.0, 0.0, 0.0),
        &v(f64::INFINITY, 0.0, 0.0),
        &v(0.0, 1.0, 0.0),
    )
    .err();
    assert_eq!(e, Some(GeometryError::NonFinite));
    let e = Facet::new(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, f64::NAN, 0.0)).err();
    assert_eq!(e, Some(GeometryError::NonFinite));
}

#[test]
fn coincident_and_collinear_facets_are_errors() {
    let o = v(1.0, 2.0, 3.0);
    let cases = [
        (o, o, o),
        (o, o, v(2.0, 2.0, 3.0)),
        (o, v(2.0, 2.0, 3.0), v(3.0, 2.0, 3.0)),
        // Nearly collinear: height 1e-14 on an edge of 1.
        (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.5, 1e-14, 0.0)),
    ];
    for (a, b, c) in cases {
        let err = Facet::new(a, b, c).unwrap_err();
        assert!(
            matches!(err, GeometryError::DegenerateFacet { .. }),
            "{err:?}"
        );
        assert!(NodeFacet::new(a, b, c, v(0.0, 0.0, 1.0)).is_err());
    }
    // A thin but valid facet is accepted at any scale.
    for scale in [1e-9, 1.0, 1e9] {
        let f = Facet::new(
            v(0.0, 0.0, 0.0),
            v(scale, 0.0, 0.0),
            v(0.5 * scale, 1e-6 * scale, 0.0),
        );
        assert!(f.is_ok(), "scale {scale}");
    }
}

#[test]
fn non_finite_coordinates_are_errors() {
    let good = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let err = Facet::new(good[0], v(bad, 0.0, 0.0), good[2]).unwrap_err();
        assert_eq!(err, GeometryError::NonFinite);
        let err = NodeFacet::new(good[0], good[1], good[2], v(0.0, bad, 0.0)).unwrap_err();
        assert_eq!(err, GeometryError::NonFinite);
        assert!(point_vertex(&good[0], &v(bad, 0.0, 0.0)).is_err());
        assert!(point_edge(&good[0], &good[1], &v(bad, 0.0, 0.0)).is_err());
    }
    let pair = NodeFacet::new(good[0], good[1], good[2], v(0.2, 0.2, -0.1)).unwrap();
    assert_eq!(
        penalty(&pair, f64::NAN).unwrap_err(),
        GeometryError::Overflow
    );
    assert_eq!(
        multiplier(&pair, f64::INFINITY).unwrap_err(),
        GeometryError::Overflow
    );
}

#[test]
fn zero_distances_are_errors() {
    let (a, b) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
    assert!(matches!(
        point_vertex(&a, &a),
        Err(GeometryError::ZeroDistance { .. })
    ));
    assert!(matches!(
        point_edge(&a, &b, &v(0.3, 0.0, 0.0)),
        Err(GeometryError::ZeroDistance { .. })
    ));
    assert!(matches!(
        point_edge(&a, &a, &b),
        Err(GeometryError::DegenerateEdge { .. })
    ));
}

/// The zero-distance threshold is relative to the larger distance of the two points from the
/// origin, whatever the unit: a node 10⁻¹³ from a vertex at the origin is a distance, a node
/// 10⁻¹³ from a vertex at 1 is not.
#[test]
fn the_zero_distance_threshold_scales_with_the_coordinates() {
    let tiny = v(1e-13, 0.0, 0.0);
    let d = point_vertex(&v(0.0, 0.0, 0.0), &tiny).expect("a distance at any scale");
    assert_eq!(d.distance, 1e-13);
    assert!(matches!(
        point_vertex(&v(1.0, 0.0, 0.0), &(v(1.0, 0.0, 0.0) + tiny)),
        Err(GeometryError::ZeroDistance { .. })
    ));
}

/// Any finite f64, with magnitudes spread over the whole exponent range.
fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e3..1e3f64,
        any::<f64>().prop_filter("finite", |x| x.is_finite()),
        (-308i32..308, -1.0..1.0f64).prop_map(|(e, m)| m * 10f64.powi(e)),
        Just(0.0),
    ]
}

fn point() -> impl Strategy<Value = Vec3> {
    (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| v(x, y, z))
}

fn finite(values: impl IntoIterator<Item = f64>) -> bool {
    values.into_iter().all(f64::is_finite)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    #[test]
    fn no_nan_escapes(a in point(), b in point(), c in point(), l in point(), alpha in coordinate()) {
        if let Ok(pair) = NodeFacet::new(a, b, c, l) {
            prop_assert!(finite(pair.projection.shape) && pair.gap().is_finite());
            prop_assert!(finite(pair.gap_gradient().iter().copied()));
            if let Ok(h) = pair.gap_hessian() {
                prop_assert!(finite(h.iter().copied()));
            }
            if let Ok(g) = pair.shape_gradients() {
                prop_assert!(finite(g.iter().flatten().flat_map(|v| v.iter().copied())));
            }
            if let Ok(t) = penalty(&pair, alpha) {
                prop_assert!(finite(t.force.iter().chain(t.stiffness.iter()).copied()));
            }
            if let Ok(t) = multiplier(&pair, alpha) {
                prop_assert!(finite(t.jacobian.iter().chain(t.geometric_stiffness.iter()).copied()));
            }
            let f = pair.facet;
            let t = f.triad();
            prop_assert!(finite(t.u.iter().chain(t.v.iter()).chain(t.w.iter()).copied()));
            for k in 0..3 {
                let d = f.d_triad(k);
                prop_assert!(finite(d.du.iter().chain(d.dv.iter()).chain(d.dw.iter()).copied()));
            }
            let cp = closest_point(&f, &l);
            prop_assert!(finite(cp.barycentric) && finite(cp.point.iter().copied()));
        }
        if let Ok(pe) = point_edge(&a, &b, &l) {
            prop_assert!(finite(pe.gradient.iter().chain(pe.hessian.iter()).copied()));
        }
        if let Ok(pv) = point_vertex(&a, &l) {
            prop_assert!(finite(pv.gradient.iter().chain(pv.hessian.iter()).copied()));
        }
    }
}
