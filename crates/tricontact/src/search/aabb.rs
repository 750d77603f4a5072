//! Axis-aligned bounding boxes: union, inflation, and the squared distance from a point.
//!
//! `distance_squared(p) = Σ_d max(min_d − p_d, 0, p_d − max_d)²`, zero inside the box. The search
//! prunes a subtree when this exceeds the best squared distance found so far.

use crate::linalg::Vec3;

/// An axis-aligned box `[min, max]`. The empty box has `min = +∞`, `max = −∞`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box, neutral for [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
        max: Vec3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
    };

    /// The smallest box holding the given points.
    #[must_use]
    #[inline]
    pub fn of_points(points: &[Vec3]) -> Aabb {
        points.iter().fold(Aabb::EMPTY, |b, p| b.union_point(p))
    }

    /// The smallest box holding `self` and `p`. The points must be finite: a NaN coordinate does
    /// not leave the box unchanged but resets that coordinate's bound, so callers leave such points
    /// out.
    #[must_use]
    #[inline]
    pub fn union_point(&self, p: &Vec3) -> Aabb {
        Aabb {
            min: self.min.inf(p),
            max: self.max.sup(p),
        }
    }

    /// The smallest box holding both boxes.
    #[must_use]
    #[inline]
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.inf(&other.min),
            max: self.max.sup(&other.max),
        }
    }

    /// The box grown by `r` on every side.
    #[must_use]
    #[inline]
    pub fn inflate(&self, r: f64) -> Aabb {
        let d = Vec3::repeat(r);
        Aabb {
            min: self.min - d,
            max: self.max + d,
        }
    }

    /// The box centre.
    #[must_use]
    #[inline]
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Squared distance from `p` to the box (zero inside).
    #[must_use]
    #[inline]
    pub fn distance_squared(&self, p: &Vec3) -> f64 {
        let below = self.min - p;
        let above = p - self.max;
        let d = below.sup(&above).sup(&Vec3::zeros());
        d.norm_squared()
    }

    /// Half the surface area `xy + yz + zx` (zero for the empty box): the refit-quality measure.
    #[must_use]
    #[inline]
    pub fn half_area(&self) -> f64 {
        let e = (self.max - self.min).sup(&Vec3::zeros());
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}
