//! Finite-difference checks of the gap, its gradient and Hessian, and the shape functions.

mod common;

use common::{CASES, REL_STEP, TOL, facet_size, fd_gradient, fd_jacobian, node, pair, rel_err};
use nalgebra::SVector;
use proptest::prelude::*;
use tricontact::{NodeFacet, Vec12};

fn pair_at(x: &Vec12) -> NodeFacet {
    NodeFacet::from_stacked(x).expect("well-shaped pair")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    #[test]
    fn gap_gradient(x in pair()) {
        let h = REL_STEP * facet_size(&x);
        let fd = fd_gradient(|y| pair_at(y).gap(), &x, h);
        let exact = pair_at(&x).gap_gradient();
        let err = rel_err(&fd, &exact);
        prop_assert!(err <= TOL, "relative error {err:e}");
    }

    #[test]
    fn gap_hessian(x in pair()) {
        let h = REL_STEP * facet_size(&x);
        let fd = fd_jacobian(|y| pair_at(y).gap_gradient(), &x, h);
        let exact = pair_at(&x).gap_hessian().unwrap();
        let err = rel_err(&fd, &exact);
        prop_assert!(err <= TOL, "relative error {err:e}\nfd {fd}\nexact {exact}");
    }

    #[test]
    fn gap_hessian_is_symmetric(x in pair()) {
        let hess = pair_at(&x).gap_hessian().unwrap();
        prop_assert!(rel_err(&hess.transpose(), &hess) <= 1e-12);
    }

    #[test]
    fn shape_function_gradients(x in pair()) {
        let h = REL_STEP * facet_size(&x);
        let fd = fd_jacobian(|y| SVector::<f64, 3>::from(pair_at(y).projection.shape), &x, h);
        let exact = pair_at(&x).shape_gradients().expect("finite");
        for (a, row) in exact.iter().enumerate() {
            for (b, g) in row.iter().enumerate() {
                let approx = fd.fixed_view::<1, 3>(a, 3 * b).transpose();
                // Scale: ∇N is of order 1/size.
                let err = (approx - g).amax() * facet_size(&x);
                prop_assert!(err <= TOL, "∇_{b} N_{a}: error {err:e}");
            }
        }
    }

    #[test]
    fn shape_functions_are_barycentric(x in pair()) {
        let p = pair_at(&x);
        let [ni, nj, nk] = p.projection.shape;
        prop_assert!((ni + nj + nk - 1.0).abs() < 1e-12);
        // Σ N_a x_a is the projection of x_l: it differs from x_l by P W.
        let projected = node(&x, 0) * ni + node(&x, 1) * nj + node(&x, 2) * nk;
        let offset = node(&x, 3) - projected - p.gap() * p.facet.normal();
        prop_assert!(offset.norm() <= 1e-10 * facet_size(&x).max(node(&x, 3).norm()));
        // Inside exactly when all three are non-negative.
        prop_assert_eq!(p.projection.is_inside(0.0), ni >= 0.0 && nj >= 0.0 && nk >= 0.0);
    }

    #[test]
    fn shape_function_is_one_at_its_node(x in pair()) {
        for a in 0..3 {
            let mut y = x;
            let xa = node(&x, a);
            y.fixed_rows_mut::<3>(9).copy_from(&xa);
            let p = pair_at(&y);
            for b in 0..3 {
                let expected = if a == b { 1.0 } else { 0.0 };
                prop_assert!((p.projection.shape[b] - expected).abs() < 1e-10);
            }
            prop_assert!(p.gap().abs() <= 1e-12 * facet_size(&x).max(xa.norm()));
        }
    }

    #[test]
    fn reversing_orientation_flips_gap(x in pair()) {
        let mut y = x;
        y.fixed_rows_mut::<3>(3).copy_from(&node(&x, 2));
        y.fixed_rows_mut::<3>(6).copy_from(&node(&x, 1));
        let (p, q) = (pair_at(&x), pair_at(&y));
        prop_assert!((p.gap() + q.gap()).abs() <= 1e-12 * facet_size(&x).max(node(&x, 3).norm()));
        prop_assert!((p.projection.shape[1] - q.projection.shape[2]).abs() < 1e-12);
    }
}
