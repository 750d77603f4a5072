//! Finite-difference checks of the facet normal and triad derivatives.

mod common;

use common::{CASES, REL_STEP, TOL, facet_size, fd_jacobian, node, pair, rel_err};
use nalgebra::SVector;
use proptest::prelude::*;
use tricontact::{Facet, Vec3, Vec12};

type Vec9 = SVector<f64, 9>;

fn facet(x: &Vec9) -> Facet {
    Facet::new(node(x, 0), node(x, 1), node(x, 2)).expect("well-shaped facet")
}

fn facet_coords(x: &Vec12) -> Vec9 {
    x.fixed_rows::<9>(0).into_owned()
}

/// Checks `d(a)` = ∂field/∂x_a for a = i, j, k against central differences of `field`.
fn check(
    x: &Vec12,
    field: impl Fn(&Facet) -> Vec3,
    d: impl Fn(&Facet, usize) -> tricontact::Mat3,
) -> Result<(), TestCaseError> {
    let y = facet_coords(x);
    let h = REL_STEP * facet_size(x);
    let fd = fd_jacobian(|z| field(&facet(z)), &y, h);
    let f = facet(&y);
    for a in 0..3 {
        let exact = d(&f, a);
        let approx = fd.fixed_view::<3, 3>(0, 3 * a).into_owned();
        let err = rel_err(&approx, &exact);
        prop_assert!(
            err <= TOL,
            "node {a}: relative error {err:e}\nfd {approx}\nexact {exact}"
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    #[test]
    fn area_normal_derivative(x in pair()) {
        check(&x, Facet::area_normal, Facet::d_area_normal)?;
    }

    #[test]
    fn normal_derivative(x in pair()) {
        check(&x, Facet::normal, Facet::d_normal)?;
    }

    #[test]
    fn triad_u_derivative(x in pair()) {
        check(&x, |f| f.triad().u, |f, a| f.d_triad(a).du)?;
    }

    #[test]
    fn triad_v_derivative(x in pair()) {
        check(&x, |f| f.triad().v, |f, a| f.d_triad(a).dv)?;
    }

    #[test]
    fn triad_w_derivative_matches_normal(x in pair()) {
        let f = facet(&facet_coords(&x));
        for a in 0..3 {
            prop_assert_eq!(f.d_triad(a).dw, f.d_normal(a));
        }
    }

    #[test]
    fn triad_is_orthonormal_with_seed_handedness(x in pair()) {
        let t = facet(&facet_coords(&x)).triad();
        for (p, q, expected) in [(t.u, t.u, 1.0), (t.v, t.v, 1.0), (t.w, t.w, 1.0),
                                 (t.u, t.v, 0.0), (t.u, t.w, 0.0), (t.v, t.w, 0.0)] {
            prop_assert!((p.dot(&q) - expected).abs() < 1e-12);
        }
        // V = U × W, so U × V = −W.
        prop_assert!((t.u.cross(&t.v) + t.w).norm() < 1e-12);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    /// The identity the Hessian of the gap relies on: `∂W/∂x_b = −G_b ⊗ W`.
    #[test]
    fn normal_derivative_is_rank_one(x in pair()) {
        let f = facet(&facet_coords(&x));
        for b in 0..3 {
            let rank_one = -f.shape_gradient(b) * f.normal().transpose();
            prop_assert!(rel_err(&rank_one, &f.d_normal(b)) <= 1e-10);
        }
    }

    /// `G_a = ∂N_a/∂x_l`, and the three sum to zero.
    #[test]
    fn shape_gradient_is_slave_derivative(x in pair()) {
        let f = facet(&facet_coords(&x));
        let h = REL_STEP * facet_size(&x);
        let xl: SVector<f64, 3> = x.fixed_rows::<3>(9).into_owned();
        let fd = fd_jacobian(|y| SVector::<f64, 3>::from(tricontact::project(&f, y).unwrap().shape), &xl, h);
        for a in 0..3 {
            let approx = fd.row(a).transpose();
            prop_assert!((approx - f.shape_gradient(a)).amax() * facet_size(&x) <= TOL);
        }
        let sum = f.shape_gradient(0) + f.shape_gradient(1) + f.shape_gradient(2);
        prop_assert!(sum.norm() * facet_size(&x) <= 1e-12);
    }
}

/// A local node index past 2 panics, as documented, in every per-node query (it wrapped modulo 3
/// in all but `d_triad`).
#[test]
fn a_node_index_past_two_panics() {
    let f = Facet::new(
        Vec3::zeros(),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    )
    .expect("a facet");
    // Each query answers for node 2 and panics for node 3.
    macro_rules! check {
        ($($query:ident),*) => {$(
            let _ = f.$query(2);
            let outcome = std::panic::catch_unwind(|| f.$query(3));
            assert!(outcome.is_err(), "{}(3) returned", stringify!($query));
        )*};
    }
    check!(
        opposite_edge,
        inner_edge_normal,
        shape_gradient,
        d_area_normal,
        d_normal,
        d_triad
    );
}
