//! Line search along a Newton correction, on the slope of the energy (`[[step]] line_search`).
//!
//! Where the residual `r(u) = f_int − f_ext` is the gradient of a potential `Π` (hyperelastic
//! bodies, dead loads, prescribed displacements, penalty contact, and augmented-Lagrangian contact
//! with its multipliers held fixed), the energy along a correction `δu` from `u₀`,
//! `φ(s) = Π(u₀ + s δu)`, has the slope
//!
//! ```text
//! g(s) = δu · r(u₀ + s δu),        g(0) = −δuᵀ K δu < 0   (Newton: K δu = −r(u₀)).
//! ```
//!
//! The full step is kept when `g(1) ≤ ρ |g(0)|` with `ρ = 0.9`: the energy is not rising steeply
//! where the step ends. Otherwise the step moves to the zero of the secant of `g` through `(0, g(0))`
//! and `(s, g(s))`, `s ← s g(0) / (g(0) − g(s))`, kept within `[0.1 s, 0.9 s]`, at most
//! [`MAX_TRIES`] times and never below [`MIN_FRACTION`]. A trial at which an element inverts is
//! halved instead. When the trials run out the last one is kept: the search damps an overshoot, it
//! does not fail an iteration (the iteration limit and the cutbacks still do).
//!
//! On a quadratic energy `g` is linear and the secant lands on the minimum at once. With contact
//! the search mostly acts on steps that push slave nodes deep into the master (a penalty node left
//! open by the previous iterate) or invert elements.
//!
//! The predictor of an increment is not searched: it also moves the prescribed degrees of freedom
//! to their targets, and shortening only its free part strains the elements next to them (in the
//! `contact-block` example with a penalty of the base's modulus, then the default, that inverted
//! elements and cost two cutbacks; searching only the corrections cost none).
//!
//! Each trial is a full evaluation: contact statuses and facets are decided again at the trial
//! point, and a status change there counts towards the node's switches (see
//! [`crate::contact`]) even if the trial is then shortened.
//!
//! The multiplier method (a saddle point: `g(0)` has no sign) and follower pressures (no
//! potential) iterate without it.

use crate::assembly::{DofMap, NO_EQ};

/// Slope ratio below which a step is kept.
pub const RHO: f64 = 0.9;

/// Trials per correction.
pub const MAX_TRIES: usize = 5;

/// Smallest fraction of a correction tried.
pub const MIN_FRACTION: f64 = 1.0 / 16.0;

/// A Newton correction being applied: its equations' values, the fraction applied so far, and the
/// slope of the energy before it.
#[derive(Clone, Debug)]
pub struct LineSearch {
    du: Vec<f64>,
    s: f64,
    g0: f64,
    tries: usize,
}

impl LineSearch {
    /// The correction `du` (over equations) that solved `K du = rhs` (`rhs = −r`), fully applied.
    #[must_use]
    pub fn new(du: Vec<f64>, rhs: &[f64]) -> Self {
        let g0 = -dot(&du, rhs);
        Self {
            du,
            s: 1.0,
            g0,
            tries: 0,
        }
    }

    /// Trials made (each a further assembly).
    #[must_use]
    pub fn tries(&self) -> usize {
        self.tries
    }

    /// The slope `g(s) = δu · r` at the current trial, from its `rhs = −r`.
    #[must_use]
    pub fn slope(&self, rhs: &[f64]) -> f64 {
        -dot(&self.du, rhs)
    }

    /// The next fraction to try after the current trial, given its slope (`None`: an element
    /// inverted there), or `None` to keep the current one.
    #[must_use]
    pub fn next(&self, slope: Option<f64>) -> Option<f64> {
        next_fraction(self.s, self.g0, slope, self.tries)
    }

    /// Moves the free equations of `u` to the fraction `s` of the correction; returns `s`.
    pub fn move_to(&mut self, s: f64, u: &mut [f64], dm: &DofMap) -> f64 {
        let back = self.s - s;
        for (dof, &e) in dm.eq.iter().enumerate() {
            if e != NO_EQ {
                u[dof] -= back * self.du[e];
            }
        }
        self.s = s;
        self.tries += 1;
        s
    }
}

/// The rule of the module doc: from fraction `s` with slope `g` there (`None`: inverted), after
/// `tries` trials, the next fraction, or `None` to keep `s`.
#[must_use]
pub fn next_fraction(s: f64, g0: f64, g: Option<f64>, tries: usize) -> Option<f64> {
    if tries >= MAX_TRIES || s <= MIN_FRACTION || g0.is_nan() || g0 >= 0.0 {
        return None;
    }
    let next = match g {
        None => 0.5 * s,
        Some(g) if g <= RHO * g0.abs() => return None,
        Some(g) => {
            let t = s * g0 / (g0 - g);
            if t.is_finite() {
                t.clamp(0.1 * s, 0.9 * s)
            } else {
                0.5 * s
            }
        }
    };
    Some(next.max(MIN_FRACTION))
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_that_ends_downhill_or_level_is_kept() {
        assert_eq!(next_fraction(1.0, -2.0, Some(-1.0), 0), None);
        assert_eq!(next_fraction(1.0, -2.0, Some(1.7), 0), None);
    }

    #[test]
    fn on_a_quadratic_energy_the_secant_finds_the_minimum() {
        // φ(s) = (s − 0.4)²: g(s) = 2(s − 0.4), g(0) = −0.8, g(1) = 1.2.
        let g = |s: f64| 2.0 * (s - 0.4);
        let s = next_fraction(1.0, g(0.0), Some(g(1.0)), 0).expect("overshoot");
        assert!((s - 0.4).abs() < 1e-15, "{s}");
        assert_eq!(next_fraction(s, g(0.0), Some(g(s)), 1), None);
    }

    #[test]
    fn a_stiffening_energy_ends_below_its_start_without_a_steep_rise() {
        // φ(s) = s⁴ − s (minimum at 4^(−1/3) ≈ 0.63): the full step ends on a steep rise,
        // g(1) = 3. The secant from (0, −1) undershoots on this convex slope; the trial kept is
        // downhill of the start and not rising steeply.
        let (phi, g) = (|s: f64| s.powi(4) - s, |s: f64| 4.0 * s.powi(3) - 1.0);
        let (mut s, mut tries) = (1.0, 0);
        while let Some(t) = next_fraction(s, g(0.0), Some(g(s)), tries) {
            s = t;
            tries += 1;
        }
        assert!((1..=MAX_TRIES).contains(&tries), "tries {tries}");
        assert!(g(s) <= RHO * g(0.0).abs() && phi(s) < phi(0.0), "s {s}");
        assert!(phi(s) < phi(1.0), "s {s}");
    }

    #[test]
    fn inversion_halves_and_the_floor_and_trial_count_stop_the_search() {
        assert_eq!(next_fraction(1.0, -1.0, None, 0), Some(0.5));
        assert_eq!(next_fraction(0.1, -1.0, None, 1), Some(MIN_FRACTION));
        assert_eq!(next_fraction(MIN_FRACTION, -1.0, None, 2), None);
        assert_eq!(next_fraction(1.0, -1.0, Some(100.0), MAX_TRIES), None);
        // A huge overshoot is cut to a tenth at most; a non-descent start is not searched.
        assert_eq!(next_fraction(1.0, -1.0, Some(1e6), 0), Some(0.1));
        assert_eq!(next_fraction(1.0, 0.5, Some(10.0), 0), None);
    }

    #[test]
    fn moving_changes_only_free_equations_by_the_fraction() {
        let dm = DofMap {
            eq: vec![0, NO_EQ, 1],
            n_eq: 2,
            n_nodal: 3,
        };
        let mut ls = LineSearch::new(vec![2.0, -4.0], &[-1.0, 0.5]);
        // g0 = −(2·(−1) + (−4)·0.5) = 4.
        assert_eq!(ls.g0, 4.0);
        let mut u = vec![12.0, 7.0, -24.0];
        assert_eq!(ls.move_to(0.25, &mut u, &dm), 0.25);
        assert_eq!(u, vec![10.5, 7.0, -21.0]);
        assert_eq!(ls.tries(), 1);
    }
}
