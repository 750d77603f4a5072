//! The incremental search's bounds for eight queries at once: which of the facets listed after a
//! query's first are excluded by the Lipschitz bound `d₀(f) − m` or by the first-order bound
//! `d₀(f) + n̂(f)·(p − p₀ − T) − s − slack`, and whether the rest of its list and the unlisted
//! facets are excluded (the formulas and their margins: [`crate::search::incremental`]).
//!
//! A query's values are put into lane `k` of a [`Stage`] (plain stores), and the tests run on
//! `wide::f64x8`, without a branch per test; the results are bit masks over the lanes. Any NaN
//! makes a test fail, so it excludes nothing.

use wide::f64x8;

use crate::linalg::Vec3;
use crate::search::direction::DIRECTION_ERROR;
use crate::search::lanes::PAIRS;

/// Listed facets after the first that are screened with both bounds.
pub(crate) const NEAR: usize = 2;

/// What a screen needs of a listed facet: its distance then, its direction then (decoded), and
/// how it moved (the translation `T` and the spread `s`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Listed {
    pub(crate) distance: f64,
    pub(crate) direction: Vec3,
    pub(crate) translation: Vec3,
    pub(crate) spread: f64,
}

/// The values of eight queries, lane by lane.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Stage {
    /// The query point when the lists were made, `p₀`.
    point: [[f64; PAIRS]; 3],
    /// The reach `ρ` (`+∞` without any facet).
    reach: [f64; PAIRS],
    /// The distance then of the facet listed after the screened ones.
    after: [f64; PAIRS],
    distance: [[f64; PAIRS]; NEAR],
    direction: [[[f64; PAIRS]; 3]; NEAR],
    translation: [[[f64; PAIRS]; 3]; NEAR],
    spread: [[f64; PAIRS]; NEAR],
}

/// The outcome of a screen, as lane masks: per screened facet, the lanes that must measure it; the
/// lanes whose later listed facets are all excluded; the lanes whose unlisted facets are.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Outcome {
    pub(crate) need: [u32; NEAR],
    pub(crate) later: u32,
    pub(crate) unlisted: u32,
}

/// What all queries share: the largest node motion `δ`, the search distance, the relative margin.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Limits {
    pub(crate) delta: f64,
    pub(crate) max_distance: f64,
    pub(crate) margin: f64,
}

impl Stage {
    /// Puts a query into lane `k`: its point then, reach, the distance of the facet listed after
    /// the screened ones, and those facets.
    #[inline(always)]
    pub(crate) fn set(
        &mut self,
        k: usize,
        point: &Vec3,
        (reach, after): (f64, f64),
        listed: &[Listed; NEAR],
    ) {
        for d in 0..3 {
            self.point[d][k] = point[d];
        }
        self.reach[k] = reach;
        self.after[k] = after;
        for (j, l) in listed.iter().enumerate() {
            self.distance[j][k] = l.distance;
            self.spread[j][k] = l.spread;
            for d in 0..3 {
                self.direction[j][d][k] = l.direction[d];
                self.translation[j][d][k] = l.translation[d];
            }
        }
    }

    /// Screens the lanes whose query points are `p` (coordinate by coordinate) and whose first
    /// listed facets are at the distances `b` now.
    #[inline]
    pub(crate) fn screen(&self, p: &[[f64; PAIRS]; 3], b: f64x8, limits: Limits) -> Outcome {
        let w = |a: &[f64; PAIRS]| f64x8::new(*a);
        let zero = f64x8::ZERO;
        let p = [w(&p[0]), w(&p[1]), w(&p[2])];
        let p0 = [w(&self.point[0]), w(&self.point[1]), w(&self.point[2])];
        let dp = [p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]];
        let m = (dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]).sqrt() + f64x8::splat(limits.delta);
        let amax = |v: &[f64x8; 3]| v[0].abs().fast_max(v[1].abs()).fast_max(v[2].abs());
        let reach = w(&self.reach);
        let finite = reach.is_finite().select(reach, zero);
        let tol = f64x8::splat(limits.margin) * (amax(&p) + amax(&p0) + finite);
        let beyond = |d0: f64x8| (d0 - m).simd_gt(b + tol);
        let mut need = [0u32; NEAR];
        for (j, need) in need.iter_mut().enumerate() {
            let d0 = w(&self.distance[j]);
            let t = &self.translation[j];
            let u = &self.direction[j];
            let v = [dp[0] - w(&t[0]), dp[1] - w(&t[1]), dp[2] - w(&t[2])];
            let l1 = v[0].abs() + v[1].abs() + v[2].abs();
            let slack = tol + f64x8::splat(DIRECTION_ERROR) * l1;
            let along = w(&u[0]) * v[0] + w(&u[1]) * v[1] + w(&u[2]) * v[2];
            let lower = d0 + along - w(&self.spread[j]) - slack;
            *need = (!(beyond(d0) | lower.simd_gt(b))).to_bitmask();
        }
        // Facets not listed are farther than `reach − m` now.
        let limit = reach - m - tol;
        let unlisted = b.simd_lt(limit) | f64x8::splat(limits.max_distance).simd_lt(limit);
        Outcome {
            need,
            later: beyond(w(&self.after)).to_bitmask(),
            unlisted: unlisted.to_bitmask(),
        }
    }
}
