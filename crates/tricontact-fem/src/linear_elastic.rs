//! Isotropic linear elasticity.
//!
//! Small strain: `σ = λ tr(ε) I + 2μ ε`, `ε = ½(H + Hᵀ)`, tangent
//! `∂σ_iJ/∂H_kL = λ δ_iJ δ_kL + μ (δ_ik δ_JL + δ_iL δ_Jk)`.
//!
//! Finite strain (Saint-Venant–Kirchhoff): `E = ½(FᵀF − I)`,
//! `S = λ tr(E) I + 2μ E`, `P = F S`, and
//! `∂P_iJ/∂F_kL = δ_ik S_LJ + λ F_iJ F_kL + μ F_iL F_kJ + μ (FFᵀ)_ik δ_JL`.

use nalgebra::Matrix3;

use crate::material::{Tangent, t_index};

fn delta(i: usize, j: usize) -> f64 {
    if i == j { 1.0 } else { 0.0 }
}

/// Small-strain stress and tangent.
#[must_use]
pub fn small_strain(lambda: f64, mu: f64, h: &Matrix3<f64>) -> (Matrix3<f64>, Tangent) {
    let eps = (h + h.transpose()) * 0.5;
    let sigma = Matrix3::identity() * (lambda * eps.trace()) + eps * (2.0 * mu);
    let mut c = [0.0; 81];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    c[t_index(i, j, k, l)] = lambda * delta(i, j) * delta(k, l)
                        + mu * (delta(i, k) * delta(j, l) + delta(i, l) * delta(j, k));
                }
            }
        }
    }
    (sigma, c)
}

/// Saint-Venant–Kirchhoff first Piola stress and tangent at the displacement gradient
/// `h = F − I`. The Green strain is `E = ½(H + Hᵀ + HᵀH)`, which keeps its digits at small strains
/// (`½(FᵀF − I)` would cancel to an absolute error of about 10⁻¹⁶).
#[must_use]
pub fn saint_venant_kirchhoff(lambda: f64, mu: f64, h: &Matrix3<f64>) -> (Matrix3<f64>, Tangent) {
    let f = Matrix3::identity() + h;
    let e = (h + h.transpose() + h.transpose() * h) * 0.5;
    let s = Matrix3::identity() * (lambda * e.trace()) + e * (2.0 * mu);
    let p = f * s;
    let b = f * f.transpose();
    let mut a = [0.0; 81];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    a[t_index(i, j, k, l)] = delta(i, k) * s[(l, j)]
                        + lambda * f[(i, j)] * f[(k, l)]
                        + mu * f[(i, l)] * f[(k, j)]
                        + mu * b[(i, k)] * delta(j, l);
                }
            }
        }
    }
    (p, a)
}
