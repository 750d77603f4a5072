//! Penalty and multiplier terms: finite-difference tangents, equilibrium, objectivity, symmetry.

mod common;

use common::{
    CASES, REL_STEP, TOL, facet_size, fd_gradient, fd_jacobian, node, pair, rel_err, rel_err_floor,
};
use nalgebra::{Rotation3, Unit};
use proptest::prelude::*;
use tricontact::{Mat12, NodeFacet, Vec3, Vec12, multiplier, penalty};

fn pair_at(x: &Vec12) -> NodeFacet {
    NodeFacet::from_stacked(x).expect("well-shaped pair")
}

/// A penalty factor in the units of the configuration (force per length); its value is arbitrary.
fn alpha(x: &Vec12) -> f64 {
    2.5e3 / facet_size(x)
}

fn rotation() -> impl Strategy<Value = Rotation3<f64>> {
    (common::vec3(), -3.0..3.0f64).prop_filter_map("axis", |(axis, angle)| {
        Unit::try_new(axis, 1e-3).map(|a| Rotation3::from_axis_angle(&a, angle))
    })
}

/// Applies `x ↦ Q x + t` to every node.
fn moved(x: &Vec12, q: &Rotation3<f64>, t: &Vec3) -> Vec12 {
    common::stack(
        &(q * node(x, 0) + t),
        &(q * node(x, 1) + t),
        &(q * node(x, 2) + t),
        &(q * node(x, 3) + t),
    )
}

fn block_rotation(q: &Rotation3<f64>) -> Mat12 {
    let mut big = Mat12::zeros();
    for a in 0..4 {
        big.fixed_view_mut::<3, 3>(3 * a, 3 * a)
            .copy_from(q.matrix());
    }
    big
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    #[test]
    fn penalty_force_is_energy_gradient(x in pair()) {
        let a = alpha(&x);
        let h = REL_STEP * facet_size(&x);
        let fd = fd_gradient(|y| 0.5 * a * pair_at(y).gap().powi(2), &x, h);
        let exact = penalty(&pair_at(&x), a).unwrap().force;
        // Force scale: the force at a gap of one facet size.
        let err = rel_err_floor(&fd, &exact, a * facet_size(&x));
        prop_assert!(err <= TOL, "relative error {err:e}");
    }

    #[test]
    fn penalty_tangent(x in pair()) {
        let a = alpha(&x);
        let h = REL_STEP * facet_size(&x);
        let fd = fd_jacobian(|y| penalty(&pair_at(y), a).unwrap().force, &x, h);
        let exact = penalty(&pair_at(&x), a).unwrap().stiffness;
        // Stiffness scale: α.
        let err = rel_err_floor(&fd, &exact, a);
        prop_assert!(err <= TOL, "relative error {err:e}");
        prop_assert!(rel_err(&exact.transpose(), &exact) <= 1e-12);
    }

    #[test]
    fn penalty_resistance_is_seed_formula(x in pair()) {
        let a = alpha(&x);
        let p = pair_at(&x);
        let terms = penalty(&p, a).unwrap();
        let scale = a * p.gap().abs();
        for (b, n) in p.shape4().into_iter().enumerate() {
            let seed = a * n * p.gap() * p.facet.normal();
            prop_assert!((terms.resistance(b) - seed).norm() <= 1e-12 * scale.max(f64::MIN_POSITIVE));
        }
    }

    #[test]
    fn penalty_has_no_net_force_or_moment(x in pair()) {
        let a = alpha(&x);
        let p = pair_at(&x);
        let terms = penalty(&p, a).unwrap();
        let mut force = Vec3::zeros();
        let mut moment = Vec3::zeros();
        for b in 0..4 {
            force += terms.resistance(b);
            moment += node(&x, b).cross(&terms.resistance(b));
        }
        let f_scale = a * p.gap().abs();
        let lever = (0..4).map(|b| node(&x, b).norm()).fold(0.0, f64::max);
        prop_assert!(force.norm() <= 1e-12 * f_scale + f64::MIN_POSITIVE);
        prop_assert!(moment.norm() <= 1e-12 * f_scale * lever + f64::MIN_POSITIVE);
    }

    #[test]
    fn rigid_motion_invariance(x in pair(), q in rotation(), t in common::vec3()) {
        let a = alpha(&x);
        let size = facet_size(&x);
        let y = moved(&x, &q, &(t * 10.0 * size));
        let (p, r) = (pair_at(&x), pair_at(&y));
        prop_assert!((p.gap() - r.gap()).abs() <= 1e-10 * size);
        for b in 0..3 {
            prop_assert!((p.projection.shape[b] - r.projection.shape[b]).abs() <= 1e-10);
        }
        let (tp, tr) = (penalty(&p, a).unwrap(), penalty(&r, a).unwrap());
        let big = block_rotation(&q);
        let force_scale = a * size;
        prop_assert!((big * tp.force - tr.force).amax() <= 1e-9 * force_scale);
        let k_rotated = big * tp.stiffness * big.transpose();
        prop_assert!(rel_err(&k_rotated, &tr.stiffness) <= 1e-9);
    }

    #[test]
    fn multiplier_terms(x in pair(), lambda in -10.0..10.0f64) {
        let p = pair_at(&x);
        let terms = multiplier(&p, lambda).unwrap();
        prop_assert_eq!(terms.constraint, p.gap());
        let h = REL_STEP * facet_size(&x);
        // ∇c against differences of c, and λ∇²c against differences of λ∇c.
        let fd = fd_gradient(|y| multiplier(&pair_at(y), lambda).unwrap().constraint, &x, h);
        prop_assert!(rel_err(&fd, &terms.jacobian) <= TOL);
        let fd = fd_jacobian(|y| multiplier(&pair_at(y), lambda).unwrap().jacobian * lambda, &x, h);
        // Scale of λ∇²P: |λ|/size.
        let err = rel_err_floor(&fd, &terms.geometric_stiffness, lambda.abs() / facet_size(&x));
        prop_assert!(err <= TOL, "relative error {err:e}");
        let k = terms.geometric_stiffness;
        prop_assert!(rel_err(&k.transpose(), &k) <= 1e-12);
    }
}

#[test]
fn slave_node_is_pushed_out_along_the_normal() {
    let p = NodeFacet::new(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.5, 0.5, -0.1),
    )
    .unwrap();
    let t = penalty(&p, 100.0).unwrap();
    // R_l = −αPW = +10 ez; the facet nodes share −10 ez by N = (0.5, 0.25, 0.25).
    assert!((t.resistance(3) - Vec3::new(0.0, 0.0, 10.0)).norm() < 1e-12);
    assert!((t.resistance(0) - Vec3::new(0.0, 0.0, -5.0)).norm() < 1e-12);
    assert!((t.resistance(1) - Vec3::new(0.0, 0.0, -2.5)).norm() < 1e-12);
}

mod contact_enforcement {
    use super::*;
    use tricontact::contact::{augmented, augmented_closed, multiplier_block};

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(CASES))]

        /// The augmented-Lagrangian force is the gradient of `(1/2α) min(0, λ_k + αP)²` and its
        /// tangent the derivative of the force.
        #[test]
        fn augmented_terms_are_consistent(x in pair(), lk in -5.0..0.0f64) {
            let a = alpha(&x);
            let lambda_k = lk * a * facet_size(&x);
            let h = REL_STEP * facet_size(&x);
            let energy = |y: &Vec12| {
                let m = (lambda_k + a * pair_at(y).gap()).min(0.0);
                0.5 * m * m / a
            };
            let exact = augmented(&pair_at(&x), lambda_k, a).unwrap();
            // Away from the switch λ̂ = 0 the energy is smooth.
            prop_assume!(exact.lambda_hat.abs() > 1e-3 * a * facet_size(&x));
            let scale = a * facet_size(&x);
            let fd = fd_gradient(energy, &x, h);
            prop_assert!(rel_err_floor(&fd, &exact.force, scale) <= TOL);
            let fd = fd_jacobian(|y| augmented(&pair_at(y), lambda_k, a).unwrap().force, &x, h);
            prop_assert!(rel_err_floor(&fd, &exact.stiffness, a) <= TOL);
            prop_assert_eq!(exact.updated_multiplier(), exact.lambda_hat.min(0.0));
            if exact.lambda_hat >= 0.0 {
                prop_assert_eq!(exact.force, Vec12::zeros());
            }
        }

        /// A node held closed: the force is the gradient of `λ̂²/(2α)` for either sign of `λ̂`
        /// and the tangent its derivative; where `λ̂ < 0` the terms are [`augmented`]'s.
        #[test]
        fn augmented_closed_terms_are_consistent(x in pair(), lk in -5.0..5.0f64) {
            let a = alpha(&x);
            let lambda_k = lk * a * facet_size(&x);
            let h = REL_STEP * facet_size(&x);
            let energy = |y: &Vec12| {
                let m = lambda_k + a * pair_at(y).gap();
                0.5 * m * m / a
            };
            let exact = augmented_closed(&pair_at(&x), lambda_k, a).unwrap();
            let scale = a * facet_size(&x);
            let fd = fd_gradient(energy, &x, h);
            prop_assert!(rel_err_floor(&fd, &exact.force, scale) <= TOL);
            let fd =
                fd_jacobian(|y| augmented_closed(&pair_at(y), lambda_k, a).unwrap().force, &x, h);
            prop_assert!(rel_err_floor(&fd, &exact.stiffness, a) <= TOL);
            if exact.lambda_hat < 0.0 {
                prop_assert_eq!(exact, augmented(&pair_at(&x), lambda_k, a).unwrap());
            }
        }

        /// The active multiplier block is the derivative of `(λ∇P, P)`; the inactive one enforces
        /// `λ = 0`; the switch is `κP + λ ≤ 0`.
        #[test]
        fn multiplier_block_is_consistent(x in pair(), l in -3.0..3.0f64) {
            let kappa = alpha(&x);
            let lambda = l * kappa * facet_size(&x) * 0.1;
            let p = pair_at(&x);
            let b = multiplier_block(&p, lambda, kappa).unwrap();
            prop_assert_eq!(b.active, kappa * p.gap() + lambda <= 0.0);
            let h = REL_STEP * facet_size(&x);
            if b.active {
                prop_assert_eq!(b.residual_lambda, p.gap());
                let fd = fd_jacobian(|y| pair_at(y).gap_gradient() * lambda, &x, h);
                prop_assert!(rel_err_floor(&fd, &b.k_uu, lambda.abs() / facet_size(&x)) <= TOL);
                let fd = fd_gradient(|y| pair_at(y).gap(), &x, h);
                prop_assert!(rel_err(&fd, &b.k_ulambda) <= TOL);
                prop_assert_eq!(b.k_lambdalambda, 0.0);
            } else {
                prop_assert!((b.residual_lambda * kappa - lambda).abs() <= 1e-15 * lambda.abs());
                prop_assert!((b.k_lambdalambda * kappa - 1.0).abs() <= 1e-15);
                prop_assert_eq!(b.k_ulambda, Vec12::zeros());
            }
        }
    }

    #[test]
    fn uzawa_iteration_drives_the_penetration_of_a_loaded_node_to_zero() {
        // A slave node held by a spring of stiffness s pushed into a fixed facet with force F:
        // equilibrium s (z − z0) + f_contact = 0 solved exactly per Uzawa step.
        let (s, f_push, alpha) = (100.0, 50.0, 1e3);
        let facet = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        ];
        let mut lambda_k = 0.0;
        let mut gaps = Vec::new();
        for _ in 0..8 {
            // Solve s z + F + min(0, λ_k + α z) = 0 for the node height z (P = z) by Newton.
            let mut z = 0.0;
            for _ in 0..30 {
                let pair =
                    NodeFacet::new(facet[0], facet[1], facet[2], Vec3::new(0.5, 0.5, z)).unwrap();
                let t = augmented(&pair, lambda_k, alpha).unwrap();
                let r = s * z + f_push + t.force[11];
                let k = s + t.stiffness[(11, 11)];
                z -= r / k;
            }
            let pair =
                NodeFacet::new(facet[0], facet[1], facet[2], Vec3::new(0.5, 0.5, z)).unwrap();
            lambda_k = augmented(&pair, lambda_k, alpha)
                .unwrap()
                .updated_multiplier();
            gaps.push(z);
        }
        // Each Uzawa step shrinks the penetration by s/(s+α); the multiplier tends to −F.
        assert!(gaps[0] < 0.0 && gaps.windows(2).all(|w| w[1].abs() < w[0].abs()));
        assert!(gaps[7].abs() < 1e-6 * gaps[0].abs());
        assert!((lambda_k + f_push).abs() < 1e-5 * f_push);
    }
}
