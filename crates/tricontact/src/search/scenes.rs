//! Synthetic surfaces for tests and benchmarks.
//!
//! * [`torus`]: an `nu × nv` grid on a torus (major radius `big_r`, minor radius `small_r`), each
//!   quad split into two facets: `2 nu nv` facets, outward normals, no boundary.
//! * [`grid`]: a flat `n × n` square grid in the plane `z = 0`, normals `+z`: `2 n²` facets with
//!   shared edges and vertices, the scene for exact ties.
//! * [`near_surface`]: query points within a distance of a surface; [`deformed`]: a smooth
//!   motion of its nodes (the benchmarks' small deformation).

use crate::linalg::Vec3;

/// Node positions and facets of a surface.
pub type Mesh = (Vec<Vec3>, Vec<[u32; 3]>);

/// A triangulated torus with `2 nu nv` facets (`nu` around the axis, `nv` around the tube).
///
/// # Panics
/// If `nu nv` exceeds `u32::MAX` (node numbers are `u32`).
#[must_use]
pub fn torus(nu: u32, nv: u32, big_r: f64, small_r: f64) -> Mesh {
    assert!(
        nu.checked_mul(nv).is_some(),
        "torus: {nu} × {nv} nodes do not fit node numbers of 32 bits"
    );
    let mut nodes = Vec::with_capacity((nu * nv) as usize);
    for i in 0..nu {
        let u = std::f64::consts::TAU * f64::from(i) / f64::from(nu);
        for j in 0..nv {
            let v = std::f64::consts::TAU * f64::from(j) / f64::from(nv);
            let rho = big_r + small_r * v.cos();
            nodes.push(Vec3::new(rho * u.cos(), rho * u.sin(), small_r * v.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let mut facets = Vec::with_capacity(2 * (nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            facets.push([a, b, c]);
            facets.push([a, c, d]);
        }
    }
    (nodes, facets)
}

/// A flat square grid of `2 n²` facets over `[0, n·h]²` in `z = 0`, normals `+z`.
#[must_use]
pub fn grid(n: u32, h: f64) -> Mesh {
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let mut nodes = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for j in 0..=n {
        for i in 0..=n {
            nodes.push(Vec3::new(f64::from(i) * h, f64::from(j) * h, 0.0));
        }
    }
    let mut facets = Vec::with_capacity(2 * (n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            facets.push([a, b, c]);
            facets.push([a, c, d]);
        }
    }
    (nodes, facets)
}

/// A small deterministic generator of uniform numbers in `[0, 1)` (a 64-bit linear congruential
/// generator), so scenes and query sets are reproducible without a random-number crate.
pub fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        // The top 53 bits as a fraction: exact in f64.
        #[allow(clippy::cast_precision_loss)]
        let v = (s >> 11) as f64 / (1u64 << 53) as f64;
        v
    }
}

/// Shuffles `v` in place, the same way for the same `seed` (Fisher–Yates on [`uniform`]).
pub fn shuffle<T>(v: &mut [T], seed: u64) {
    let mut r = uniform(seed);
    for i in (1..v.len()).rev() {
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let j = ((r() * (i + 1) as f64) as usize).min(i);
        v.swap(i, j);
    }
}

/// One point per facet, in facet order: a uniformly random point of the facet moved along the
/// facet normal by a uniform offset in `[−spread, spread]` — query points near the surface.
///
/// # Panics
/// If a facet names a node past the end of `nodes`.
#[must_use]
pub fn near_surface(nodes: &[Vec3], facets: &[[u32; 3]], spread: f64, seed: u64) -> Vec<Vec3> {
    let mut r = uniform(seed);
    facets
        .iter()
        .map(|&[a, b, c]| {
            let (a, b, c) = (nodes[a as usize], nodes[b as usize], nodes[c as usize]);
            let (s, t) = (r(), r());
            let (s, t) = if s + t > 1.0 {
                (1.0 - s, 1.0 - t)
            } else {
                (s, t)
            };
            let n = (b - a).cross(&(c - a)).normalize();
            a + s * (b - a) + t * (c - a) + (2.0 * r() - 1.0) * spread * n
        })
        .collect()
}

/// `nodes` moved by a wave along `z`, `a h sin(2x)`, and a twist about `z` by the angle
/// `a h z / 4`: a smooth deformation whose node motions are of order `a` element sizes `h` (the
/// largest on the benchmarks' torus is 1.0–1.3 `a h`).
#[must_use]
pub fn deformed(nodes: &[Vec3], h: f64, a: f64) -> Vec<Vec3> {
    nodes
        .iter()
        .map(|p| {
            let wave = a * h * (2.0 * p.x).sin();
            let twist = 0.25 * a * h * p.z;
            Vec3::new(
                p.x * twist.cos() - p.y * twist.sin(),
                p.x * twist.sin() + p.y * twist.cos(),
                p.z + wave,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Node numbers that would wrap (in a release build) are refused up front.
    #[test]
    #[should_panic(expected = "do not fit node numbers of 32 bits")]
    fn a_torus_too_large_for_its_node_numbers_panics() {
        let _ = torus(70_000, 70_000, 3.0, 1.0);
    }

    #[test]
    fn a_shuffle_is_a_permutation_fixed_by_its_seed() {
        let shuffled = |seed: u64| {
            let mut v: Vec<usize> = (0..1000).collect();
            shuffle(&mut v, seed);
            v
        };
        let a = shuffled(3);
        assert_eq!(a, shuffled(3));
        assert_ne!(a, shuffled(4));
        let moved = a.iter().enumerate().filter(|&(i, &x)| i != x).count();
        assert!(moved > 900, "only {moved} of 1000 moved");
        let mut sorted = a;
        sorted.sort_unstable();
        assert_eq!(sorted, (0..1000).collect::<Vec<_>>());
        let mut empty: [u8; 0] = [];
        shuffle(&mut empty, 1);
    }
}
