//! Material dispatch: stress and tangent for a displacement gradient `H`.
//!
//! Small strain (`nlgeom = false`): returns the Cauchy stress `σ(ε)`,
//! `ε = sym H`, and `C = ∂σ/∂H`. Finite strain (`nlgeom = true`): returns
//! the first Piola–Kirchhoff stress `P(F)`, `F = I + H`, and
//! `A = ∂P/∂F`. Both tangents are stored as `[f64; 81]` with index
//! `(3i + J)·9 + 3k + L` for `∂P_iJ/∂F_kL`, so one element routine serves
//! both. Linear elastic under `nlgeom` is Saint-Venant–Kirchhoff; neo-Hooke
//! under small strain is its linearisation (= linear elastic).

use nalgebra::Matrix3;

use crate::{linear_elastic, neo_hooke};

/// Fourth-order tangent `∂P_iJ/∂F_kL`, index `(3i + J)·9 + 3k + L`.
pub type Tangent = [f64; 81];

/// Index into a [`Tangent`].
#[must_use]
#[inline]
pub fn t_index(i: usize, j: usize, k: usize, l: usize) -> usize {
    (3 * i + j) * 9 + 3 * k + l
}

/// Constitutive law with Lamé constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law {
    /// Linear elastic (Saint-Venant–Kirchhoff at finite strain).
    LinearElastic,
    /// Compressible neo-Hookean `W = μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)²`.
    NeoHooke,
}

/// A material: law and Lamé constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Constitutive law.
    pub law: Law,
    /// First Lamé constant λ.
    pub lambda: f64,
    /// Shear modulus μ.
    pub mu: f64,
}

impl Material {
    /// From Young's modulus and Poisson's ratio.
    #[must_use]
    pub fn from_e_nu(law: Law, e: f64, nu: f64) -> Self {
        Self {
            law,
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            mu: e / (2.0 * (1.0 + nu)),
        }
    }

    /// Stress and tangent (see the module doc). `None` when `det F ≤ 0`
    /// under finite strain (inverted material point).
    #[must_use]
    pub fn response(&self, h: &Matrix3<f64>, nlgeom: bool) -> Option<(Matrix3<f64>, Tangent)> {
        if !nlgeom {
            return Some(linear_elastic::small_strain(self.lambda, self.mu, h));
        }
        if 1.0 + neo_hooke::det_one_plus_minus_one(h) <= 0.0 {
            return None;
        }
        Some(match self.law {
            Law::LinearElastic => linear_elastic::saint_venant_kirchhoff(self.lambda, self.mu, h),
            Law::NeoHooke => neo_hooke::first_piola(self.lambda, self.mu, h)?,
        })
    }
}

/// Cauchy stress `σ = P Fᵀ / J` (finite strain) or `σ` itself (small strain).
#[must_use]
pub fn cauchy(stress: &Matrix3<f64>, h: &Matrix3<f64>, nlgeom: bool) -> Matrix3<f64> {
    if !nlgeom {
        return *stress;
    }
    let f = Matrix3::identity() + h;
    stress * f.transpose() / f.determinant()
}

/// Von Mises equivalent stress of a symmetric stress tensor. Where the squares overflow (stresses
/// beyond about 10¹⁵⁴, which a model may reach), it is computed on the tensor scaled by its
/// largest entry (infinity was written to the `.vtu`, which VTK then cannot read).
#[must_use]
pub fn von_mises(s: &Matrix3<f64>) -> f64 {
    let v = von_mises_unscaled(s);
    if v.is_finite() {
        return v;
    }
    let m = s.amax();
    if !m.is_finite() || m == 0.0 {
        return v;
    }
    m * von_mises_unscaled(&(s / m))
}

fn von_mises_unscaled(s: &Matrix3<f64>) -> f64 {
    let d = [
        s[(0, 0)] - s[(1, 1)],
        s[(1, 1)] - s[(2, 2)],
        s[(2, 2)] - s[(0, 0)],
    ];
    let sh = s[(0, 1)].powi(2) + s[(1, 2)].powi(2) + s[(0, 2)].powi(2);
    (0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + 3.0 * sh).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_h() -> Matrix3<f64> {
        Matrix3::new(0.31, -0.12, 0.07, 0.05, -0.22, 0.18, -0.09, 0.11, 0.4)
    }

    /// Central-difference check of `∂P/∂F` against the analytical tangent.
    fn check_tangent(mat: Material, nlgeom: bool) {
        let h0 = sample_h();
        let (_, a) = mat.response(&h0, nlgeom).expect("admissible");
        let eps = 1e-6;
        let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut max_err = 0.0f64;
        for k in 0..3 {
            for l in 0..3 {
                let mut hp = h0;
                let mut hm = h0;
                hp[(k, l)] += eps;
                hm[(k, l)] -= eps;
                let (pp, _) = mat.response(&hp, nlgeom).expect("admissible");
                let (pm, _) = mat.response(&hm, nlgeom).expect("admissible");
                for i in 0..3 {
                    for j in 0..3 {
                        let fd = (pp[(i, j)] - pm[(i, j)]) / (2.0 * eps);
                        max_err = max_err.max((fd - a[t_index(i, j, k, l)]).abs());
                    }
                }
            }
        }
        assert!(
            max_err / scale <= 1e-6,
            "{mat:?} nlgeom={nlgeom}: rel err {}",
            max_err / scale
        );
    }

    #[test]
    fn tangents_match_central_differences() {
        for law in [Law::LinearElastic, Law::NeoHooke] {
            let mat = Material::from_e_nu(law, 1000.0, 0.3);
            check_tangent(mat, false);
            check_tangent(mat, true);
        }
    }

    #[test]
    fn stress_free_reference_and_inversion() {
        for law in [Law::LinearElastic, Law::NeoHooke] {
            let mat = Material::from_e_nu(law, 1000.0, 0.3);
            let (p, _) = mat.response(&Matrix3::zeros(), true).expect("admissible");
            assert!(p.norm() < 1e-12);
            let h = Matrix3::from_diagonal(&nalgebra::Vector3::new(-2.0, 0.0, 0.0));
            assert!(mat.response(&h, true).is_none());
        }
    }

    /// Down to strains of 10⁻¹³ the finite-strain stress differs from the small-strain one by the
    /// quadratic terms only (relative difference `O(|H|)`), not by round-off: the stress of a stiff
    /// model under a small load must not lose its digits to `F − F⁻ᵀ` or `ln det F` cancelling.
    #[test]
    fn finite_strain_reduces_to_small_strain() {
        for law in [Law::LinearElastic, Law::NeoHooke] {
            for e in [1000.0, 2.1e11] {
                let mat = Material::from_e_nu(law, e, 0.3);
                for scale in [1e-4, 1e-7, 1e-10, 1e-13] {
                    let h = sample_h() * scale;
                    let (p, _) = mat.response(&h, true).expect("admissible");
                    let (s, _) = mat.response(&h, false).expect("admissible");
                    let rel = (p - s).norm() / s.norm();
                    assert!(
                        rel <= 5.0 * h.norm() + 1e-13,
                        "{law:?} E {e} |H| {:.1e}: relative difference {rel:.2e}",
                        h.norm()
                    );
                }
            }
        }
    }

    #[test]
    fn determinant_minus_one_matches_the_determinant() {
        for scale in [1.0, 1e-3] {
            let h = sample_h() * scale;
            let direct = (Matrix3::identity() + h).determinant() - 1.0;
            let expanded = neo_hooke::det_one_plus_minus_one(&h);
            assert!((direct - expanded).abs() <= 1e-15, "{direct} vs {expanded}");
        }
        // Where the direct form has lost everything, the expansion keeps the trace.
        let h = Matrix3::from_diagonal(&nalgebra::Vector3::new(3e-17, 0.0, 0.0));
        assert_eq!((Matrix3::identity() + h).determinant() - 1.0, 0.0);
        assert_eq!(neo_hooke::det_one_plus_minus_one(&h), 3e-17);
    }

    #[test]
    fn von_mises_of_stresses_whose_squares_overflow() {
        for scale in [1e160, 1e200, 1e300] {
            let s = Matrix3::new(3.0, 1.0, 0.0, 1.0, -2.0, 0.5, 0.0, 0.5, 1.0);
            let v = von_mises(&(s * scale));
            assert!(v.is_finite(), "{scale:e}: {v}");
            assert!(
                (v / scale - von_mises(&s)).abs() <= 1e-14 * von_mises(&s),
                "{scale:e}"
            );
        }
    }

    #[test]
    fn von_mises_of_uniaxial_and_shear() {
        let s = Matrix3::new(5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert!((von_mises(&s) - 5.0).abs() < 1e-12);
        let t = Matrix3::new(0.0, 2.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert!((von_mises(&t) - 2.0 * 3f64.sqrt()).abs() < 1e-12);
    }
}
