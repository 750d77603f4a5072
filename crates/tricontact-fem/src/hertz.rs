//! Hertz theory for an elastic sphere pressed on a flat, and the measurement of a contact pair
//! against it (the `[hertz]` table of a model).
//!
//! Theory (sphere radius `R`, total force `F`, contact modulus `E*` with
//! `1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂`, so `E* = E/(1 − ν²)` on a rigid flat):
//!
//! ```text
//! a = (3 F R / (4 E*))^(1/3)      contact radius
//! p0 = 3 F / (2 π a²)             peak pressure,   p(r) = p0 √(1 − r²/a²)
//! δ = a² / R = k F^(2/3),  k = (9 / (16 R E*²))^(1/3)    approach of distant points
//! ```
//!
//! Measurement at a converged increment:
//! * `F` = `symmetry` × the pair's normal force (`Σ −λ`; a quarter model has `symmetry = 4`);
//! * the profile is `(r, p)` over the pair's closed slave nodes: `r` the distance of the deformed node
//!   from the axis through `centre`, `p` the nodal `contact_pressure` (force over lumped area);
//! * the fitted profile: `p² = p0² − (p0²/a²) r²` is linear in `r²`, so a linear least-squares fit
//!   `p² ≈ c₀ + c₁ r²` gives `p0 = √c₀` and `a = √(−c₀/c₁)` — the contact radius and peak
//!   pressure the mesh predicts, free of the node spacing at the contact edge;
//! * the largest nodal pressure is reported beside the fitted `p0`;
//! * the approach is `−ū·axis`, `ū` the mean displacement of the `loaded` group. Hertz's `δ` is
//!   the approach of points infinitely far away in a half-space; the loaded face of a finite body
//!   differs from it by terms linear in `F`: the compliance of the body beyond the contact zone
//!   (positive) minus the part of Hertz's far field beyond the face (Boussinesq, on the axis at
//!   depth `z`: `(1 + ν)(3 − 2ν) F / (2π E z)`, about `1.2·10⁻⁷ F` for the steel sphere at
//!   `z = R`). So the force–approach curve is fitted as `δ = k F^(2/3) + c F` (least squares over
//!   the increments) and the fitted `k` is compared with Hertz's; `c`, the linear remainder, may
//!   have either sign.

use crate::analysis::Analysis;
use crate::contact::ContactPair;
use crate::driver::IncrementInfo;
use crate::error::{FemError, Result};
use crate::model::HertzDef;

/// Hertz theory for one sphere on a flat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hertz {
    /// Sphere radius `R`.
    pub radius: f64,
    /// Contact modulus `E*`.
    pub modulus: f64,
}

impl Hertz {
    /// Contact radius `a(F) = F^(1/3) (3R/(4E*))^(1/3)`; 0 without a compressive force (`F ≤ 0`:
    /// no contact). The cube roots are taken apart so that a tiny force does not underflow.
    #[must_use]
    pub fn contact_radius(&self, force: f64) -> f64 {
        if force <= 0.0 {
            return 0.0;
        }
        force.cbrt() * (3.0 * self.radius / (4.0 * self.modulus)).cbrt()
    }

    /// Peak pressure `p0(F)`; 0 when `F ≤ 0`. Written as `(3/(2π)) F^(1/3) (4E*/(3R))^(2/3)`
    /// rather than `3F/(2πa²)`, which is `0/0` where `a²` underflows.
    #[must_use]
    pub fn peak_pressure(&self, force: f64) -> f64 {
        if force <= 0.0 {
            return 0.0;
        }
        let stiffness = (4.0 * self.modulus / (3.0 * self.radius)).cbrt();
        3.0 / (2.0 * std::f64::consts::PI) * force.cbrt() * stiffness * stiffness
    }

    /// Pressure `p(r)` under the force `F` (0 outside the contact, and when `F ≤ 0`).
    #[must_use]
    pub fn pressure(&self, force: f64, r: f64) -> f64 {
        let a = self.contact_radius(force);
        if a == 0.0 || r.abs() >= a {
            return 0.0;
        }
        self.peak_pressure(force) * (1.0 - (r / a).powi(2)).sqrt()
    }

    /// Coefficient `k` of `δ = k F^(2/3)`.
    #[must_use]
    pub fn approach_coefficient(&self) -> f64 {
        (9.0 / (16.0 * self.radius * self.modulus * self.modulus)).cbrt()
    }

    /// Approach `δ(F) = a²/R`.
    #[must_use]
    pub fn approach(&self, force: f64) -> f64 {
        self.approach_coefficient() * force.max(0.0).powf(2.0 / 3.0)
    }
}

/// Least-squares fit of `p² = c₀ + c₁ r²` over `(r, p)`: `(a, p0)`, or `None` with fewer than
/// three points or a profile that does not fall with `r`.
#[must_use]
pub fn fit_profile(profile: &[(f64, f64)]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = profile.iter().map(|&(r, p)| (r * r, p * p)).collect();
    let (c0, c1) = linear_fit(&pts, |_| 1.0, |x| x)?;
    (pts.len() >= 3 && c0 > 0.0 && c1 < 0.0).then(|| ((-c0 / c1).sqrt(), c0.sqrt()))
}

/// Least-squares fit of `δ = k F^(2/3) + c F` over `(F, δ)`: `(k, c)`, or `None` with fewer than
/// two distinct forces.
#[must_use]
pub fn fit_approach(samples: &[(f64, f64)]) -> Option<(f64, f64)> {
    linear_fit(samples, |f| f.max(0.0).powf(2.0 / 3.0), |f| f)
}

/// Least squares `y ≈ c₀ g₀(x) + c₁ g₁(x)` by the 2×2 normal equations, scaled so the
/// determinant test is relative.
fn linear_fit(
    pts: &[(f64, f64)],
    g0: impl Fn(f64) -> f64,
    g1: impl Fn(f64) -> f64,
) -> Option<(f64, f64)> {
    let (mut a00, mut a01, mut a11, mut b0, mut b1) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y) in pts {
        let (u, v) = (g0(x), g1(x));
        a00 += u * u;
        a01 += u * v;
        a11 += v * v;
        b0 += u * y;
        b1 += v * y;
    }
    let det = a00 * a11 - a01 * a01;
    if det.is_nan() || det <= 1e-12 * a00 * a11 {
        return None;
    }
    Some(((a11 * b0 - a01 * b1) / det, (a00 * b1 - a01 * b0) / det))
}

/// The resolved `[hertz]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct HertzSetup {
    /// The theory.
    pub theory: Hertz,
    /// History column of the pair's normal force.
    pub force_column: String,
    /// Point of first contact.
    pub centre: [f64; 3],
    /// Unit load axis.
    pub axis: [f64; 3],
    /// Symmetry factor.
    pub symmetry: f64,
    /// Nodes of the loaded group.
    pub loaded: Vec<usize>,
    /// Slave nodes of the pair (first pass): the nodes of the pressure profile.
    pub slaves: Vec<usize>,
}

/// How many model sizes (the diagonal of the mesh's bounding box) a `centre` may lie from the
/// mesh, and a `radius` may reach.
const FAR: f64 = 1e6;

impl HertzSetup {
    /// Resolves the table against the analysis.
    ///
    /// # Errors
    /// As [`HertzSetup::resolve_at`], its messages without their place in the model file.
    pub fn resolve(def: &HertzDef, an: &Analysis) -> Result<Self> {
        Self::resolve_at(def, an, &|_| String::new())
    }

    /// Resolves the table against the analysis; `at(key)` is the prefix of a message about one
    /// of its keys (its place in the model file: [`crate::source::SourceMap::at`]).
    ///
    /// # Errors
    /// [`FemError::Invalid`] listing every problem found: unknown pair or group, no unique pair,
    /// non-positive radius or modulus, zero axis, zero symmetry, a centre or radius far outside
    /// the mesh.
    pub fn resolve_at(def: &HertzDef, an: &Analysis, at: &dyn Fn(&str) -> String) -> Result<Self> {
        let mut problems = Vec::new();
        let mut problem = |key: &str, message: String| {
            problems.push(format!("{}[hertz] {message}", at(key)));
        };
        let pair = chosen_pair(def, an, &mut problem);
        let group = match an.mesh.lookup(&def.loaded, None) {
            Ok(Some(g)) => Some(g),
            Ok(None) => {
                problem(
                    "loaded",
                    format!("loaded: {}", unknown_group(an, &def.loaded)),
                );
                None
            }
            Err(m) => {
                problem("loaded", format!("loaded: {m}"));
                None
            }
        };
        let modulus = match (def.modulus, pair) {
            (Some(m), _) => Some(m),
            (None, Some(pair)) => {
                let m = slave_modulus(an, pair.passes[0].slaves.first().copied());
                if m.is_none() {
                    problem(
                        "modulus",
                        "modulus: no body element at the slave nodes".into(),
                    );
                }
                m
            }
            (None, None) => None,
        };
        let norm = def.axis[0].hypot(def.axis[1]).hypot(def.axis[2]);
        check_values(def, an, norm, &mut problem);
        // Taken from the slave body, it is not > 0 only when that body's material is invalid
        // (a problem of its own): say so rather than quote a modulus the user never gave.
        if def.modulus.is_none() && modulus.is_some_and(|m| !positive(m)) {
            problem(
                "modulus",
                "modulus: taken from the slave body's material, which is invalid; fix the material or give `modulus`".into(),
            );
        }
        let (Some(pair), Some(group), Some(modulus), true) =
            (pair, group, modulus, problems.is_empty())
        else {
            return Err(FemError::Invalid(problems));
        };
        Ok(Self {
            theory: Hertz {
                radius: def.radius,
                modulus,
            },
            force_column: format!("{}_normal_force", pair.name),
            centre: def.centre,
            axis: def.axis.map(|x| x / norm),
            symmetry: def.symmetry as f64,
            loaded: group.nodes.clone(),
            slaves: pair.passes[0].slaves.clone(),
        })
    }

    /// Measures one converged increment.
    #[must_use]
    pub fn measure(&self, an: &Analysis, info: &IncrementInfo<'_>) -> HertzSample {
        let field = |name: &str| {
            info.point_fields
                .iter()
                .find(|f| f.name == name)
                .map(|f| f.values.as_slice())
        };
        let force = self.symmetry
            * info
                .history
                .iter()
                .find(|(n, _)| n == &self.force_column)
                .map_or(0.0, |(_, v)| *v);
        let mut profile = Vec::new();
        if let (Some(status), Some(pressure)) = (field("contact_status"), field("contact_pressure"))
        {
            for &a in &self.slaves {
                if status[a] > 0.5 {
                    let node = an.mesh.nodes[a];
                    let x: [f64; 3] = std::array::from_fn(|i| node[i] + info.u[3 * a + i]);
                    profile.push((self.radial_distance(x), pressure[a]));
                }
            }
        }
        profile.sort_by(|p, q| p.0.total_cmp(&q.0));
        let approach = if self.loaded.is_empty() {
            0.0
        } else {
            -self
                .loaded
                .iter()
                .map(|&a| {
                    (0..3)
                        .map(|i| info.u[3 * a + i] * self.axis[i])
                        .sum::<f64>()
                })
                .sum::<f64>()
                / self.loaded.len() as f64
        };
        HertzSample {
            step: info.step,
            increment: info.increment,
            iterations: info.iterations,
            force,
            approach,
            fit: fit_profile(&profile),
            max_pressure: profile.iter().map(|p| p.1).fold(0.0, f64::max),
            profile,
        }
    }

    /// Distance of `x` from the axis through the centre.
    fn radial_distance(&self, x: [f64; 3]) -> f64 {
        let d: [f64; 3] = std::array::from_fn(|i| x[i] - self.centre[i]);
        let along: f64 = (0..3).map(|i| d[i] * self.axis[i]).sum();
        (0..3)
            .map(|i| (d[i] - along * self.axis[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

/// The contact pair the table names, or the model's only one; otherwise a `problem`.
fn chosen_pair<'a>(
    def: &HertzDef,
    an: &'a Analysis,
    problem: &mut dyn FnMut(&str, String),
) -> Option<&'a ContactPair> {
    let names: Vec<&str> = an.contacts.iter().map(|p| p.name.as_str()).collect();
    match &def.contact {
        Some(name) => {
            let pair = an.contacts.iter().find(|p| &p.name == name);
            if pair.is_none() {
                problem(
                    "contact",
                    format!("contact: no pair '{name}' (pairs: {})", names.join(", ")),
                );
            }
            pair
        }
        None if an.contacts.len() == 1 => Some(&an.contacts[0]),
        None if an.contacts.is_empty() => {
            problem(
                "",
                "needs a [[contact]] pair (the sphere as slave, the flat as master)".into(),
            );
            None
        }
        None => {
            problem(
                "",
                format!(
                    "contact: name the pair, the model has {} (pairs: {})",
                    an.contacts.len(),
                    names.join(", ")
                ),
            );
            None
        }
    }
}

/// `x` is finite and positive.
fn positive(x: f64) -> bool {
    x > 0.0 && x.is_finite()
}

/// The table's own values (`norm` that of its axis): a finite centre, a finite positive radius,
/// modulus (when given) and axis length, a symmetry of at least 1, and the centre and radius
/// within [`FAR`] model sizes of the mesh (a unit slip otherwise).
fn check_values(def: &HertzDef, an: &Analysis, norm: f64, problem: &mut dyn FnMut(&str, String)) {
    let centre_finite = def.centre.iter().all(|c| c.is_finite());
    if !centre_finite {
        problem(
            "centre",
            format!("centre must be three finite numbers (got {:?})", def.centre),
        );
    }
    if !positive(def.radius) {
        problem(
            "radius",
            format!("radius must be finite and > 0 (got {})", def.radius),
        );
    }
    // A modulus taken from the slave body is that of a valid material, or of one reported
    // invalid with its own key: only a given one is checked here.
    if let Some(m) = def.modulus
        && !positive(m)
    {
        problem(
            "modulus",
            format!("modulus must be finite and > 0 (got {m})"),
        );
    }
    if !positive(norm) {
        problem(
            "axis",
            format!("axis must be finite and not zero (got {:?})", def.axis),
        );
    }
    if def.symmetry == 0 {
        problem("symmetry", "symmetry must be ≥ 1 (got 0)".into());
    }
    // A unit slip (metres for millimetres, or worse) shows as a centre or radius far outside
    // the model; at 10³⁰⁰ the distances from the axis overflowed.
    let (low, high) = an.mesh.bounding_box();
    let size = an.mesh.size();
    let outside = (0..3)
        .map(|i| (low[i] - def.centre[i]).max(def.centre[i] - high[i]))
        .fold(0.0, f64::max);
    if centre_finite && outside > FAR * size {
        problem(
            "centre",
            format!(
                "centre {:?} is more than {FAR:e} model sizes ({size:e}) from the mesh: is it in the mesh's units?",
                def.centre
            ),
        );
    }
    if def.radius.is_finite() && def.radius > FAR * size {
        problem(
            "radius",
            format!(
                "radius {:e} exceeds {FAR:e} model sizes ({size:e}): is it in the mesh's units?",
                def.radius
            ),
        );
    }
}

fn unknown_group(an: &Analysis, name: &str) -> String {
    format!(
        "unknown group '{name}' (groups in the mesh: {})",
        an.mesh.group_list()
    )
}

/// `E/(1 − ν²)` of the material of a body element holding `node`.
fn slave_modulus(an: &Analysis, node: Option<usize>) -> Option<f64> {
    let node = node?;
    let body = an
        .body
        .iter()
        .find(|b| an.mesh.elements[b.element].nodes.contains(&node))?;
    let m = &an.materials[body.material];
    let (lambda, mu) = (m.lambda, m.mu);
    let e = mu * (3.0 * lambda + 2.0 * mu) / (lambda + mu);
    let nu = lambda / (2.0 * (lambda + mu));
    Some(e / (1.0 - nu * nu))
}

/// One increment measured against Hertz theory.
#[derive(Clone, Debug, PartialEq)]
pub struct HertzSample {
    /// Step index (0-based).
    pub step: usize,
    /// Increment within the step.
    pub increment: usize,
    /// Newton iterations of the increment.
    pub iterations: usize,
    /// Total force (symmetry applied).
    pub force: f64,
    /// Approach of the loaded group.
    pub approach: f64,
    /// `(r, p)` of the closed slave nodes, by increasing `r`.
    pub profile: Vec<(f64, f64)>,
    /// Fitted `(a, p0)`.
    pub fit: Option<(f64, f64)>,
    /// Largest nodal pressure.
    pub max_pressure: f64,
}

/// Relative errors of a sample against Hertz at the sample's own force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HertzErrors {
    /// Hertz contact radius at the computed force.
    pub radius: f64,
    /// Hertz peak pressure at the computed force.
    pub peak: f64,
    /// Fitted contact radius / Hertz − 1 (NaN without a fit).
    pub fit_radius: f64,
    /// Fitted p0 / Hertz − 1 (NaN without a fit).
    pub fit_peak: f64,
    /// Largest nodal pressure / Hertz p0 − 1.
    pub max_pressure: f64,
}

impl HertzSample {
    /// Errors against `theory`.
    #[must_use]
    pub fn errors(&self, theory: &Hertz) -> HertzErrors {
        let a = theory.contact_radius(self.force);
        let p0 = theory.peak_pressure(self.force);
        let (fa, fp) = self.fit.unwrap_or((f64::NAN, f64::NAN));
        HertzErrors {
            radius: a,
            peak: p0,
            fit_radius: fa / a - 1.0,
            fit_peak: fp / p0 - 1.0,
            max_pressure: self.max_pressure / p0 - 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const STEEL: Hertz = Hertz {
        radius: 20.0,
        modulus: 210_000.0 / 0.91,
    };

    #[test]
    fn theory_is_self_consistent() {
        let f = 20_000.0;
        let a = STEEL.contact_radius(f);
        // δ = a²/R and F = ∫ p dA = 2π p0 a²/3.
        assert!((STEEL.approach(f) - a * a / STEEL.radius).abs() < 1e-14 * a);
        let p0 = STEEL.peak_pressure(f);
        assert!((2.0 * std::f64::consts::PI * p0 * a * a / 3.0 - f).abs() < 1e-9 * f);
        assert!((STEEL.pressure(f, 0.6 * a) - 0.8 * p0).abs() < 1e-12 * p0);
        assert_eq!(STEEL.pressure(f, 1.01 * a), 0.0);
    }

    /// Without a compressive force there is no contact: every quantity is zero, never NaN, also
    /// for forces so small that `a²` underflows.
    #[test]
    fn no_force_no_contact_and_tiny_forces_stay_finite() {
        for f in [0.0, -0.0, -5.0, f64::NEG_INFINITY] {
            assert_eq!(STEEL.contact_radius(f), 0.0, "{f}");
            assert_eq!(STEEL.peak_pressure(f), 0.0, "{f}");
            assert_eq!(STEEL.pressure(f, 0.0), 0.0, "{f}");
            assert_eq!(STEEL.approach(f), 0.0, "{f}");
        }
        for f in [1e-300, f64::MIN_POSITIVE, 5e-324] {
            let (a, p0) = (STEEL.contact_radius(f), STEEL.peak_pressure(f));
            assert!(a > 0.0 && p0 > 0.0 && p0.is_finite(), "{f}: {a} {p0}");
            assert!(STEEL.pressure(f, 0.0).is_finite(), "{f}");
        }
        // The closed form of p0 is 3F/(2πa²).
        let f = 20_000.0;
        let a = STEEL.contact_radius(f);
        let p0 = 3.0 * f / (2.0 * std::f64::consts::PI * a * a);
        assert!((STEEL.peak_pressure(f) / p0 - 1.0).abs() < 1e-14);
    }

    #[test]
    fn fits_recover_exact_data() {
        let f = 20_000.0;
        let a = STEEL.contact_radius(f);
        let profile: Vec<(f64, f64)> = (0..9)
            .map(|i| {
                let r = 0.11 * a * f64::from(i);
                (r, STEEL.pressure(f, r))
            })
            .collect();
        let (fa, fp) = fit_profile(&profile).expect("fit");
        assert!((fa / a - 1.0).abs() < 1e-10 && (fp / STEEL.peak_pressure(f) - 1.0).abs() < 1e-10);
        let c = 3e-6;
        let curve: Vec<(f64, f64)> = (1..6)
            .map(|i| {
                let f = 4000.0 * f64::from(i);
                (f, STEEL.approach(f) + c * f)
            })
            .collect();
        let (k, cc) = fit_approach(&curve).expect("fit");
        assert!((k / STEEL.approach_coefficient() - 1.0).abs() < 1e-9);
        assert!((cc / c - 1.0).abs() < 1e-8);
    }

    #[test]
    fn degenerate_fits_are_none() {
        assert_eq!(fit_profile(&[(0.0, 1.0), (0.1, 1.0)]), None);
        assert_eq!(fit_profile(&[(0.0, 1.0), (0.1, 1.1), (0.2, 1.2)]), None);
        assert_eq!(fit_approach(&[(1.0, 1.0)]), None);
        assert_eq!(fit_approach(&[]), None);
    }
}
