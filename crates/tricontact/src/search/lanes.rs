//! The kernel's Voronoi-region computation lane by lane: the up to [`LANES`] facets of a group
//! of a tree leaf ([`groups`]) against one point, or [`LANES`] (point, facet) pairs at once (the
//! incremental search).
//!
//! The arithmetic is exactly that of [`distance_squared_to_triangle`], operation for operation:
//! the six dot products `d1 … d6` of the edges `ab`, `ac` with `p − a`, `p − b`, `p − c`, the
//! three scaled sub-areas `va, vb, vc`, the edge parameters and the face's barycentric coordinates,
//! and finally `|p − (a N_a + b N_b + c N_c)|²`. The scalar kernel picks the first Voronoi region
//! whose test holds (vertices, then edges, then the face); here every lane computes every
//! candidate and selects by the same priority, without branches, one vector [`V`] per quantity.
//! The results are bit for bit those of the scalar kernel (no fused multiply–add on either side):
//! the tree compares exactly the numbers the brute-force search compares. A lane whose selected
//! coordinates are not finite (extreme coordinates, where the scalar kernel rescales), or whose
//! facet is thin (`closest::point_triangle::is_thin`, by the same operations: the scalar kernel
//! then takes the sub-areas from the facet's normal), is recomputed with the scalar kernel. One
//! body ([`region`]) serves both uses.
//!
//! # Lane width
//! One measurement is one machine register per quantity: eight lanes (`wide::f64x8`) where the
//! build targets AVX-512, four (`wide::f64x4`, one AVX register) otherwise. A tree leaf of up to
//! eight facets ([`crate::search::LEAF_SIZE`]) is therefore measured as one group of eight lanes
//! or as up to two groups of four ([`groups`]), and the incremental search takes its queries a
//! group of lanes at a time. With four lanes, `wide` was measured 1.5–1.7× faster than the same
//! code on `[f64; 4]` arrays, which the compiler left scalar. Without AVX-512 an `f64x8` is two
//! AVX registers, and the region arithmetic's thirty-odd live vectors no longer fit in the sixteen
//! registers: they spill to the stack. On an AMD EPYC (Zen 3, AVX2), leaves of eight measured in
//! two groups of four answered coherent queries 12 % faster than in one `f64x8` (532 → 471 ns at
//! 10⁵ facets, 559 → 492 ns at 10⁶, `search_loop closest`, interleaved runs), and the incremental
//! search's groups of four cost what groups of eight did (within 3 %). On an AMD EPYC Zen 4, whose
//! AVX-512 runs on 256-bit units, eight lanes in one `f64x8` are the faster: the same code built
//! without AVX-512 (groups of four) took 39 % longer for coherent queries at 10⁵ and 13 % at 10⁶
//! (520 vs 375 ns, 533 vs 472 ns). Building with
//! `RUSTFLAGS="-C target-cpu=native --cfg tricontact_eight_lanes"` makes the lanes eight wide on
//! any machine: to test that width where it is not the default, and to repeat the comparison.

#[cfg(not(any(
    all(target_arch = "x86_64", target_feature = "avx512f"),
    tricontact_eight_lanes
)))]
use wide::f64x4 as Vector;
#[cfg(any(
    all(target_arch = "x86_64", target_feature = "avx512f"),
    tricontact_eight_lanes
))]
use wide::f64x8 as Vector;

use crate::closest::point_triangle::THIN;
use crate::closest::{
    ClosestPoint, Feature, closest_point_and_distance_squared, closest_point_on_triangle,
    distance_squared_to_triangle,
};
use crate::linalg::Vec3;

/// One quantity of every lane: the facets of a group, or the pairs of [`closest_pairs`].
pub(crate) type V = Vector;

/// Lanes of one measurement: the facets of one group evaluated together (eight with AVX-512,
/// four otherwise; see the module documentation).
pub(crate) const LANES: usize = std::mem::size_of::<V>() / std::mem::size_of::<f64>();

/// (point, facet) pairs evaluated together by [`closest_pairs`]: one lane each.
pub(crate) const PAIRS: usize = LANES;

/// Lane-wise dot product, summed as nalgebra sums a 3-vector dot: `(x·x + y·y) + z·z`.
#[inline(always)]
fn dot(u: &[V; 3], v: &[V; 3]) -> V {
    u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
}

/// Lane-wise `u − v`.
#[inline(always)]
fn sub(u: &[V; 3], v: &[V; 3]) -> [V; 3] {
    [u[0] - v[0], u[1] - v[1], u[2] - v[2]]
}

/// Where `mask` is set, takes `value` into `n` (a bitwise select, no branch).
#[inline(always)]
fn select(n: &mut [V; 3], mask: V, value: [V; 3]) {
    for (dst, src) in n.iter_mut().zip(value) {
        *dst = mask.select(src, *dst);
    }
}

/// What the region computation gives per lane.
pub(crate) struct Region {
    /// Barycentric coordinates of the closest point.
    pub(crate) n: [V; 3],
    /// The closest point `a N_a + b N_b + c N_c`.
    pub(crate) point: [V; 3],
    /// `|p − point|²`.
    pub(crate) d2: V,
    /// Feature masks, in the scalar kernel's priority: vertices 0, 1, 2, edges 0, 1, 2.
    pub(crate) masks: [V; 6],
    /// Bits of the lanes whose coordinates are not finite (to be recomputed by the scalar kernel).
    pub(crate) bad: u32,
}

/// The Voronoi region, closest point and squared distance of `p` and the facet `(a, b, c)`, lane
/// by lane (see the module documentation).
#[inline(always)]
pub(crate) fn region(a: &[V; 3], b: &[V; 3], c: &[V; 3], pl: &[V; 3]) -> Region {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(pl, a));
    let (bp, cp) = (sub(&ap, &ab), sub(&ap, &ac));
    let (d1, d2) = (dot(&ab, &ap), dot(&ac, &ap));
    let (d3, d4) = (dot(&ab, &bp), dot(&ac, &bp));
    let (d5, d6) = (dot(&ab, &cp), dot(&ac, &cp));
    let vc = d1 * d4 - d3 * d2;
    let va = d3 * d6 - d5 * d4;
    let vb = d5 * d2 - d1 * d6;
    // The region tests, in the scalar kernel's order of priority (vertices, edges, face).
    let (zero, one) = (V::ZERO, V::ONE);
    let v0 = d1.simd_le(zero) & d2.simd_le(zero);
    let v1 = d3.simd_ge(zero) & d4.simd_le(d3);
    let v2 = d6.simd_ge(zero) & d5.simd_le(d6);
    let e0 = vc.simd_le(zero) & d1.simd_ge(zero) & d3.simd_le(zero);
    let e1 = va.simd_le(zero) & d4.simd_ge(d3) & d5.simd_ge(d6);
    let e2 = vb.simd_le(zero) & d2.simd_ge(zero) & d6.simd_le(zero);
    let vertex = v0 | v1 | v2;
    // One division per lane, that of the region selected: the face's `1 / (va + vb + vc)` or an
    // edge's parameter, each the scalar kernel's own quotient (a vertex needs none). The face,
    // then each region of higher priority overrides it where its test holds.
    let (mut num, mut den) = (one, va + vb + vc);
    let d43 = d4 - d3;
    for (mask, (n, d)) in [
        (e2, (d2, d2 - d6)),
        (e1, (d43, d43 + (d5 - d6))),
        (e0, (d1, d1 - d3)),
        (vertex, (one, one)),
    ] {
        num = mask.select(n, num);
        den = mask.select(d, den);
    }
    let t = num / den;
    let mut n = [va * t, vb * t, vc * t];
    select(&mut n, e2, [one - t, zero, t]);
    select(&mut n, e1, [zero, one - t, t]);
    select(&mut n, e0, [one - t, t, zero]);
    select(&mut n, v2, [zero, zero, one]);
    select(&mut n, v1, [zero, one, zero]);
    select(&mut n, v0, [one, zero, zero]);
    // |p − (a N_a + b N_b + c N_c)|², summed as nalgebra sums it.
    let point: [V; 3] = std::array::from_fn(|d| a[d] * n[0] + b[d] * n[1] + c[d] * n[2]);
    let diff = sub(pl, &point);
    // A thin facet (the scalar kernel's test, operation for operation) is measured by the scalar
    // kernel, which computes its sub-areas from its normal.
    let (ab2, ac2, abac) = (d1 - d3, d2 - d6, d2 - d4);
    let lengths = ab2 * ac2;
    let thin = !(lengths - abac * abac).simd_ge(V::splat(THIN) * lengths);
    let bad = (thin | !(n[0].is_finite() & n[1].is_finite() & n[2].is_finite())).to_bitmask();
    Region {
        n,
        point,
        d2: dot(&diff, &diff),
        masks: [v0, v1, v2, e0, e1, e2],
        bad,
    }
}

/// What a leaf's measurement gives per lane: the squared distance, the barycentric coordinates of
/// the closest point and its feature (a number into [`FEATURES`], or [`RECOMPUTE`] for a lane the
/// scalar kernel measured: its distance is right, its coordinates are to be recomputed).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Measured {
    pub(crate) d2: V,
    pub(crate) n: [V; 3],
    pub(crate) code: V,
}

/// The feature number of a lane measured by the scalar kernel (see [`Measured`]).
pub(crate) const RECOMPUTE: u8 = 7;

/// Measures `p` against the group (see [`groups`]) of `count` facets whose rows start at
/// `rows[0]` (see `Bvh::rows`). Lanes at and beyond `count` hold whatever follows and are to be
/// ignored.
#[inline(always)]
pub(crate) fn measure_leaf(rows: &[f64], count: usize, p: &Vec3) -> Measured {
    let corner = |v: usize| -> [V; 3] { std::array::from_fn(|d| row(rows, count, 3 * v + d)) };
    let (a, b, c) = (corner(0), corner(1), corner(2));
    let pl: [V; 3] = std::array::from_fn(|d| V::splat(p[d]));
    let r = region(&a, &b, &c, &pl);
    let mut measured = Measured {
        d2: r.d2,
        n: r.n,
        code: feature_codes(&r.masks),
    };
    let bad = r.bad & ((1 << count) - 1);
    if bad != 0 {
        let mut d2 = r.d2.to_array();
        let mut code = measured.code.to_array();
        for k in 0..count {
            if bad & (1 << k) != 0 {
                let [a, b, c] = leaf_corners(rows, count, k);
                d2[k] = distance_squared_to_triangle(&a, &b, &c, p);
                code[k] = f64::from(RECOMPUTE);
            }
        }
        measured.d2 = V::new(d2);
        measured.code = V::new(code);
    }
    measured
}

/// The leaf `(first, count)` cut into its head of at most [`LANES`] facets and the rest, each
/// `(first slot, count)` (the rest empty with AVX-512): the groups of [`groups`], for the hot path
/// that measures them without an iterator.
#[inline(always)]
pub(crate) fn halves(first: usize, count: usize) -> [(usize, usize); 2] {
    let head = count.min(LANES);
    [(first, head), (first + head, count - head)]
}

const _: () = assert!(
    crate::search::LEAF_SIZE <= 2 * LANES,
    "a leaf is at most two groups"
);

/// The groups of at most [`LANES`] facets, `(first slot, count)`, that the leaf `(first, count)`
/// is stored and measured as (one with AVX-512, up to two otherwise): each has its own block of
/// rows (see `Bvh::rows`).
#[inline(always)]
pub(crate) fn groups(first: usize, count: usize) -> impl Iterator<Item = (usize, usize)> {
    halves(first, count).into_iter().filter(|&(_, n)| n > 0)
}

/// Rows per facet of a leaf's block (see `Bvh::rows`): nine coordinates, then the facet index.
pub(crate) const ROWS: usize = 10;

/// The row of a leaf's block holding the facet indices (as `f64`, exact).
const FACET_ROW: usize = 9;

/// Writes facet `k` of a group of `count` facets into the group's block of rows: coordinate
/// `r = 3v + d` of corner `v` at `r count + k`, the facet index at `9 count + k`.
#[inline]
pub(crate) fn write_leaf(
    block: &mut [f64],
    count: usize,
    k: usize,
    corners: &[Vec3; 3],
    facet: u32,
) {
    for r in 0..FACET_ROW {
        block[r * count + k] = corners[r / 3][r % 3];
    }
    block[FACET_ROW * count + k] = f64::from(facet);
}

/// The corners of facet `k` of the group of `count` facets whose rows start at `rows[0]` (the
/// inverse of [`write_leaf`]).
#[inline]
pub(crate) fn leaf_corners(rows: &[f64], count: usize, k: usize) -> [Vec3; 3] {
    let x = |r: usize| rows[r * count + k];
    std::array::from_fn(|v| Vec3::new(x(3 * v), x(3 * v + 1), x(3 * v + 2)))
}

/// The feature of each lane as a number into [`FEATURES`]: the first mask set in priority order
/// (vertices 0, 1, 2, edges 3, 4, 5), 6 for the face.
#[inline(always)]
fn feature_codes(masks: &[V; 6]) -> V {
    let mut code = V::splat(6.0);
    for (m, mask) in masks.iter().enumerate().rev() {
        #[allow(clippy::cast_precision_loss)]
        let value = V::splat(m as f64);
        code = mask.select(value, code);
    }
    code
}

/// Row `r` of a group of `count` facets whose rows start at `rows[0]`: [`LANES`] lanes, the
/// first `count` of them the group's.
#[inline(always)]
pub(crate) fn row(rows: &[f64], count: usize, r: usize) -> V {
    let at = r * count;
    V::new(
        rows[at..at + LANES]
            .try_into()
            .expect("one vector of lanes"),
    )
}

/// Lane numbers `0, 1, …, LANES − 1`.
#[inline(always)]
fn lane() -> V {
    #[allow(clippy::cast_precision_loss)]
    V::new(std::array::from_fn(|k| k as f64))
}

/// The best facet in each lane over the leaves offered so far, in the order (squared distance,
/// facet index), with where it came from and its closest point: facets, slots, gathered-leaf
/// numbers and feature numbers as exact `f64`. The best over all lanes is the best over all
/// offers, whatever lane each offer came in; updating it is branch-free.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LaneBest {
    d2: V,
    facet: V,
    slot: V,
    leaf: V,
    n: [V; 3],
    code: V,
}

/// The best of a [`LaneBest`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Winner {
    pub(crate) d2: f64,
    pub(crate) facet: u32,
    pub(crate) slot: u32,
    /// The gathered leaf it came from (`None` for the seed).
    pub(crate) leaf: Option<u32>,
    /// Barycentric coordinates of the closest point, valid when `feature` is one of [`FEATURES`].
    pub(crate) n: [f64; 3],
    /// A number into [`FEATURES`], or [`RECOMPUTE`].
    pub(crate) feature: u8,
}

impl Winner {
    /// The closest point on the winning facet, whose corners are `corners`: bit for bit
    /// [`closest_point_on_triangle`]'s, from the lanes' coordinates where they hold (those of
    /// [`closest_point_and_distance_squared`], which differ only for a triangle below
    /// [`crate::closest::TINY`], which no tree holds).
    #[inline]
    pub(crate) fn closest(&self, [a, b, c]: &[Vec3; 3], p: &Vec3) -> ClosestPoint {
        let Some(&feature) = FEATURES.get(usize::from(self.feature)) else {
            return closest_point_on_triangle(a, b, c, p);
        };
        // Summed as the lanes sum it (and as the scalar kernel does).
        let [na, nb, nc] = self.n;
        ClosestPoint {
            feature,
            barycentric: self.n,
            point: a * na + b * nb + c * nc,
            distance: self.d2.sqrt(),
        }
    }
}

impl LaneBest {
    /// Nothing offered yet: every lane at `max2` with no facet (`+∞`), so that a facet at `max2`
    /// is still taken.
    #[inline(always)]
    pub(crate) fn new(max2: f64) -> Self {
        Self {
            d2: V::splat(max2),
            facet: V::splat(f64::INFINITY),
            slot: V::splat(-1.0),
            leaf: V::splat(-1.0),
            n: [V::ZERO; 3],
            code: V::splat(f64::from(RECOMPUTE)),
        }
    }

    /// Offers one candidate, not from a gathered leaf, in lane 0 (its closest point is to be
    /// recomputed).
    #[inline]
    pub(crate) fn seed(&mut self, d2: f64, facet: u32, slot: u32) {
        let one = |v: f64| V::new(std::array::from_fn(|k| if k == 0 { v } else { 0.0 }));
        let measured = Measured {
            d2: one(d2),
            n: [V::ZERO; 3],
            code: V::splat(f64::from(RECOMPUTE)),
        };
        let lane0 = lane().simd_eq(V::ZERO);
        self.take(
            &measured,
            one(f64::from(facet)),
            one(f64::from(slot)),
            -1.0,
            lane0,
        );
    }

    /// Offers the lanes `live` of a measurement, with their facet indices and slots, from the
    /// gathered leaf `leaf`. A lane whose distance is NaN is never taken.
    #[inline(always)]
    fn take(&mut self, m: &Measured, facet: V, slot: V, leaf: f64, live: V) {
        let better = m.d2.simd_lt(self.d2) | (m.d2.simd_eq(self.d2) & facet.simd_lt(self.facet));
        let take = better & live;
        self.d2 = take.select(m.d2, self.d2);
        self.facet = take.select(facet, self.facet);
        self.slot = take.select(slot, self.slot);
        self.leaf = take.select(V::splat(leaf), self.leaf);
        for (n, new) in self.n.iter_mut().zip(m.n) {
            *n = take.select(new, *n);
        }
        self.code = take.select(m.code, self.code);
    }

    /// Offers the measurement `m` of the `count` facets of the leaf whose rows start at
    /// `rows[0]` and slots at `first` (lanes past `count` ignored), as the gathered leaf `leaf`.
    #[inline(always)]
    pub(crate) fn take_leaf(
        &mut self,
        rows: &[f64],
        (first, count): (usize, usize),
        m: &Measured,
        leaf: u32,
    ) {
        #[allow(clippy::cast_precision_loss)]
        let (at, live) = (first as f64, count as f64);
        self.take(
            m,
            row(rows, count, FACET_ROW),
            V::splat(at) + lane(),
            f64::from(leaf),
            lane().simd_lt(V::splat(live)),
        );
    }

    /// The smallest squared distance of all lanes (`max2` while nothing was taken).
    #[inline(always)]
    pub(crate) fn bound(&self) -> f64 {
        smallest(self.d2)
    }

    /// The best over all lanes, `None` when nothing was taken: the smallest facet index among the
    /// lanes at the smallest distance, from the lowest such lane (the same facet may sit in two
    /// lanes, the seed's and a leaf's, with the same distance). Found without branches: two
    /// horizontal minima and a mask.
    #[inline]
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    pub(crate) fn best(&self) -> Option<Winner> {
        let d2 = self.bound();
        let tied = self.d2.simd_eq(V::splat(d2));
        let facets = tied.select(self.facet, V::splat(f64::INFINITY));
        let facet = smallest(facets);
        if facet == f64::INFINITY {
            return None;
        }
        let k = facets
            .simd_eq(V::splat(facet))
            .to_bitmask()
            .trailing_zeros() as usize;
        let leaf = self.leaf.as_array()[k];
        Some(Winner {
            d2,
            facet: facet as u32,
            slot: self.slot.as_array()[k] as u32,
            leaf: (leaf >= 0.0).then_some(leaf as u32),
            n: self.n.map(|n| n.as_array()[k]),
            feature: self.code.as_array()[k] as u8,
        })
    }
}

/// The smallest of the lanes (a tree of comparisons, no branch). The lanes of a [`LaneBest`]
/// are never NaN (a NaN offer is not taken) unless all are (a NaN search distance): the result is
/// then NaN, as `f64::min` would give.
#[inline(always)]
fn smallest(v: V) -> f64 {
    let m = |a: f64, b: f64| if b < a { b } else { a };
    let mut d = v.to_array();
    let mut half = LANES / 2;
    while half > 0 {
        for k in 0..half {
            d[k] = m(d[k], d[k + half]);
        }
        half /= 2;
    }
    d[0]
}

/// Three coordinates of the lanes as vectors.
#[inline(always)]
pub(crate) fn load(v: &[[f64; PAIRS]; 3]) -> [V; 3] {
    [V::new(v[0]), V::new(v[1]), V::new(v[2])]
}

/// [`PAIRS`] (point, facet) pairs, coordinate by coordinate: `corners[v][d][k]` is coordinate `d`
/// of corner `v` of pair `k`'s facet, `points[d][k]` coordinate `d` of its point.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Pairs {
    pub(crate) corners: [[[f64; PAIRS]; 3]; 3],
    pub(crate) points: [[f64; PAIRS]; 3],
}

impl Pairs {
    /// Puts the facet `corners` and the point `p` into lane `k`.
    #[inline(always)]
    pub(crate) fn set(&mut self, k: usize, corners: &[Vec3; 3], p: &Vec3) {
        for (v, x) in corners.iter().enumerate() {
            for d in 0..3 {
                self.corners[v][d][k] = x[d];
            }
        }
        for d in 0..3 {
            self.points[d][k] = p[d];
        }
    }

    /// Lane `k`'s facet corners and point.
    fn lane(&self, k: usize) -> ([Vec3; 3], Vec3) {
        let c = &self.corners;
        let corner = |v: usize| Vec3::new(c[v][0][k], c[v][1][k], c[v][2][k]);
        let p = &self.points;
        (
            [corner(0), corner(1), corner(2)],
            Vec3::new(p[0][k], p[1][k], p[2][k]),
        )
    }
}

/// The features by the number [`closest_pairs`] gives them: the region masks' order, then the face.
const FEATURES: [Feature; 7] = [
    Feature::Vertex(0),
    Feature::Vertex(1),
    Feature::Vertex(2),
    Feature::Edge(0),
    Feature::Edge(1),
    Feature::Edge(2),
    Feature::Face,
];

/// The closest point and squared distance of each pair `k` whose bit is set in `live`, bit for
/// bit those of [`closest_point_and_distance_squared`], handed to `emit(k, closest, d2)` (so a
/// caller writes them where they belong, without an intermediate array).
///
/// Returns the distances of all lanes as a vector (for a caller that goes on in lanes), exact
/// where the lanes needed no scalar fallback (`None` when some did).
#[inline]
pub(crate) fn closest_pairs(
    pairs: &Pairs,
    live: u32,
    mut emit: impl FnMut(usize, ClosestPoint, f64),
) -> Option<V> {
    let (a, b, c) = (
        load(&pairs.corners[0]),
        load(&pairs.corners[1]),
        load(&pairs.corners[2]),
    );
    let r = region(&a, &b, &c, &load(&pairs.points));
    let distance_lanes = r.d2.sqrt();
    let n = r.n.map(V::to_array);
    let point = r.point.map(V::to_array);
    let d2 = r.d2.to_array();
    let distance = distance_lanes.to_array();
    let code = feature_codes(&r.masks).trunc_int().to_array();
    let mut left = live;
    while left != 0 {
        let k = left.trailing_zeros() as usize;
        left &= left - 1;
        if r.bad & (1 << k) != 0 {
            let ([a, b, c], p) = pairs.lane(k);
            let (closest, d2) = closest_point_and_distance_squared(&a, &b, &c, &p);
            emit(k, closest, d2);
            continue;
        }
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let closest = ClosestPoint {
            feature: FEATURES[(code[k] as usize).min(6)],
            barycentric: [n[0][k], n[1][k], n[2][k]],
            point: Vec3::new(point[0][k], point[1][k], point[2][k]),
            distance: distance[k],
        };
        emit(k, closest, d2[k]);
    }
    (r.bad & live == 0).then_some(distance_lanes)
}

/// Bits of the pairs whose facets are clearly not degenerate: twice the area `|w|` above
/// `tolerance` times the longest edge squared (and `|w|²` a normal number) with room for any
/// rounding, so that [`crate::Facet::new`] accepts them. The other lanes are to be decided by it.
#[inline]
pub(crate) fn clearly_valid(pairs: &Pairs, tolerance: f64) -> u32 {
    let [a, b, c] = pairs.corners.each_ref().map(load);
    let (ab, ac, bc) = (sub(&b, &a), sub(&c, &a), sub(&c, &b));
    let w = [
        ab[1] * ac[2] - ab[2] * ac[1],
        ab[2] * ac[0] - ab[0] * ac[2],
        ab[0] * ac[1] - ab[1] * ac[0],
    ];
    let w2 = dot(&w, &w);
    let longest = dot(&ab, &ab).max(dot(&ac, &ac)).max(dot(&bc, &bc));
    let floor = longest * longest * V::splat(tolerance * tolerance);
    let normal =
        w2.simd_ge(V::splat(4.0 * f64::MIN_POSITIVE)) & w2.simd_le(V::splat(0.25 * f64::MAX));
    (w2.simd_gt(floor) & floor.is_finite() & normal).to_bitmask()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::bvh::index;
    use crate::search::scenes::uniform;

    #[test]
    fn a_leafs_groups_cover_it_in_order_a_vector_at_a_time() {
        for count in 1..=crate::search::LEAF_SIZE {
            let g: Vec<(usize, usize)> = groups(40, count).collect();
            assert_eq!(g.len(), count.div_ceil(LANES));
            let mut next = 40;
            for &(first, n) in &g {
                assert_eq!(first, next);
                assert!((1..=LANES).contains(&n));
                next += n;
            }
            assert_eq!(next, 40 + count);
        }
    }

    /// The rows of one leaf (see `Bvh::rows`) holding `corners` as facets `0, 1, …`, followed by
    /// `junk` (what lies past a leaf in the tree: other leaves' rows).
    fn leaf_rows(corners: &[[Vec3; 3]], junk: f64) -> Vec<f64> {
        let count = corners.len();
        let mut rows = vec![junk; ROWS * count + LANES];
        for (k, x) in corners.iter().enumerate() {
            write_leaf(&mut rows, count, k, x, index(k));
        }
        rows
    }

    /// One leaf through [`measure_leaf`] and [`LaneBest`] against the scalar kernel, bit for bit:
    /// every lane's squared distance, and the winner (smallest distance, then index) with its
    /// closest point; lanes past the leaf hold junk, NaN or not, which must not matter.
    fn check(corners: &[[Vec3; 3]], p: &Vec3) {
        for junk in [0.0, f64::NAN, 1e300, -3.5] {
            let rows = leaf_rows(corners, junk);
            let m = measure_leaf(&rows, corners.len(), p);
            let lanes = m.d2.to_array();
            let mut brute: Option<(f64, usize)> = None;
            for (k, [a, b, c]) in corners.iter().enumerate() {
                let scalar = distance_squared_to_triangle(a, b, c, p);
                assert_eq!(
                    lanes[k].to_bits(),
                    scalar.to_bits(),
                    "lane {k}: {} vs {scalar} for {corners:?}, {p:?}",
                    lanes[k]
                );
                if brute.is_none_or(|(d2, _)| scalar < d2) {
                    brute = Some((scalar, k));
                }
            }
            let mut best = LaneBest::new(f64::INFINITY);
            best.take_leaf(&rows, (0, corners.len()), &m, 3);
            let w = best.best().expect("a winner");
            let (d2, k) = brute.expect("a facet");
            assert_eq!(
                (w.d2.to_bits(), w.facet, w.slot),
                (d2.to_bits(), index(k), index(k))
            );
            assert_eq!(w.leaf, Some(3));
            let [a, b, c] = &corners[k];
            // The lanes' coordinates are the kernel's; a lane the scalar kernel measured is
            // finished by `closest_point_on_triangle` (the two differ below `TINY` alone).
            let want = if FEATURES.get(usize::from(w.feature)).is_some() {
                closest_point_and_distance_squared(a, b, c, p).0
            } else {
                closest_point_on_triangle(a, b, c, p)
            };
            let got = w.closest(&corners[k], p);
            assert_eq!(got.feature, want.feature);
            assert_eq!(got.distance.to_bits(), want.distance.to_bits());
            for d in 0..3 {
                assert_eq!(got.barycentric[d].to_bits(), want.barycentric[d].to_bits());
                assert_eq!(got.point[d].to_bits(), want.point[d].to_bits());
            }
        }
    }

    /// Leaves offered one after another: the winner is the smallest distance, ties to the lowest
    /// facet index, whichever lanes and leaves they came in; NaN lanes (excluded facets) and
    /// lanes past a leaf are never taken; nothing within `max2` gives no winner.
    #[test]
    fn the_lane_wise_best_is_the_best_of_all_offers() {
        let mut r = uniform(23);
        let mut v = || Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5);
        let pool: Vec<[Vec3; 3]> = (0..6).map(|_| [v(), v(), v()]).collect();
        let p = v();
        for trial in 0..300 {
            // Leaves drawn from a small pool of facets, so that equal distances recur in the
            // same lane and in different lanes, under different facet indices.
            let mut best = LaneBest::new(f64::INFINITY);
            let mut brute: Option<(f64, u32)> = None;
            let mut slot = 0;
            for leaf in 0..4 {
                let count = 1 + (trial + leaf) % LANES;
                let corners: Vec<[Vec3; 3]> = (0..count)
                    .map(|k| pool[(trial * 7 + leaf * 3 + k * 5) % pool.len()])
                    .collect();
                let mut rows = leaf_rows(&corners, f64::NAN);
                let mut m = measure_leaf(&rows, count, &p);
                let mut d2 = m.d2.to_array();
                for (k, d) in d2.iter_mut().enumerate().take(count) {
                    // Facet numbers run backwards, so that a later offer may win a tie.
                    let facet = 1000 - slot - index(k);
                    rows[FACET_ROW * count + k] = f64::from(facet);
                    if (trial + k) % 11 == 0 {
                        *d = f64::NAN;
                    } else if brute.is_none_or(|b| (*d, facet) < b) {
                        brute = Some((*d, facet));
                    }
                }
                m.d2 = V::new(d2);
                best.take_leaf(&rows, (slot as usize, count), &m, index(leaf));
                slot += index(count);
            }
            let w = best.best().map(|w| (w.d2, w.facet));
            assert_eq!(w, brute, "trial {trial}");
        }
        let mut none = LaneBest::new(1e-300);
        let rows = leaf_rows(&pool[..2], 0.0);
        none.take_leaf(&rows, (0, 2), &measure_leaf(&rows, 2, &p), 0);
        assert!(none.best().is_none());
        // A seed at exactly the limit is taken, and its closest point is recomputed.
        let mut seeded = LaneBest::new(4.0);
        seeded.seed(4.0, 9, 17);
        let w = seeded.best().expect("the seed");
        assert_eq!(
            (w.d2, w.facet, w.slot, w.leaf, w.feature),
            (4.0, 9, 17, None, RECOMPUTE)
        );
    }

    /// Every pair through [`closest_pairs`] against the scalar kernel, bit for bit.
    fn check_pairs(cases: &[([Vec3; 3], Vec3)]) {
        for group in cases.chunks(PAIRS) {
            let mut pairs = Pairs::default();
            for (k, (c, p)) in group.iter().enumerate() {
                pairs.set(k, c, p);
            }
            let mut out = [None; PAIRS];
            let live = (1 << group.len()) - 1;
            closest_pairs(&pairs, live, |k, c, d2| out[k] = Some((c, d2)));
            for (k, ([a, b, c], p)) in group.iter().enumerate() {
                let (closest, d2) = closest_point_and_distance_squared(a, b, c, p);
                let (lc, ld2) = out[k].expect("every live lane emitted");
                assert_eq!(
                    ld2.to_bits(),
                    d2.to_bits(),
                    "pair {k}: {a:?} {b:?} {c:?} {p:?}"
                );
                assert_eq!(lc.feature, closest.feature);
                assert_eq!(lc.distance.to_bits(), closest.distance.to_bits());
                for d in 0..3 {
                    assert_eq!(
                        lc.barycentric[d].to_bits(),
                        closest.barycentric[d].to_bits()
                    );
                    assert_eq!(lc.point[d].to_bits(), closest.point[d].to_bits());
                }
            }
        }
    }

    #[test]
    fn lanes_equal_the_scalar_kernel_bit_for_bit() {
        let mut r = uniform(17);
        let mut v = |s: f64| Vec3::new(s * (r() - 0.5), s * (r() - 0.5), s * (r() - 0.5));
        for scale in [1.0, 1e-9, 1e9, 1e-160, 1e160] {
            for n in 1..=LANES {
                for _ in 0..2000 {
                    let corners: Vec<[Vec3; 3]> =
                        (0..n).map(|_| [v(scale), v(scale), v(scale)]).collect();
                    check(&corners, &v(2.0 * scale));
                }
            }
            let cases: Vec<([Vec3; 3], Vec3)> = (0..4000)
                .map(|_| ([v(scale), v(scale), v(scale)], v(2.0 * scale)))
                .collect();
            check_pairs(&cases);
        }
    }

    #[test]
    fn clearly_valid_facets_are_valid() {
        let mut r = uniform(5);
        let mut pairs = Pairs::default();
        let (mut clear, mut valid) = (0, 0);
        for scale in [1.0, 1e-150, 1e150] {
            for _ in 0..2000 {
                let mut v = || Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * scale;
                let (a, b) = (v(), v());
                // Slivers around the tolerance: c on the line ab moved off it by 10⁻¹⁴…10⁻⁹.
                let t = 10f64.powf(-14.0 + 5.0 * (v().x / scale + 0.5));
                let c = a + (b - a) * 0.3 + v() * t;
                let corners: [[Vec3; 3]; PAIRS] =
                    std::array::from_fn(|k| if k % 2 == 0 { [a, b, c] } else { [a, b, v()] });
                for (k, c) in corners.iter().enumerate() {
                    pairs.set(k, c, &Vec3::zeros());
                }
                let bits = clearly_valid(&pairs, 2.0 * crate::DEGENERACY_TOLERANCE);
                for (k, [a, b, c]) in corners.iter().enumerate() {
                    let ok = crate::Facet::new(*a, *b, *c).is_ok();
                    if bits & (1 << k) != 0 {
                        assert!(ok, "{a:?} {b:?} {c:?}");
                        clear += 1;
                    }
                    valid += usize::from(ok);
                }
            }
        }
        // Nearly every valid facet is clearly valid: few are left to the exact test.
        assert!(clear * 10 > valid * 9, "{clear} of {valid}");
    }

    #[test]
    fn lanes_equal_the_scalar_kernel_on_features_and_degenerate_facets() {
        let a = Vec3::new(0.0, 0.0, 0.0);
        let b = Vec3::new(1.0, 0.0, 0.0);
        let c = Vec3::new(0.0, 1.0, 0.0);
        let facets = [
            [a, b, c],
            [a, b, 2.0 * b],                         // collinear
            [a, a, c],                               // two corners coincide
            [b, b, b],                               // a point
            [a, b, Vec3::new(0.5, 1e-7, 0.0)], // a valid sliver: measured by the scalar kernel
            [a, Vec3::new(1e-3, 0.0, 0.0), 5.0 * c], // a needle with a right angle
        ];
        let mut points = vec![
            a,
            b,
            c,
            0.5 * (a + b),
            0.5 * (b + c),
            0.5 * (c + a),
            (a + b + c) / 3.0,
        ];
        points.extend(points.clone().iter().map(|p| p + Vec3::new(0.0, 0.0, 0.3)));
        points.extend([Vec3::new(-1.0, -1.0, 0.0), Vec3::new(2.0, 2.0, -1.0)]);
        let mut cases = Vec::new();
        for p in &points {
            // A leaf's facets are measured a vector of lanes at a time (four lanes without
            // AVX-512, where this test found six facets too many for one group).
            for group in facets.chunks(LANES) {
                check(group, p);
            }
            check(&facets[1..3], p);
            cases.extend(facets.iter().map(|f| (*f, *p)));
        }
        // The sliver's lanes are the scalar kernel's (its sub-areas from the normal).
        let thin = |[a, b, c]: [Vec3; 3], p: Vec3| {
            let v = |x: &Vec3| -> [V; 3] { std::array::from_fn(|d| V::splat(x[d])) };
            region(&v(&a), &v(&b), &v(&c), &v(&p)).bad != 0
        };
        assert!(thin(facets[4], (a + b) / 2.0));
        assert!(!thin(facets[0], (a + b) / 2.0));
        // Non-finite coordinates go through the scalar kernel's rescaling.
        let huge = [[
            a,
            Vec3::new(f64::MAX, 0.0, 0.0),
            Vec3::new(0.0, f64::MAX, 0.0),
        ]];
        let far = Vec3::new(1e300, 1e300, 1.0);
        check(&huge, &far);
        cases.push((huge[0], far));
        // Every feature appears, in every lane position.
        let features: std::collections::HashSet<_> = cases
            .iter()
            .map(|([a, b, c], p)| {
                format!(
                    "{:?}",
                    crate::closest::closest_point_on_triangle(a, b, c, p).feature
                )
            })
            .collect();
        assert_eq!(features.len(), 7, "{features:?}");
        for shift in 0..PAIRS {
            let mut rotated = cases.clone();
            rotated.rotate_left(shift);
            check_pairs(&rotated);
        }
    }
}
