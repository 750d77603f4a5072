//! Shared test helpers: random well-shaped node–facet configurations and central differences.
#![allow(dead_code)]

use nalgebra::{SMatrix, SVector};
use proptest::prelude::*;
use tricontact::{Vec3, Vec12};

/// Number of random configurations per property.
pub const CASES: u32 = 1000;

/// Relative step of the central differences, times the facet size.
pub const REL_STEP: f64 = 1e-5;

/// Acceptance threshold on the relative error of a derivative.
pub const TOL: f64 = 1e-6;

pub fn vec3() -> impl Strategy<Value = Vec3> {
    (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A well-shaped facet (smallest height at least 0.2 of the longest edge), anywhere in space and
/// at any scale from 1e-3 to 1e3, plus a slave node above, below or beside it: its barycentric
/// coordinates range over [-0.8, 1.8] and its height over ±0.6 of the facet size.
pub fn pair() -> impl Strategy<Value = Vec12> {
    (
        vec3(),
        vec3(),
        vec3(),
        vec3(),
        -3.0..3.0f64,
        (-0.8..1.8f64, -0.8..1.8f64, -0.6..0.6f64),
    )
        .prop_filter("well-shaped facet", |(a, b, c, ..)| quality(a, b, c) > 0.2)
        .prop_map(|(a, b, c, shift, exp, (s, t, h))| {
            let scale = 10f64.powf(exp);
            let (xi, xj, xk) = (a * scale, b * scale, c * scale);
            let shift = shift * 5.0 * scale;
            let w = (xj - xi).cross(&(xk - xi));
            let size = size(&xi, &xj, &xk);
            let xl = xi + s * (xj - xi) + t * (xk - xi) + h * size * w.normalize();
            stack(&(xi + shift), &(xj + shift), &(xk + shift), &(xl + shift))
        })
}

/// Smallest height over longest edge: 0 for a degenerate facet, √3/2 for an equilateral one.
pub fn quality(a: &Vec3, b: &Vec3, c: &Vec3) -> f64 {
    let l = size(a, b, c);
    (b - a).cross(&(c - a)).norm() / (l * l)
}

pub fn size(a: &Vec3, b: &Vec3, c: &Vec3) -> f64 {
    (b - a).norm().max((c - b).norm()).max((a - c).norm())
}

pub fn stack(xi: &Vec3, xj: &Vec3, xk: &Vec3, xl: &Vec3) -> Vec12 {
    let mut x = Vec12::zeros();
    for (a, p) in [xi, xj, xk, xl].into_iter().enumerate() {
        x.fixed_rows_mut::<3>(3 * a).copy_from(p);
    }
    x
}

pub fn node<const N: usize>(x: &SVector<f64, N>, a: usize) -> Vec3 {
    Vec3::new(x[3 * a], x[3 * a + 1], x[3 * a + 2])
}

/// Facet size of a stacked pair (longest edge of the first three nodes).
pub fn facet_size(x: &Vec12) -> f64 {
    size(&node(x, 0), &node(x, 1), &node(x, 2))
}

/// Central-difference Jacobian of `f` at `x` with step `h`.
pub fn fd_jacobian<const M: usize, const N: usize>(
    f: impl Fn(&SVector<f64, N>) -> SVector<f64, M>,
    x: &SVector<f64, N>,
    h: f64,
) -> SMatrix<f64, M, N> {
    let mut jac = SMatrix::<f64, M, N>::zeros();
    for c in 0..N {
        let (mut xp, mut xm) = (*x, *x);
        xp[c] += h;
        xm[c] -= h;
        jac.set_column(c, &((f(&xp) - f(&xm)) / (2.0 * h)));
    }
    jac
}

/// Central-difference gradient of a scalar `f` at `x` with step `h`.
pub fn fd_gradient<const N: usize>(
    f: impl Fn(&SVector<f64, N>) -> f64,
    x: &SVector<f64, N>,
    h: f64,
) -> SVector<f64, N> {
    fd_jacobian(|y| SVector::<f64, 1>::new(f(y)), x, h).transpose()
}

/// `max |approx − exact| / max |exact|` (absolute when `exact` vanishes).
pub fn rel_err<const M: usize, const N: usize>(
    approx: &SMatrix<f64, M, N>,
    exact: &SMatrix<f64, M, N>,
) -> f64 {
    rel_err_floor(approx, exact, 0.0)
}

/// `max |approx − exact| / max(max |exact|, floor)`: relative to the result, or to the natural
/// scale `floor` of the quantity when the result itself is nearly zero (a force at a tiny gap).
pub fn rel_err_floor<const M: usize, const N: usize>(
    approx: &SMatrix<f64, M, N>,
    exact: &SMatrix<f64, M, N>,
    floor: f64,
) -> f64 {
    let diff = (approx - exact).amax();
    let scale = exact.amax().max(floor);
    if scale > 0.0 { diff / scale } else { diff }
}
