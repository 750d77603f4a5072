//! Compressible neo-Hookean solid, total-Lagrangian form.
//!
//! `W = μ/2 (tr C − 3) − μ ln J + λ/2 (ln J)²`, `C = FᵀF`, `J = det F`.
//! `P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ`, and with `d(F⁻ᵀ)_iJ/dF_kL = −F⁻¹_Jk F⁻¹_Li`,
//! `∂P_iJ/∂F_kL = μ δ_ik δ_JL + (μ − λ ln J) F⁻¹_Jk F⁻¹_Li + λ F⁻¹_Ji F⁻¹_Lk`.
//! Cauchy stress: `σ = (μ (b − I) + λ ln J I) / J`, `b = FFᵀ`.

use nalgebra::Matrix3;

use crate::material::{Tangent, t_index};

/// First Piola stress and tangent; `None` if `F` is singular or `J ≤ 0`.
#[must_use]
pub fn first_piola(lambda: f64, mu: f64, f: &Matrix3<f64>) -> Option<(Matrix3<f64>, Tangent)> {
    let j = f.determinant();
    if j <= 0.0 {
        return None;
    }
    let finv = f.try_inverse()?;
    let fit = finv.transpose();
    let lnj = j.ln();
    let p = (f - fit) * mu + fit * (lambda * lnj);
    let mut a = [0.0; 81];
    let c1 = mu - lambda * lnj;
    for i in 0..3 {
        for jj in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    let mut v =
                        c1 * finv[(jj, k)] * finv[(l, i)] + lambda * finv[(jj, i)] * finv[(l, k)];
                    if i == k && jj == l {
                        v += mu;
                    }
                    a[t_index(i, jj, k, l)] = v;
                }
            }
        }
    }
    Some((p, a))
}
