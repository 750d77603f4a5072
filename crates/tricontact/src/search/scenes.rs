//! Synthetic surfaces for tests and benchmarks.
//!
//! * [`torus`]: an `nu × nv` grid on a torus (major radius `big_r`, minor radius `small_r`), each
//!   quad split into two facets: `2 nu nv` facets, outward normals, no boundary.
//! * [`grid`]: a flat `n × n` square grid in the plane `z = 0`, normals `+z`: `2 n²` facets with
//!   shared edges and vertices, the scene for exact ties.

use crate::linalg::Vec3;

/// Node positions and facets of a surface.
pub type Mesh = (Vec<Vec3>, Vec<[u32; 3]>);

/// A triangulated torus with `2 nu nv` facets (`nu` around the axis, `nv` around the tube).
#[must_use]
pub fn torus(nu: u32, nv: u32, big_r: f64, small_r: f64) -> Mesh {
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
