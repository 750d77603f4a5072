//! Compressible neo-Hookean solid, total-Lagrangian form.
//!
//! `W = μ/2 (tr C − 3) − μ ln J + λ/2 (ln J)²`, `C = FᵀF`, `J = det F`.
//! `P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ`, and with `d(F⁻ᵀ)_iJ/dF_kL = −F⁻¹_Jk F⁻¹_Li`,
//! `∂P_iJ/∂F_kL = μ δ_ik δ_JL + (μ − λ ln J) F⁻¹_Jk F⁻¹_Li + λ F⁻¹_Ji F⁻¹_Lk`.
//! Cauchy stress: `σ = (μ (b − I) + λ ln J I) / J`, `b = FFᵀ`.
//!
//! # Small strains without round-off
//! The input is the displacement gradient `H = F − I`, and neither `F − F⁻ᵀ` nor `ln J` is formed
//! as a difference of numbers near 1, which would leave an absolute error of `ε ≈ 10⁻¹⁶` in a
//! stress of relative size `|H|` (a stiff model under a small load, `|H| = 10⁻⁸`, would keep only
//! eight digits and Newton would stall above its tolerance):
//! * `F − F⁻ᵀ = H + Hᵀ F⁻ᵀ` (from `Fᵀ F⁻ᵀ = I`);
//! * `J − 1 = tr H + I₂(H) + det H` (the expansion of `det(I + H)`, `I₂` the sum of the principal
//!   2×2 minors), and `ln J = ln_1p(J − 1)`.

use nalgebra::Matrix3;

use crate::material::{Tangent, t_index};

/// First Piola stress and tangent at the displacement gradient `h = F − I`; `None` if `F` is
/// singular or `J ≤ 0`.
#[must_use]
pub fn first_piola(lambda: f64, mu: f64, h: &Matrix3<f64>) -> Option<(Matrix3<f64>, Tangent)> {
    let j_minus_1 = det_one_plus_minus_one(h);
    if 1.0 + j_minus_1 <= 0.0 {
        return None;
    }
    let f = Matrix3::identity() + h;
    let finv = f.try_inverse()?;
    let fit = finv.transpose();
    let lnj = j_minus_1.ln_1p();
    let p = (h + h.transpose() * fit) * mu + fit * (lambda * lnj);
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

/// `det(I + H) − 1 = tr H + I₂(H) + det H`, without the cancellation of forming `det(I + H)`.
#[must_use]
pub fn det_one_plus_minus_one(h: &Matrix3<f64>) -> f64 {
    let minors = h[(0, 0)] * h[(1, 1)] - h[(0, 1)] * h[(1, 0)] + h[(0, 0)] * h[(2, 2)]
        - h[(0, 2)] * h[(2, 0)]
        + h[(1, 1)] * h[(2, 2)]
        - h[(1, 2)] * h[(2, 1)];
    h.trace() + minors + h.determinant()
}
