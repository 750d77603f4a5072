//! Squared distances from one point to the (up to) four facets of a leaf, computed lane by lane.
//!
//! The arithmetic is exactly that of [`distance_squared_to_triangle`], operation for operation:
//! the six dot products `d1 … d6` of the edges `ab`, `ac` with `p − a`, `p − b`, `p − c`, the
//! three scaled sub-areas `va, vb, vc`, the edge parameters and the face's barycentric coordinates,
//! and finally `|p − (a N_a + b N_b + c N_c)|²`. The scalar kernel picks the first Voronoi region
//! whose test holds (vertices, then edges, then the face); here every lane computes every
//! candidate and selects by the same priority, without branches, so the four facets are evaluated
//! together and the results are bit for bit those of the scalar kernel: the tree compares exactly
//! the numbers the brute-force search compares. A lane whose selected coordinates are not finite
//! (extreme coordinates, where the scalar kernel rescales) is recomputed with the scalar kernel.

use crate::closest::distance_squared_to_triangle;
use crate::linalg::Vec3;

/// Facets evaluated together.
pub(crate) const LANES: usize = 4;

type L = [f64; LANES];

/// Lane-wise `f(x[k], y[k])`.
#[inline(always)]
fn map2(x: &L, y: &L, f: impl Fn(f64, f64) -> f64) -> L {
    std::array::from_fn(|k| f(x[k], y[k]))
}

/// Lane-wise dot product, summed as nalgebra sums a 3-vector dot: `(x·x + y·y) + z·z`.
#[inline(always)]
fn dot(u: &[L; 3], v: &[L; 3]) -> L {
    std::array::from_fn(|k| u[0][k] * v[0][k] + u[1][k] * v[1][k] + u[2][k] * v[2][k])
}

/// Lane-wise `u − v`.
#[inline(always)]
fn sub(u: &[L; 3], v: &[L; 3]) -> [L; 3] {
    std::array::from_fn(|d| map2(&u[d], &v[d], |x, y| x - y))
}

/// Where `mask[k]`, takes `value[k]` into `into[k]` (bitwise, so the compiler needs no branch).
#[inline(always)]
fn select(into: &mut [L; 3], mask: &[bool; LANES], value: [L; 3]) {
    let m: [u64; LANES] = std::array::from_fn(|k| 0u64.wrapping_sub(u64::from(mask[k])));
    for (dst, src) in into.iter_mut().zip(value) {
        *dst = std::array::from_fn(|k| {
            f64::from_bits((src[k].to_bits() & m[k]) | (dst[k].to_bits() & !m[k]))
        });
    }
}

/// Squared distances from `p` to the facets `corners[..]` (one to four of them); lanes beyond
/// `corners.len()` repeat the last facet.
#[inline]
pub(crate) fn distances_squared(corners: &[[Vec3; 3]], p: &Vec3) -> L {
    debug_assert!((1..=LANES).contains(&corners.len()));
    let last = corners.len() - 1;
    let padded: [&[Vec3; 3]; LANES] = std::array::from_fn(|k| &corners[k.min(last)]);
    let corner =
        |v: usize| -> [L; 3] { std::array::from_fn(|d| std::array::from_fn(|k| padded[k][v][d])) };
    let (a, b, c) = (corner(0), corner(1), corner(2));
    let pl: [L; 3] = std::array::from_fn(|d| [p[d]; LANES]);
    let (ab, ac, ap) = (sub(&b, &a), sub(&c, &a), sub(&pl, &a));
    let (bp, cp) = (sub(&ap, &ab), sub(&ap, &ac));
    let (d1, d2) = (dot(&ab, &ap), dot(&ac, &ap));
    let (d3, d4) = (dot(&ab, &bp), dot(&ac, &bp));
    let (d5, d6) = (dot(&ab, &cp), dot(&ac, &cp));
    let vc: L = std::array::from_fn(|k| d1[k] * d4[k] - d3[k] * d2[k]);
    let va: L = std::array::from_fn(|k| d3[k] * d6[k] - d5[k] * d4[k]);
    let vb: L = std::array::from_fn(|k| d5[k] * d2[k] - d1[k] * d6[k]);
    // The face, then each region of higher priority overrides it where its test holds.
    let inv: L = std::array::from_fn(|k| 1.0 / (va[k] + vb[k] + vc[k]));
    let mut n: [L; 3] = [
        map2(&va, &inv, |x, y| x * y),
        map2(&vb, &inv, |x, y| x * y),
        map2(&vc, &inv, |x, y| x * y),
    ];
    let zero = [0.0; LANES];
    let one = [1.0; LANES];
    let t2: L = std::array::from_fn(|k| d2[k] / (d2[k] - d6[k]));
    let e2 = std::array::from_fn(|k| vb[k] <= 0.0 && d2[k] >= 0.0 && d6[k] <= 0.0);
    select(&mut n, &e2, [map2(&one, &t2, |x, y| x - y), zero, t2]);
    let t1: L = std::array::from_fn(|k| (d4[k] - d3[k]) / ((d4[k] - d3[k]) + (d5[k] - d6[k])));
    let e1 = std::array::from_fn(|k| va[k] <= 0.0 && d4[k] >= d3[k] && d5[k] >= d6[k]);
    select(&mut n, &e1, [zero, map2(&one, &t1, |x, y| x - y), t1]);
    let t0: L = std::array::from_fn(|k| d1[k] / (d1[k] - d3[k]));
    let e0 = std::array::from_fn(|k| vc[k] <= 0.0 && d1[k] >= 0.0 && d3[k] <= 0.0);
    select(&mut n, &e0, [map2(&one, &t0, |x, y| x - y), t0, zero]);
    let v2 = std::array::from_fn(|k| d6[k] >= 0.0 && d5[k] <= d6[k]);
    select(&mut n, &v2, [zero, zero, one]);
    let v1 = std::array::from_fn(|k| d3[k] >= 0.0 && d4[k] <= d3[k]);
    select(&mut n, &v1, [zero, one, zero]);
    let v0 = std::array::from_fn(|k| d1[k] <= 0.0 && d2[k] <= 0.0);
    select(&mut n, &v0, [one, zero, zero]);
    // |p − (a N_a + b N_b + c N_c)|², summed as nalgebra sums it.
    let diff: [L; 3] = std::array::from_fn(|d| {
        std::array::from_fn(|k| p[d] - (a[d][k] * n[0][k] + b[d][k] * n[1][k] + c[d][k] * n[2][k]))
    });
    let mut out = dot(&diff, &diff);
    for k in 0..=last {
        if !(n[0][k].is_finite() && n[1][k].is_finite() && n[2][k].is_finite()) {
            let [a, b, c] = &corners[k];
            out[k] = distance_squared_to_triangle(a, b, c, p);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::scenes::uniform;

    fn check(corners: &[[Vec3; 3]], p: &Vec3) {
        let lanes = distances_squared(corners, p);
        for (k, [a, b, c]) in corners.iter().enumerate() {
            let scalar = distance_squared_to_triangle(a, b, c, p);
            assert_eq!(
                lanes[k].to_bits(),
                scalar.to_bits(),
                "lane {k}: {} vs {scalar} for {corners:?}, {p:?}",
                lanes[k]
            );
        }
    }

    #[test]
    fn lanes_equal_the_scalar_kernel_bit_for_bit() {
        let mut r = uniform(17);
        let mut v = |s: f64| Vec3::new(s * (r() - 0.5), s * (r() - 0.5), s * (r() - 0.5));
        for scale in [1.0, 1e-9, 1e9, 1e-160, 1e160] {
            for n in 1..=LANES {
                for _ in 0..2000 {
                    let corners: Vec<[Vec3; 3]> =
                        (0..n).map(|_| [v(scale), v(scale), v(scale)]).collect();
                    check(&corners, &v(2.0 * scale));
                }
            }
        }
    }

    #[test]
    fn lanes_equal_the_scalar_kernel_on_features_and_degenerate_facets() {
        let a = Vec3::new(0.0, 0.0, 0.0);
        let b = Vec3::new(1.0, 0.0, 0.0);
        let c = Vec3::new(0.0, 1.0, 0.0);
        let facets = [
            [a, b, c],
            [a, b, 2.0 * b], // collinear
            [a, a, c],       // two corners coincide
            [b, b, b],       // a point
        ];
        let mut points = vec![a, b, c, 0.5 * (a + b), 0.5 * (b + c), (a + b + c) / 3.0];
        points.extend(points.clone().iter().map(|p| p + Vec3::new(0.0, 0.0, 0.3)));
        points.extend([Vec3::new(-1.0, -1.0, 0.0), Vec3::new(2.0, 2.0, -1.0)]);
        for p in &points {
            check(&facets, p);
            check(&facets[1..3], p);
        }
        // Non-finite coordinates go through the scalar kernel's rescaling.
        let huge = [[
            a,
            Vec3::new(f64::MAX, 0.0, 0.0),
            Vec3::new(0.0, f64::MAX, 0.0),
        ]];
        check(&huge, &Vec3::new(1e300, 1e300, 1.0));
    }
}
