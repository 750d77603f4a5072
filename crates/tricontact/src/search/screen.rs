//! The incremental search's bounds for a vector of queries at once (one per lane: eight with
//! AVX-512, four otherwise): which of the facets listed after a query's first are excluded by the
//! first-order bound `d₀(f) − r + n̂(f)·(p − p₀) − slack` (`r` the rise of the facet's nodes along
//! `n̂`, `slack = tol + ε m` the same for all of a query's facets), and whether the rest of its
//! list (the Lipschitz bound `d₀(f) − m`) and the unlisted facets are excluded (the formulas and
//! their margins: [`crate::search::incremental`]). The first-order bound is below the Lipschitz
//! bound by at most `2 ε m` (`|n̂| ≤ 1 + ε`), so the screened facets are tested by it alone.
//!
//! [`Bounds`] is the scalar form, one query at a time (the walks beyond a query's record, and the
//! queries answered one facet at a time). For the lanes' queries at once, their values are put
//! into lane `k` of a [`Stage`] (plain stores), and the same tests, operation for operation, run
//! on the lanes' vectors (`lanes::V`) without a branch per test; the results are bit masks over
//! the lanes. Any NaN makes a test fail, so it excludes nothing.

use crate::linalg::Vec3;
use crate::search::direction::DIRECTION_ERROR;
use crate::search::lanes::{PAIRS, V, load};

/// Relative margin of the certificate, on the magnitude of the coordinates and distances.
pub(crate) const MARGIN: f64 = 1e-9;

/// Listed facets after the first that are screened by the first-order bound.
pub(crate) const NEAR: usize = 2;

/// What a screen needs of a listed facet: its level `d₀(f) − r`, its distance then less the rise
/// `r = maxₙ n̂·mₙ` of its nodes along its direction since (`r` is negative when the facet moved
/// away along `n̂`), and that direction `n̂` then (decoded).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Listed {
    pub(crate) level: f64,
    pub(crate) direction: Vec3,
}

/// The values of [`PAIRS`] queries, lane by lane.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Stage {
    /// The query point when the lists were made, `p₀`.
    point: [[f64; PAIRS]; 3],
    /// The reach `ρ` (`+∞` without any facet).
    reach: [f64; PAIRS],
    /// The distance then of the facet listed after the screened ones.
    after: [f64; PAIRS],
    /// The screened facets' `d₀(f) − r`.
    level: [[f64; PAIRS]; NEAR],
    direction: [[[f64; PAIRS]; 3]; NEAR],
}

/// The outcome of a screen, as lane masks: per screened facet, the lanes that must measure it; the
/// lanes whose later listed facets are all excluded; the lanes whose unlisted facets are.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Outcome {
    pub(crate) need: [u32; NEAR],
    pub(crate) later: u32,
    pub(crate) unlisted: u32,
}

/// What all queries share: the largest node motion `δ` and the search distance.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Limits {
    pub(crate) delta: f64,
    pub(crate) max_distance: f64,
}

/// One query's bounds: its motion `dp = p − p₀`, `m = |dp| + δ` of the Lipschitz bound, the margin
/// `tol` on distances, the first-order bound's `slack = tol + ε m`, and its reach `ρ`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bounds {
    pub(crate) dp: Vec3,
    m: f64,
    tol: f64,
    slack: f64,
    reach: f64,
}

impl Bounds {
    /// The bounds of a query at `p` whose list was made at `p0` with reach `reach` (`+∞` for an
    /// empty list), after the nodes moved by at most `delta`.
    #[inline(always)]
    pub(crate) fn new(p: &Vec3, p0: &Vec3, reach: f64, delta: f64) -> Self {
        let dp = p - p0;
        let finite = if reach.is_finite() { reach } else { 0.0 };
        let m = dp.norm() + delta;
        let tol = MARGIN * (p.amax() + p0.amax() + finite);
        Self {
            dp,
            m,
            tol,
            slack: tol + DIRECTION_ERROR * m,
            reach,
        }
    }

    /// `true` when a listed facet at the distance `d0` then, and every one listed after it, is
    /// farther than `b` now (the Lipschitz bound `d₀(f) − m`).
    #[inline(always)]
    pub(crate) fn beyond(&self, d0: f64, b: f64) -> bool {
        d0 - self.m > b + self.tol
    }

    /// `true` when the listed facet `l` is farther than `b` now by the first-order bound.
    #[inline(always)]
    pub(crate) fn excludes(&self, l: &Listed, b: f64) -> bool {
        l.level + l.direction.dot(&self.dp) - self.slack > b
    }

    /// `true` when the facets not listed are farther than `b`, or than the search distance, now
    /// (they were farther than `ρ`, so they are now farther than `ρ − m`).
    #[inline(always)]
    pub(crate) fn unlisted(&self, b: f64, max_distance: f64) -> bool {
        let limit = self.reach - self.m - self.tol;
        b < limit || max_distance < limit
    }
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
            self.level[j][k] = l.level;
            for d in 0..3 {
                self.direction[j][d][k] = l.direction[d];
            }
        }
    }

    /// Screens the lanes whose query points are `p` (coordinate by coordinate) and whose first
    /// listed facets are at the distances `b` now: [`Bounds`] lane by lane.
    #[inline]
    pub(crate) fn screen(&self, p: &[[f64; PAIRS]; 3], b: V, limits: Limits) -> Outcome {
        let w = |a: &[f64; PAIRS]| V::new(*a);
        let zero = V::ZERO;
        let (p, p0) = (load(p), load(&self.point));
        let dp = [p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]];
        let m = (dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]).sqrt() + V::splat(limits.delta);
        let amax = |v: &[V; 3]| v[0].abs().fast_max(v[1].abs()).fast_max(v[2].abs());
        let reach = w(&self.reach);
        let finite = reach.is_finite().select(reach, zero);
        let tol = V::splat(MARGIN) * (amax(&p) + amax(&p0) + finite);
        let slack = tol + V::splat(DIRECTION_ERROR) * m;
        let mut need = [0u32; NEAR];
        for (j, need) in need.iter_mut().enumerate() {
            let u = load(&self.direction[j]);
            let along = u[0] * dp[0] + u[1] * dp[1] + u[2] * dp[2];
            let lower = w(&self.level[j]) + along - slack;
            *need = (!lower.simd_gt(b)).to_bitmask();
        }
        // Facets not listed are farther than `reach − m` now.
        let limit = reach - m - tol;
        let unlisted = b.simd_lt(limit) | V::splat(limits.max_distance).simd_lt(limit);
        Outcome {
            need,
            later: (w(&self.after) - m).simd_gt(b + tol).to_bitmask(),
            unlisted: unlisted.to_bitmask(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::scenes::uniform;

    /// The lanes of [`Stage::screen`] against [`Bounds`], query by query, on random values around
    /// the decision thresholds (and NaN among them): the same masks, bit for bit.
    #[test]
    fn the_screen_is_the_scalar_bounds_lane_by_lane() {
        let mut r = uniform(31);
        let mut v = |s: f64| Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * s;
        let (mut needed, mut excluded) = (0, 0);
        for round in 0..2000 {
            let limits = Limits {
                delta: 0.01 * v(1.0).x.abs(),
                max_distance: if round % 3 == 0 { 0.3 } else { f64::INFINITY },
            };
            let mut stage = Stage::default();
            let mut p = [[0.0; PAIRS]; 3];
            let mut b = [0.0; PAIRS];
            let mut lanes = Vec::new();
            for k in 0..PAIRS {
                let p0 = v(4.0);
                let q = p0 + v(0.1);
                let first = 0.2 + v(0.2).x;
                let listed: [Listed; NEAR] = std::array::from_fn(|_| {
                    let distance = first + v(0.1).x.abs();
                    let direction = v(2.0).normalize();
                    let rise = v(0.04).x;
                    Listed {
                        level: distance - rise,
                        direction,
                    }
                });
                let reach = if k == 7 { f64::INFINITY } else { first + 0.15 };
                let after = if k == 6 {
                    f64::NAN
                } else {
                    first + v(0.2).x.abs()
                };
                stage.set(k, &p0, (reach, after), &listed);
                for d in 0..3 {
                    p[d][k] = q[d];
                }
                b[k] = first;
                lanes.push((Bounds::new(&q, &p0, reach, limits.delta), listed, after));
            }
            let out = stage.screen(&p, V::new(b), limits);
            for (k, (bounds, listed, after)) in lanes.iter().enumerate() {
                let bit = |mask: u32| mask & (1 << k) != 0;
                for (j, l) in listed.iter().enumerate() {
                    let skip = bounds.excludes(l, b[k]);
                    assert_eq!(bit(out.need[j]), !skip, "round {round} lane {k} facet {j}");
                    needed += usize::from(!skip);
                    excluded += usize::from(skip);
                }
                assert_eq!(bit(out.later), bounds.beyond(*after, b[k]));
                let unlisted = bounds.unlisted(b[k], limits.max_distance);
                assert_eq!(bit(out.unlisted), unlisted, "round {round} lane {k}");
            }
        }
        // Both outcomes occur often: the values straddle the thresholds.
        assert!(
            needed > 2000 && excluded > 2000,
            "{needed} needed, {excluded} excluded"
        );
    }
}
