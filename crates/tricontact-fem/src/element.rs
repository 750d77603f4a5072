//! Volume-element internal force and consistent tangent (one routine for
//! small strain and total-Lagrangian finite strain).
//!
//! At each quadrature point: `J = Σ_a X_a ⊗ ∂N_a/∂ξ`, `∂N_a/∂X = J⁻ᵀ ∂N_a/∂ξ`,
//! `H = Σ_a u_a ⊗ ∂N_a/∂X`. With the stress `P` and tangent `A = ∂P/∂F` of
//! [`crate::material`]:
//!
//! `f_ai = Σ_gp w det J  P_iJ ∂N_a/∂X_J`,
//! `K_(ai)(bk) = Σ_gp w det J  ∂N_a/∂X_J A_iJkL ∂N_b/∂X_L`.
//!
//! Degrees of freedom are ordered `3a + i`; `K` is row-major. Under small
//! strain `P = σ` and this is the usual `Bᵀ D B`.

use nalgebra::Matrix3;

use crate::material::{Material, cauchy, t_index};
use crate::shape::{MAX_NODES, QPoint};

/// An integration point where `det F ≤ 0` (or the reference map is singular).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inverted;

/// Reference gradients `∂N_a/∂X` and `w det J` at one quadrature point.
#[must_use]
pub fn reference_gradients(q: &QPoint, x0: &[[f64; 3]]) -> Option<([[f64; 3]; MAX_NODES], f64)> {
    let n = q.shape.len;
    let mut jac = Matrix3::<f64>::zeros();
    for a in 0..n {
        for i in 0..3 {
            for j in 0..3 {
                jac[(i, j)] += x0[a][i] * q.shape.dn[a][j];
            }
        }
    }
    let det = jac.determinant();
    let inv = jac.try_inverse()?;
    let mut g = [[0.0; 3]; MAX_NODES];
    for a in 0..n {
        for j in 0..3 {
            g[a][j] = (0..3).map(|m| q.shape.dn[a][m] * inv[(m, j)]).sum();
        }
    }
    Some((g, q.w * det))
}

/// Reference Jacobian determinants at the quadrature points.
#[must_use]
pub fn jacobian_dets(rule: &[QPoint], x0: &[[f64; 3]]) -> Vec<f64> {
    rule.iter()
        .map(|q| {
            let mut jac = Matrix3::<f64>::zeros();
            for a in 0..q.shape.len {
                for i in 0..3 {
                    for j in 0..3 {
                        jac[(i, j)] += x0[a][i] * q.shape.dn[a][j];
                    }
                }
            }
            jac.determinant()
        })
        .collect()
}

fn displacement_gradient(g: &[[f64; 3]; MAX_NODES], u: &[[f64; 3]], n: usize) -> Matrix3<f64> {
    let mut h = Matrix3::zeros();
    for a in 0..n {
        for i in 0..3 {
            for j in 0..3 {
                h[(i, j)] += u[a][i] * g[a][j];
            }
        }
    }
    h
}

/// Internal force `f` (length `3n`) and, if `k` is given, tangent (`9n²`,
/// row-major); both are overwritten.
///
/// # Errors
/// [`Inverted`] when a point has `det F ≤ 0` or a singular reference map.
pub fn internal_force(
    rule: &[QPoint],
    x0: &[[f64; 3]],
    u: &[[f64; 3]],
    mat: &Material,
    nlgeom: bool,
    f: &mut [f64],
    mut k: Option<&mut [f64]>,
) -> Result<(), Inverted> {
    let n = x0.len();
    let nd = 3 * n;
    f[..nd].fill(0.0);
    if let Some(k) = k.as_deref_mut() {
        k[..nd * nd].fill(0.0);
    }
    for q in rule {
        let (g, wdet) = reference_gradients(q, x0).ok_or(Inverted)?;
        if wdet <= 0.0 {
            return Err(Inverted);
        }
        let h = displacement_gradient(&g, u, n);
        let (p, a) = mat.response(&h, nlgeom).ok_or(Inverted)?;
        for b in 0..n {
            for i in 0..3 {
                let mut s = 0.0;
                for j in 0..3 {
                    s += p[(i, j)] * g[b][j];
                }
                f[3 * b + i] += wdet * s;
            }
        }
        if let Some(k) = k.as_deref_mut() {
            // ga[a][i][kk][l] = Σ_J ∂N_a/∂X_J A_iJkL
            let mut ga = [[[[0.0; 3]; 3]; 3]; MAX_NODES];
            for aa in 0..n {
                for i in 0..3 {
                    for kk in 0..3 {
                        for l in 0..3 {
                            let mut s = 0.0;
                            for j in 0..3 {
                                s += g[aa][j] * a[t_index(i, j, kk, l)];
                            }
                            ga[aa][i][kk][l] = wdet * s;
                        }
                    }
                }
            }
            for aa in 0..n {
                for i in 0..3 {
                    let row = &mut k[(3 * aa + i) * nd..(3 * aa + i + 1) * nd];
                    for b in 0..n {
                        for kk in 0..3 {
                            let gl = &ga[aa][i][kk];
                            row[3 * b + kk] += gl[0] * g[b][0] + gl[1] * g[b][1] + gl[2] * g[b][2];
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// Volume-averaged Cauchy stress of the element.
///
/// # Errors
/// [`Inverted`] as in [`internal_force`].
pub fn mean_cauchy_stress(
    rule: &[QPoint],
    x0: &[[f64; 3]],
    u: &[[f64; 3]],
    mat: &Material,
    nlgeom: bool,
) -> Result<Matrix3<f64>, Inverted> {
    let n = x0.len();
    let mut sum = Matrix3::zeros();
    let mut vol = 0.0;
    for q in rule {
        let (g, wdet) = reference_gradients(q, x0).ok_or(Inverted)?;
        let h = displacement_gradient(&g, u, n);
        let (p, _) = mat.response(&h, nlgeom).ok_or(Inverted)?;
        sum += cauchy(&p, &h, nlgeom) * wdet;
        vol += wdet;
    }
    Ok(sum / vol)
}
