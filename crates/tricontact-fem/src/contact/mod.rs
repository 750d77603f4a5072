//! Frictionless node-to-facet contact in the solver: the `[[contact]]` pairs as [`ExtraTerms`].
//!
//! # Per evaluation (every Newton iteration)
//! Positions are always current, `x = X + u` (small-strain solids included). The facet is chosen at
//! `x`; the gap and its derivatives are then evaluated on `x_a − x_s = (X_a − X_s) + (u_a − u_s)`,
//! centred on the slave node, so that their round-off does not grow with the distance from the
//! origin. For every pair and
//! pass, the master surface's tree is built at `x` and each slave node gets **one** constraint: the
//! facet of [`tricontact::contact::choose_facet`] (among facets within the longest master edge the
//! node projects into, smallest `|P|`, ties to the lowest index; with self-contact, among those
//! facing the node's own surface: [`pair::Pass::choose`]), or with `small_sliding` the facet,
//! shape functions and normal frozen at the start of the increment (see [`gap`]). Hysteresis: a
//! node keeps its previous facet while it projects into it within [`HYSTERESIS`] and its `|P|`
//! there exceeds the chosen one's by at most `HYSTERESIS · h` (no flip-flopping across an edge,
//! where `∇²P` jumps, from round-off); and while it penetrates its previous facet (foot within
//! [`LOST_TOLERANCE`]) it takes no facet facing the other way (no tunnelling through a thin
//! part whose far side a Newton step brought nearer). With finite sliding (any method), a node
//! near a concave kink of at least
//! [`flank::ENFORCED_KINK_DEGREES`] between its facet and a neighbour gets a **second**
//! constraint, on that neighbour ([`flank::second_flank`]; see "Concave kinks" below). The node's
//! terms ([`penalty`], [`multiplier`], [`augmented`]) are scattered to global DOFs `3·node + d`;
//! multipliers are extra unknowns after the nodal DOFs: per multiplier pair, one per slave node
//! for its own constraint and, with finite sliding, one more for its second flank (slave `j`'s
//! two at places `j` and `slaves + j` of the pair's, which is which given by
//! [`state::SecondFlank::traded`]; `λ = 0` while a node has no second flank or it is open).
//!
//! Sign conventions (the kernel's): `P > 0` open, `P < 0` penetrating; the constraint enters as
//! `Π + λP`, compression is `λ ≤ 0`, the contact force on the slave node is `−λW`.
//!
//! # Active set and outer loops
//! * Multiplier: the switch of [`multiplier`] is re-evaluated every iteration (primal–dual active
//!   set); penalty and augmented: a node is closed while `P ≤ 0` (`λ̂ ≤ 0`). A node changing status
//!   more than [`MAX_SWITCHES`] times in an increment is held closed for the rest of the increment
//!   (cycling) and counted in the iteration log, whatever the method: its constraint or force then
//!   acts at `P > 0` too, a small pull, which [`ContactTerms`] bounds at convergence (at most the
//!   pair's tolerance as a gap, `λ/α`; a larger pull fails the increment). A node at the edge of
//!   the contact zone otherwise opens, closes deep (its open Newton step carries it through the
//!   master) and opens again every third iteration. Holding multiplier nodes in the status they
//!   wanted at the fifth change instead left nodes open inside the master (0.041 deep, 80 % of the
//!   press, in `contact-block`).
//! * Augmented Lagrangian: after Newton converged, if the largest gap `|P|` of a closed node (a
//!   penetration, or an opening still held by its estimate when backing off) exceeds the pair's
//!   tolerance, every node's estimate takes the Uzawa update `λ_k ← min(0, λ_k + αP)` and the
//!   increment is solved again (outer loop of [`crate::driver`]).
//! * Facet cycling: a node sitting in a concave kink of the master (a valley, e.g. the bottom of
//!   an indentation) has no single-facet equilibrium and flips between the flanks. When it
//!   returns to the facet it left at its previous change (A → B → A), or after [`MAX_SWITCHES`]
//!   facet changes in an increment, its facet is frozen (its plane extended) for the rest of the
//!   increment, and counted as frozen in the iteration log. Freezing at the first return instead
//!   of the fifth change: `fem-bench --contact 20` 8 → 6 Newton iterations with a penalty (7 → 5
//!   with multipliers, same forces: a row of slave nodes on a master edge flips every
//!   iteration), `contact-block` 72 → 62 iterations with multipliers (normal force within
//!   0.14 %). The frozen plane serves only while the node's foot stays within
//!   [`LOST_TOLERANCE`] of the facet (barycentric): beyond, the facet is chosen again, and frozen
//!   at once. A Newton iterate can carry a frozen node far along the plane (1.6 facets past its
//!   facet in `contact-block` pressed 30 % with a penalty), where it no longer approximates the
//!   surface. Measured, `tricontact run` before → after: `contact-block` pressed 20 % (`z =
//!   -0.10`) and slid, augmented: failed at 63 % of the slide → 22 increments, 192 iterations;
//!   multiplier 101 → 95 iterations; penalty 21 → 22 increments, 166 → 174 iterations; the
//!   `sliding` example pressed 0.1: penalty 453 → 420 iterations, augmented 581 → 541,
//!   multiplier 157 → 159; `contact-block` as given but with a penalty 78 → 81 iterations, and
//!   with `line_search = true` penalty 0 → 2 cutbacks (85 iterations), augmented 96 → 92
//!   iterations and 0 → 1 cutback; every example file unchanged. Thresholds of 0.25 and 0.5
//!   instead of `LOST_TOLERANCE` lost the 20 % augmented run again. A node in no facet's
//!   projection region keeps its previous facet while its foot is within [`LOST_TOLERANCE`] of it
//!   and it touches it (`P` at most the pair's tolerance: with `P ≤ 0` required, a multiplier
//!   node held at `P = 0` lost its facet to round-off as a soft block spread past the master's
//!   edge, and Newton diverged; `tests/contact_cases.rs`).
//! * Concave kinks: near a valley the master body is the union of the half-spaces behind the two
//!   flanks, and a node held on one flank's plane can be pushed across the valley line, behind
//!   the other. With finite sliding the flank across the kink is a second constraint
//!   ([`state::SecondFlank`]): with the augmented Lagrangian it has its own multiplier estimate
//!   (the Uzawa update and the gap check take it too), with multipliers its own unknown (its
//!   switch, like the penalty's and the augmented Lagrangian's status for it, decided afresh at
//!   each iteration), and the two estimates or unknowns, and their statuses, trade places when
//!   the node's facet and its second flank do (for the unknowns, [`state::SecondFlank::traded`]
//!   says which is which). One second constraint at most: in a corner of three concave planes
//!   the third is measured, not held. `examples/v-groove` (a wedge pressed into a V-groove, a
//!   row of its bottom nodes on the valley line): with one constraint per node its valley nodes
//!   cycled between the flanks, the penalty and the augmented Lagrangian failed at 75 % of the
//!   press, and the multipliers left them 7.8·10⁻³ behind the other flank; now 4 increments, 17,
//!   29 and 10 iterations, the multipliers' nodes behind neither (2.6·10⁻¹⁵). Only kinks of at least
//!   [`flank::ENFORCED_KINK_DEGREES`] count: an earlier trial took every concave neighbour the
//!   node was behind, and runs that converge failed (`sliding` pressed 0.1 with a penalty, in its
//!   press at 0° and in its slide at 5°; `sliding` as given 213 → 281 iterations and
//!   `contact-block` with a penalty 81 → 118 at 0°), the nearly flat kinks of a finely meshed
//!   curved surface counting; at 15° every other example's solution is unchanged. With
//!   `small_sliding` a node keeps one constraint; what it leaves unheld is measured
//!   ([`flank::flank_penetration`]) and reported.
//! * The node states (facet, shape functions, normal, multiplier estimate, status) are committed at
//!   convergence and restored on a cutback.

pub mod augmented;
pub mod flank;
pub mod gap;
pub mod multiplier;
pub mod output;
pub mod pair;
pub mod penalty;
pub mod state;

use tricontact::Vec3;
use tricontact::contact::PROJECTION_TOLERANCE;
use tricontact::search::{Bvh, Query};

use crate::analysis::Analysis;
use crate::assembly::{ExtraTerms, PointField};
use crate::model::ContactMethod;
use gap::Gap;
pub use pair::ContactPair;
use state::NodeState;

/// Tolerance of the facet hysteresis (see [`ContactTerms`]'s evaluation): barycentric, and
/// relative to the mean facet size for the gap.
pub const HYSTERESIS: f64 = 1e-6;

/// How far (barycentric) a node in no facet's projection region (below a concave kink) may be
/// outside its previous facet and keep it.
pub const LOST_TOLERANCE: f64 = 0.1;

/// Status changes of a node within one increment before its status is frozen.
pub const MAX_SWITCHES: u32 = 4;

/// The largest pull of a node held closed at convergence, as a share of the largest push of the
/// pair's closed nodes, where one presses. It stands beside the pair's `tolerance` on `λ/α`, a
/// gap, which a penalty far above the load's scale makes loose: a strip wrapped onto a base by a
/// follower pressure converged with held nodes pulling 0.22 each and the pair's net force a pull.
pub const HELD_PULL_SHARE: f64 = 0.1;

/// The contact pairs of an analysis with their state.
#[derive(Clone, Debug)]
pub struct ContactTerms {
    reference: Vec<[f64; 3]>,
    /// Gmsh node tags, for messages.
    node_tags: Vec<u64>,
    pairs: Vec<ContactPair>,
    /// Offset of each pair's multipliers among the extra unknowns.
    offsets: Vec<usize>,
    n_extra: usize,
    committed: Vec<Vec<Vec<NodeState>>>,
    trial: Vec<Vec<Vec<NodeState>>>,
    committed_force: Vec<f64>,
    trial_force: Vec<f64>,
    areas: Vec<f64>,
    /// The mid-side nodes whose mean pressure is a tri6 corner's ([`pair::Pass::proxies`]).
    proxies: Vec<Vec<usize>>,
    note: Option<String>,
    /// Why the last Uzawa check asked for another solve.
    outer: Option<String>,
    /// Node positions at the start of the increment (see [`ContactTerms::check_crossings`]).
    start: Vec<Vec3>,
}

impl ContactTerms {
    /// The contact terms of `an`'s pairs, all nodes open.
    #[must_use]
    pub fn new(an: &Analysis) -> Self {
        let pairs = an.contacts.clone();
        let mut offsets = Vec::new();
        let mut n_extra = 0;
        for p in &pairs {
            offsets.push(n_extra);
            n_extra += multipliers(p);
        }
        let state: Vec<Vec<Vec<NodeState>>> = pairs
            .iter()
            .map(|p| {
                p.passes
                    .iter()
                    .map(|q| vec![NodeState::default(); q.slaves.len()])
                    .collect()
            })
            .collect();
        let n = an.mesh.nodes.len();
        let mut areas = vec![0.0; n];
        let mut proxies = vec![Vec::new(); n];
        for p in &pairs {
            for q in &p.passes {
                for ((&s, &a), near) in q.slaves.iter().zip(&q.areas).zip(&q.proxies) {
                    areas[s] = a;
                    proxies[s].clone_from(near);
                }
            }
        }
        Self {
            reference: an.mesh.nodes.clone(),
            node_tags: an.mesh.node_tags.clone(),
            pairs,
            offsets,
            n_extra,
            committed: state.clone(),
            trial: state,
            committed_force: vec![0.0; 3 * n],
            trial_force: vec![0.0; 3 * n],
            areas,
            proxies,
            note: None,
            outer: None,
            start: Vec::new(),
        }
    }

    /// The resolved pairs.
    #[must_use]
    pub fn pairs(&self) -> &[ContactPair] {
        &self.pairs
    }

    /// Committed node states: `[pair][pass][slave]`.
    #[must_use]
    pub fn states(&self) -> &[Vec<Vec<NodeState>>] {
        &self.committed
    }

    /// Committed contact force over nodal DOFs.
    #[must_use]
    pub fn forces(&self) -> &[f64] {
        &self.committed_force
    }

    fn positions(&self, u: &[f64]) -> Vec<Vec3> {
        self.reference
            .iter()
            .enumerate()
            .map(|(a, p)| Vec3::new(p[0] + u[3 * a], p[1] + u[3 * a + 1], p[2] + u[3 * a + 2]))
            .collect()
    }

    /// `x_a − x_s` formed as `(X_a − X_s) + (u_a − u_s)`: its round-off is that of the distance
    /// between the nodes, not of their distance from the origin (`x_a − x_s` of the current
    /// positions loses `ε|X|`, which varies from iteration to iteration and stalled Newton on
    /// models far from the origin under small loads).
    fn relative(&self, u: &[f64], a: usize, s: usize) -> Vec3 {
        let (xa, xs) = (self.reference[a], self.reference[s]);
        Vec3::new(
            (xa[0] - xs[0]) + (u[3 * a] - u[3 * s]),
            (xa[1] - xs[1]) + (u[3 * a + 1] - u[3 * s + 1]),
            (xa[2] - xs[2]) + (u[3 * a + 2] - u[3 * s + 2]),
        )
    }

    /// The gap of slave `j` of pass `q` of pair `p` at `x` (`u`), with the facet's nodes: the facet
    /// is chosen at the current positions `x`, and the gap that enters the terms is built in
    /// coordinates centred on the slave node ([`Self::relative`]; every term is invariant under
    /// translation).
    fn evaluate(
        &self,
        (p, q, j): (usize, usize, usize),
        x: &[Vec3],
        u: &[f64],
        bvh: Option<&Bvh>,
    ) -> Option<(u32, [usize; 3], Gap)> {
        let s = self.pairs[p].passes[q].slaves[j];
        let (f, nodes, gap) = self.choose(p, q, j, x, bvh)?;
        let local = nodes.map(|a| self.relative(u, a, s));
        let gap = match gap {
            Gap::Finite(pair) => Gap::Finite(
                tricontact::NodeFacet::new(local[0], local[1], local[2], Vec3::zeros())
                    .unwrap_or(pair),
            ),
            Gap::Linear { shape, normal, .. } => Gap::linear(local, Vec3::zeros(), shape, normal),
        };
        Some((f, nodes, gap))
    }

    /// The facet of slave `j` of pass `q` of pair `p` at `x`, its nodes, and the gap there in
    /// global coordinates.
    fn choose(
        &self,
        p: usize,
        q: usize,
        j: usize,
        x: &[Vec3],
        bvh: Option<&Bvh>,
    ) -> Option<(u32, [usize; 3], Gap)> {
        let pass = &self.pairs[p].passes[q];
        let s = pass.slaves[j];
        let nodes_of = |f: u32| pass.surface.facets()[f as usize].map(|a| a as usize);
        if let Some(bvh) = bvh {
            let st = &self.trial[p][q][j];
            let previous = st
                .facet
                .filter(|&f| (f as usize) < pass.surface.len())
                .and_then(|f| {
                    let nodes = nodes_of(f);
                    tricontact::NodeFacet::new(x[nodes[0]], x[nodes[1]], x[nodes[2]], x[s])
                        .ok()
                        .map(|pair| (f, nodes, pair))
                });
            // Facet frozen after cycling: its plane (extended) for the rest of the increment,
            // while the node's foot stays within LOST_TOLERANCE of the facet.
            if st.facet_frozen
                && let Some((f, nodes, pair)) = previous
                && pair.projection.is_inside(LOST_TOLERANCE)
            {
                return Some((f, nodes, Gap::Finite(pair)));
            }
            let Some((f, pair)) = pass.choose(bvh, x, j) else {
                // In no facet's projection region (below a valley, or just past the master's
                // edge): the previous facet's plane while the foot stays within LOST_TOLERANCE of
                // it and the node touches it, within the pair's tolerance (a multiplier holds
                // `P = 0` up to round-off, which may be positive).
                let tolerance = self.pairs[p].tolerance;
                return previous
                    .filter(|(_, _, pair)| {
                        pair.projection.is_inside(LOST_TOLERANCE) && pair.gap() <= tolerance
                    })
                    .map(|(f, nodes, pair)| (f, nodes, Gap::Finite(pair)));
            };
            // Sides: while the node penetrates its previous facet (its foot within
            // LOST_TOLERANCE), a facet facing the other way is not taken. A Newton step can carry
            // a node past a thin part's mid-plane, where the far side is nearer: taking it pushed
            // the node on through the part (a block tunnelled through a plate one element thick).
            if let Some((prev, nodes, old)) = previous
                && prev != f
                && old.gap() < 0.0
                && old.projection.is_inside(LOST_TOLERANCE)
                && old.facet.normal().dot(&pair.facet.normal()) < 0.0
            {
                return Some((prev, nodes, Gap::Finite(old)));
            }
            // Hysteresis: keep the previous facet while the node still projects into it within
            // HYSTERESIS (barycentric) and its |P| is not larger than the chosen one's by more
            // than HYSTERESIS·h. A node on a shared edge or vertex otherwise flips between facets
            // from one iteration to the next, and with it the Hessian term `λ∇²P` of the tangent
            // (it jumps across edges): Newton then cycles instead of converging.
            if let Some((prev, nodes, old)) = previous
                && prev != f
                && old.projection.is_inside(HYSTERESIS)
                && old.gap().abs() <= pair.gap().abs() + HYSTERESIS * self.pairs[p].facet_size
            {
                return Some((prev, nodes, Gap::Finite(old)));
            }
            Some((f, nodes_of(f), Gap::Finite(pair)))
        } else {
            let (f, shape, normal) = self.trial[p][q][j].start?;
            let nodes = nodes_of(f);
            let xf = nodes.map(|a| x[a]);
            let w = Vec3::new(normal[0], normal[1], normal[2]);
            Some((f, nodes, Gap::linear(xf, x[s], shape, w)))
        }
    }
}

impl ContactTerms {
    /// The second constraint of slave `j` of pass `q` of pair `p`, whose own facet is `f`, at `x`
    /// (`u`; `bvh` the pass's tree there): the flank of [`flank::second_flank`], its nodes, and
    /// the pair in coordinates centred on the slave node (as [`Self::evaluate`] builds the node's
    /// own).
    fn second_flank(
        &self,
        (p, q, j): (usize, usize, usize),
        (bvh, f): (&Bvh, u32),
        x: &[Vec3],
        u: &[f64],
    ) -> Option<(u32, [usize; 3], tricontact::NodeFacet)> {
        let pass = &self.pairs[p].passes[q];
        let s = pass.slaves[j];
        let hysteresis = flank::Hysteresis {
            previous: self.trial[p][q][j].second.facet,
            tolerance: HYSTERESIS * self.pairs[p].facet_size,
        };
        let facing = pass.facing(j, x);
        let (g, _) = flank::second_flank(
            &pass.surface,
            bvh,
            x,
            (s, f),
            (pass.radius, hysteresis, facing),
        )?;
        let nodes = pass.surface.facets()[g as usize].map(|a| a as usize);
        let local = nodes.map(|a| self.relative(u, a, s));
        let pair = tricontact::NodeFacet::new(local[0], local[1], local[2], Vec3::zeros()).ok()?;
        Some((g, nodes, pair))
    }

    /// Checks the nodes held closed after cycling at a converged state: a node may be held
    /// closed only while it still presses, or pulls by less than the pair's `tolerance`
    /// measured as a gap, `λ/α` (the gap itself with a penalty), and, where some closed node of
    /// the pair presses, by at most [`HELD_PULL_SHARE`] of the largest push (a force, on either
    /// of a node's constraints). A larger pull means the held status is wrong, and the increment
    /// fails (it is cut back) instead of ending with a node glued to the master.
    fn check_held_nodes(&self) -> Result<(), String> {
        for (p, pair) in self.pairs.iter().enumerate() {
            // The largest push of a closed node (held or not), a force.
            let push = self.trial[p].iter().flatten().fold(0.0f64, |m, st| {
                let own = if st.active { -st.lambda } else { 0.0 };
                let second = if st.second.active {
                    -st.second.lambda
                } else {
                    0.0
                };
                m.max(own).max(second)
            });
            for (q, pass) in pair.passes.iter().enumerate() {
                for (j, st) in self.trial[p][q].iter().enumerate() {
                    if !(st.held && st.active) {
                        continue;
                    }
                    let node = self.node_tags[pass.slaves[j]];
                    let pull = st.lambda / pair.penalty;
                    if pull > pair.tolerance {
                        return Err(format!(
                            "contact '{}': slave node {node} was held closed after cycling and pulls at convergence (λ/α = {pull:.3e} > tolerance {:.3e})",
                            pair.name, pair.tolerance
                        ));
                    }
                    // With no node pressing (first touch, lift-off) the gap bound above serves.
                    if push > 0.0 && st.lambda > HELD_PULL_SHARE * push {
                        return Err(format!(
                            "contact '{}': slave node {node} was held closed after cycling and pulls at convergence with a force of {:.3e}, more than a tenth of the largest push of the pair's closed nodes ({push:.3e})",
                            pair.name, st.lambda
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

impl ContactTerms {
    /// Each slave node's depth behind the master beyond its own facet's plane, for the
    /// reports: behind a facet across a concave edge of its facet
    /// ([`flank::flank_penetration`]; a second constraint, where there is one, holds it to its
    /// gap), and with `small_sliding`, behind the facet the node is
    /// over now (its constraint is the plane frozen at the start of the increment, which a
    /// large slide leaves far behind).
    fn measure_flanks(&mut self, u: &[f64]) -> Result<(), String> {
        if self.pairs.is_empty() {
            return Ok(());
        }
        let x = self.positions(u);
        for (p, pair) in self.pairs.iter().enumerate() {
            for (q, pass) in pair.passes.iter().enumerate() {
                let bvh = Bvh::build(&pass.surface, &x, pass.radius).map_err(|e| e.to_string())?;
                for (j, st) in self.trial[p][q].iter_mut().enumerate() {
                    let s = pass.slaves[j];
                    st.flank = st.facet.map_or(0.0, |f| {
                        let facing = pass.facing(j, &x);
                        flank::flank_penetration(
                            &pass.surface,
                            &bvh,
                            &x,
                            (s, f),
                            (pass.radius, facing),
                        )
                    });
                    if pair.small_sliding
                        && let Some((_, now)) = pass.choose(&bvh, &x, j)
                    {
                        st.flank = st.flank.max(-now.gap());
                    }
                }
            }
        }
        Ok(())
    }
}

impl ContactTerms {
    /// A slave node closed in two multiplier pairs at once with (nearly) the same normal, as on the
    /// seam of a master surface split into two pairs: its two constraint rows repeat each other.
    fn repeated_constraints(&self) -> Option<String> {
        let mut closed: std::collections::HashMap<usize, (&str, [f64; 3])> =
            std::collections::HashMap::new();
        for (pair, states) in self.pairs.iter().zip(&self.trial) {
            if pair.method != ContactMethod::Multiplier {
                continue;
            }
            for (&node, st) in pair.passes[0].slaves.iter().zip(&states[0]) {
                if !st.active {
                    continue;
                }
                if let Some(&(first, n)) = closed.get(&node) {
                    let cos: f64 = (0..3).map(|d| n[d] * st.normal[d]).sum();
                    if cos.abs() > 1.0 - 1e-6 {
                        return Some(format!(
                            "slave node {} is closed in contacts '{first}' and '{}' at once, with the same normal, so its two constraints repeat each other: make the two master groups one contact, or use method = \"penalty\"",
                            self.node_tags[node], pair.name
                        ));
                    }
                } else {
                    closed.insert(node, (&pair.name, st.normal));
                }
            }
        }
        None
    }

    /// Checks, at a converged state `u`, that no slave node without a facet went through the
    /// master surface during the increment. A Newton step that carries a node deeper into the
    /// master than the search radius (the longest master edge) leaves it with no facet within
    /// reach, hence open, and the increment could converge with the bodies interpenetrating and no
    /// contact force. Such a node is behind its closest master facet now (`P < 0`, projecting
    /// into it, and beyond the radius, or the facet would have been found) and was within reach
    /// of that facet's plane at the start of the increment (`P > −radius`: in front of it, or in
    /// contact); the increment then fails and is cut back, until its steps stay within the
    /// radius. A node already deeper at the start (meshes that overlap from the outset) is left
    /// to the initial-penetration check. With self-contact the facets tested are those that face
    /// the node within a few search radii ([`crossing_candidates`]), not only the closest.
    fn check_crossings(&self, u: &[f64]) -> Result<(), String> {
        // No increment begun (no start positions): nothing to compare with.
        if self.start.len() != self.reference.len() {
            return Ok(());
        }
        let x = self.positions(u);
        for (p, pair) in self.pairs.iter().enumerate() {
            for (q, pass) in pair.passes.iter().enumerate() {
                let lost: Vec<usize> = (0..pass.slaves.len())
                    .filter(|&j| self.trial[p][q][j].facet.is_none())
                    .collect();
                if lost.is_empty() {
                    continue;
                }
                let bvh = Bvh::build(&pass.surface, &x, 0.0).map_err(|e| e.to_string())?;
                for j in lost {
                    let s = pass.slaves[j];
                    let query = Query {
                        point: x[s],
                        exclude: u32::try_from(s).ok(),
                    };
                    for facet in crossing_candidates(pass, &bvh, &x, (j, &query)) {
                        let nodes = pass.surface.facets()[facet as usize].map(|a| a as usize);
                        let gap_at = |x: &[Vec3]| {
                            tricontact::NodeFacet::new(x[nodes[0]], x[nodes[1]], x[nodes[2]], x[s])
                                .ok()
                        };
                        let (Some(now), Some(then)) = (gap_at(&x), gap_at(&self.start)) else {
                            continue;
                        };
                        if now.gap() < 0.0
                            && then.gap() > -pass.radius
                            && now.projection.is_inside(PROJECTION_TOLERANCE)
                        {
                            return Err(format!(
                                "contact '{}': slave node {} went through the master surface in this increment, {:.3e} behind face {}, beyond the search radius {:.3e} (the longest master edge), so it found no facet; smaller increments keep each Newton step within reach",
                                pair.name,
                                self.node_tags[s],
                                -now.gap(),
                                pass.face_tags[facet as usize],
                                pass.radius
                            ));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// How far, in search radii, [`ContactTerms::check_crossings`] looks for the facets that face a
/// self-contact node.
const CROSSING_REACH: f64 = 4.0;

/// The facets of `pass`'s surface that [`ContactTerms::check_crossings`] tests slave `j` against
/// at `x` (`query` its point, excluding its own facets; `bvh` the surface's tree there): the
/// closest; with self-contact, every facet within [`CROSSING_REACH`] search radii that faces the
/// node's own surface ([`tricontact::contact::faces`]), nearest first. (The closest facing facet
/// alone would not do: it is often the far face of the node's own part, which the node has
/// always been behind, while the facet it went through lies farther.)
fn crossing_candidates(
    pass: &pair::Pass,
    bvh: &Bvh,
    x: &[Vec3],
    (j, query): (usize, &Query),
) -> Vec<u32> {
    let Some(n) = pass.facing(j, x) else {
        return bvh
            .closest(&pass.surface, query, f64::INFINITY)
            .map(|hit| hit.facet)
            .into_iter()
            .collect();
    };
    // Sorted by distance, then facet index.
    bvh.within(&pass.surface, query, CROSSING_REACH * pass.radius)
        .into_iter()
        .filter(|hit| {
            let [a, b, c] = pass.surface.corners(hit.facet, x);
            tricontact::Facet::new(a, b, c)
                .is_ok_and(|f| tricontact::contact::faces(&f.normal(), &n))
        })
        .map(|hit| hit.facet)
        .collect()
}

fn scatter(
    nodes: [usize; 4],
    r: &tricontact::Vec12,
    k: &tricontact::Mat12,
    residual: &mut [f64],
    force: &mut [f64],
    triplets: &mut Vec<(usize, usize, f64)>,
) {
    let dof = |i: usize| 3 * nodes[i / 3] + i % 3;
    for i in 0..12 {
        residual[dof(i)] += r[i];
        force[dof(i)] -= r[i];
        for j in 0..12 {
            let v = k[(i, j)];
            if v != 0.0 {
                triplets.push((dof(i), dof(j), v));
            }
        }
    }
}

/// The status of a node this iteration: the status it `want`s, counting a change from
/// `was_active`; on the change after [`MAX_SWITCHES`] the node is held closed for the rest of the
/// increment, and a held node stays closed.
fn settle(st: &mut NodeState, was_active: bool, want: bool) -> bool {
    if st.held {
        return true;
    }
    if want != was_active {
        st.switches += 1;
        if st.switches > MAX_SWITCHES {
            st.held = true;
            return true;
        }
    }
    want
}

/// One slave node's evaluation: its facet, the facet's nodes and the node–facet geometry (`None`:
/// no facet within reach).
type Evaluation<'a> = Option<&'a (u32, [usize; 3], Gap)>;

/// Where a node's terms go: the residual, the contact force, the tangent triplets.
type Out<'a> = (
    &'a mut [f64],
    &'a mut [f64],
    &'a mut Vec<(usize, usize, f64)>,
);

/// Records the facet of `eval` in the node's state, counting a change of facet: back on the facet
/// it left last time (A → B → A, a two-cycle) or after [`MAX_SWITCHES`] changes the node's facet
/// is frozen for the rest of the increment. Returns whether the facet changed.
fn follow_facet(st: &mut NodeState, eval: Evaluation<'_>) -> bool {
    let facet = eval.map(|e| e.0);
    let moved = facet != st.facet;
    if moved && st.facet.is_some() && eval.is_some() {
        st.facet_switches += 1;
        let returned = facet == st.left_facet;
        if returned || st.facet_switches > MAX_SWITCHES {
            st.facet_frozen = true;
        }
        st.left_facet = st.facet;
    }
    match eval {
        Some((f, _, g)) => {
            let w = g.normal();
            st.facet = Some(*f);
            st.shape = g.shape();
            st.normal = [w[0], w[1], w[2]];
            st.gap = g.gap();
        }
        None => {
            st.facet = None;
            st.gap = 0.0;
        }
    }
    moved
}

/// A kernel failure as a message.
fn geometry(e: tricontact::GeometryError) -> String {
    format!("contact: {e}")
}

/// Penalty contact of slave node `s`: closed when the penalty wants it (see [`settle`]), then its
/// terms `α P` with their tangent.
fn penalty_node(
    st: &mut NodeState,
    was_active: bool,
    eval: Evaluation<'_>,
    alpha: f64,
    s: usize,
    out: Out<'_>,
) -> Result<(), String> {
    let want = eval.is_some_and(|(_, _, g)| penalty::wants_closed(g));
    closed_terms(st, was_active, want, eval, s, out, |g, _| {
        let (r, k) = penalty::penalty_terms(g, alpha).map_err(geometry)?;
        Ok((r, k, alpha * g.gap()))
    })
}

/// Augmented-Lagrangian contact of slave node `s`: closed when its multiplier estimate
/// `λ̂ = λ_k + α P` wants it, then its terms with their tangent.
fn augmented_node(
    st: &mut NodeState,
    was_active: bool,
    eval: Evaluation<'_>,
    alpha: f64,
    s: usize,
    out: Out<'_>,
) -> Result<(), String> {
    let lambda_hat = match eval {
        Some((_, _, g)) => Some(augmented::lambda_hat(g, st.lambda_k, alpha).map_err(geometry)?),
        None => None,
    };
    let want = eval
        .zip(lambda_hat)
        .is_some_and(|((_, _, g), lh)| augmented::wants_closed(g, lh));
    closed_terms(st, was_active, want, eval, s, out, |g, lambda_k| {
        let (r, k) = augmented::augmented_terms(g, lambda_k, alpha).map_err(geometry)?;
        Ok((r, k, lambda_hat.unwrap_or(0.0)))
    })
}

/// The status of a node of penalty or augmented contact from the status it `want`s (see
/// [`settle`]); when closed, its residual, tangent and multiplier from `terms(gap, λ_k)`, scattered
/// into `out`. Open, its multiplier is zero.
fn closed_terms(
    st: &mut NodeState,
    was_active: bool,
    want: bool,
    eval: Evaluation<'_>,
    s: usize,
    (residual, force, triplets): Out<'_>,
    terms: impl FnOnce(&Gap, f64) -> Result<(tricontact::Vec12, tricontact::Mat12, f64), String>,
) -> Result<(), String> {
    let act = settle(st, was_active, want) && eval.is_some();
    st.active = false;
    st.lambda = 0.0;
    if let Some((_, fnodes, g)) = eval
        && act
    {
        let (r, k, lambda) = terms(g, st.lambda_k)?;
        st.active = true;
        st.lambda = lambda;
        let nodes = [fnodes[0], fnodes[1], fnodes[2], s];
        scatter(nodes, &r, &k, residual, force, triplets);
    }
    Ok(())
}

/// The second constraint of slave node `s` (see [`flank`]) with a penalty, or with the
/// augmented Lagrangian where `augmented`: against `second` (the flank's facet, its nodes and the
/// pair; `None`, the node has none), closed when the method wants it (`P_G ≤ 0`;
/// `λ̂ = λ_k + αP_G < 0`), then its terms scattered into `out`. Its status is decided afresh at
/// each evaluation (no cycling is counted or held for it, unlike the node's own), its facet with
/// a hysteresis ([`flank::second_flank`]).
fn second_terms(
    st: &mut state::SecondFlank,
    second: Option<&(u32, [usize; 3], tricontact::NodeFacet)>,
    (augmented, alpha): (bool, f64),
    s: usize,
    (residual, force, triplets): Out<'_>,
) -> Result<(), String> {
    st.active = false;
    st.lambda = 0.0;
    follow_flank(st, second);
    let Some(&(_, fnodes, pair)) = second else {
        return Ok(());
    };
    let gap = Gap::Finite(pair);
    let (closed, lambda) = if augmented {
        let lambda_hat = augmented::lambda_hat(&gap, st.lambda_k, alpha).map_err(geometry)?;
        (augmented::wants_closed(&gap, lambda_hat), lambda_hat)
    } else {
        (penalty::wants_closed(&gap), alpha * pair.gap())
    };
    if closed {
        let (r, k) = if augmented {
            augmented::augmented_terms(&gap, st.lambda_k, alpha)
        } else {
            penalty::penalty_terms(&gap, alpha)
        }
        .map_err(geometry)?;
        st.active = true;
        st.lambda = lambda;
        let nodes = [fnodes[0], fnodes[1], fnodes[2], s];
        scatter(nodes, &r, &k, residual, force, triplets);
    }
    Ok(())
}

/// Lagrange-multiplier contact of slave node `s` whose multiplier is the unknown `ldof` (value in
/// `u`): the active block (`c = P = 0`) or the inactive one (`λ = 0`), and the coupling terms.
fn multiplier_node(
    st: &mut NodeState,
    was_active: bool,
    eval: Evaluation<'_>,
    alpha: f64,
    (s, ldof): (usize, usize),
    u: &[f64],
    (residual, force, triplets): Out<'_>,
) -> Result<(), String> {
    let lambda = u[ldof];
    let want = eval.is_some_and(|(_, _, g)| multiplier::wants_active(g.gap(), lambda, alpha));
    let act = settle(st, was_active, want) && eval.is_some();
    st.active = act;
    st.lambda = if act { lambda } else { 0.0 };
    let block = match eval {
        Some((_, _, g)) if act => multiplier::active_block(g, lambda).map_err(geometry)?,
        _ => multiplier::inactive_block(lambda, alpha),
    };
    let nodes = eval.filter(|_| act).map(|(_, f, _)| [f[0], f[1], f[2], s]);
    scatter_multiplier(&block, nodes, ldof, (residual, force, triplets));
    Ok(())
}

/// Scatters a node's multiplier block into `out`: its multiplier's equation (row and column
/// `ldof`) and, where active (`nodes`: the facet's three and the slave node), the coupling and
/// the geometric stiffness over their DOFs.
fn scatter_multiplier(
    block: &multiplier::Block,
    nodes: Option<[usize; 4]>,
    ldof: usize,
    (residual, force, triplets): Out<'_>,
) {
    if let Some(nodes) = nodes {
        scatter(
            nodes,
            &block.residual_u,
            &block.k_uu,
            residual,
            force,
            triplets,
        );
        for i in 0..12 {
            let d = 3 * nodes[i / 3] + i % 3;
            triplets.push((d, ldof, block.k_ulambda[i]));
            triplets.push((ldof, d, block.k_ulambda[i]));
        }
    }
    residual[ldof] += block.residual_lambda;
    triplets.push((ldof, ldof, block.k_lambdalambda));
}

/// The second constraint of slave node `s` with Lagrange multipliers, its multiplier the unknown
/// `ldof` (value in `u`): against `second` (the flank's facet, its nodes and the pair; `None`, the
/// node has none), the active block (`c = P_G = 0`) where the switch `κP_G + λ ≤ 0` wants it, the
/// inactive one (`λ = 0`) otherwise. Its status is decided afresh at each evaluation, as
/// [`second_terms`]'s.
fn second_multiplier(
    st: &mut state::SecondFlank,
    second: Option<&(u32, [usize; 3], tricontact::NodeFacet)>,
    alpha: f64,
    (s, ldof): (usize, usize),
    u: &[f64],
    out: Out<'_>,
) -> Result<(), String> {
    let lambda = u[ldof];
    follow_flank(st, second);
    st.active = second.is_some_and(|g| multiplier::wants_active(g.2.gap(), lambda, alpha));
    st.lambda = if st.active { lambda } else { 0.0 };
    let block = match second {
        Some(&(_, _, pair)) if st.active => {
            multiplier::active_block(&Gap::Finite(pair), lambda).map_err(geometry)?
        }
        _ => multiplier::inactive_block(lambda, alpha),
    };
    let nodes = second
        .filter(|_| st.active)
        .map(|&(_, f, _)| [f[0], f[1], f[2], s]);
    scatter_multiplier(&block, nodes, ldof, out);
    Ok(())
}

/// Records the second flank of this evaluation (`second`: its facet, its nodes and the pair;
/// `None`, the node has none) in the node's state: its facet, gap and normal (`None`, 0 and 0).
fn follow_flank(
    st: &mut state::SecondFlank,
    second: Option<&(u32, [usize; 3], tricontact::NodeFacet)>,
) {
    st.facet = second.map(|g| g.0);
    st.gap = second.map_or(0.0, |g| g.2.gap());
    st.normal = second.map_or([0.0; 3], |g| {
        let w = g.2.facet.normal();
        [w[0], w[1], w[2]]
    });
}

/// The multiplier unknowns of `pair` among the extra unknowns: with Lagrange multipliers one per
/// slave node for its own constraint and, with finite sliding, one more for its second flank
/// (slave `j`'s at places `j` and `slaves + j`: [`own_unknown`], [`second_unknown`]); none
/// otherwise.
fn multipliers(pair: &ContactPair) -> usize {
    match pair.method {
        ContactMethod::Multiplier if pair.small_sliding => pair.passes[0].slaves.len(),
        ContactMethod::Multiplier => 2 * pair.passes[0].slaves.len(),
        _ => 0,
    }
}

/// The place, among its pair's multiplier unknowns, of the multiplier of slave `j`'s own
/// constraint (of `slaves`): `j`, or its second flank's place `slaves + j` while the two have
/// traded facets an odd number of times ([`state::SecondFlank::traded`]).
fn own_unknown(st: &NodeState, j: usize, slaves: usize) -> usize {
    if st.second.traded { slaves + j } else { j }
}

/// The place of the multiplier of slave `j`'s second flank: the other of [`own_unknown`]'s two.
fn second_unknown(st: &NodeState, j: usize, slaves: usize) -> usize {
    if st.second.traded { j } else { slaves + j }
}

/// `w` with the components prescribed at `node` zeroed.
fn free_part(w: &[f64; 3], node: usize, dm: &crate::assembly::DofMap) -> [f64; 3] {
    std::array::from_fn(|d| {
        if dm.eq[3 * node + d] == crate::assembly::NO_EQ {
            0.0
        } else {
            w[d]
        }
    })
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Gmsh node tags for a message: the first eight, and how many more.
fn listed(tags: &[u64]) -> String {
    const LISTED: usize = 8;
    let shown: Vec<String> = tags.iter().take(LISTED).map(u64::to_string).collect();
    match tags.len().saturating_sub(LISTED) {
        0 => shown.join(", "),
        n => format!("{} and {n} more", shown.join(", ")),
    }
}

impl ExtraTerms for ContactTerms {
    fn num_extra(&self) -> usize {
        self.n_extra
    }

    fn extra_nodes(&self) -> Vec<Option<usize>> {
        let mut owners = vec![None; self.n_extra];
        for (p, &offset) in self.pairs.iter().zip(&self.offsets) {
            let slaves = &p.passes[0].slaves;
            for k in 0..multipliers(p) {
                owners[offset + k] = Some(slaves[k % slaves.len()]);
            }
        }
        owners
    }

    /// The unknowns of the second flanks' places (mostly inactive) after their blocks' other
    /// multipliers (after a trade such a place holds the own constraint's: only the speed differs).
    fn extra_late(&self) -> Vec<bool> {
        let mut late = vec![false; self.n_extra];
        for (p, &offset) in self.pairs.iter().zip(&self.offsets) {
            let slaves = p.passes[0].slaves.len();
            for k in slaves..multipliers(p) {
                late[offset + k] = true;
            }
        }
        late
    }

    fn symmetric(&self) -> bool {
        true
    }

    fn nonlinear(&self) -> bool {
        !self.pairs.is_empty()
    }

    fn supports_bodies(&self) -> bool {
        !self.pairs.is_empty()
    }

    fn begin_increment(&mut self, u: &[f64]) -> Result<(), String> {
        self.trial.clone_from(&self.committed);
        for st in self.trial.iter_mut().flatten().flatten() {
            st.switches = 0;
            st.held = false;
            st.facet_switches = 0;
            st.facet_frozen = false;
            st.left_facet = None;
        }
        let x = self.positions(u);
        self.start.clone_from(&x);
        for p in 0..self.pairs.len() {
            if !self.pairs[p].small_sliding {
                continue;
            }
            for q in 0..self.pairs[p].passes.len() {
                let pass = &self.pairs[p].passes[q];
                let bvh = Bvh::build(&pass.surface, &x, pass.radius).map_err(|e| e.to_string())?;
                for j in 0..pass.slaves.len() {
                    let start = self
                        .evaluate((p, q, j), &x, u, Some(&bvh))
                        .map(|(f, _, g)| {
                            let w = g.normal();
                            (f, g.shape(), [w[0], w[1], w[2]])
                        });
                    self.trial[p][q][j].start = start;
                }
            }
        }
        Ok(())
    }

    fn add_terms(
        &mut self,
        u: &[f64],
        residual: &mut [f64],
        triplets: &mut Vec<(usize, usize, f64)>,
    ) -> Result<(), String> {
        let x = self.positions(u);
        let n_nodal = 3 * self.reference.len();
        let mut force = vec![0.0; n_nodal];
        let (mut active_count, mut changed, mut frozen, mut held, mut moved, mut two) =
            (0usize, 0usize, 0usize, 0usize, 0usize, 0usize);
        for p in 0..self.pairs.len() {
            let (method, alpha, small) = {
                let pr = &self.pairs[p];
                (pr.method, pr.penalty, pr.small_sliding)
            };
            for q in 0..self.pairs[p].passes.len() {
                let bvh = if small {
                    None
                } else {
                    let pass = &self.pairs[p].passes[q];
                    Some(Bvh::build(&pass.surface, &x, pass.radius).map_err(|e| e.to_string())?)
                };
                let slaves = self.pairs[p].passes[q].slaves.len();
                for j in 0..slaves {
                    let s = self.pairs[p].passes[q].slaves[j];
                    let eval = self.evaluate((p, q, j), &x, u, bvh.as_ref());
                    let second = match (&eval, &bvh) {
                        (Some((f, _, _)), Some(bvh)) => {
                            self.second_flank((p, q, j), (bvh, *f), &x, u)
                        }
                        _ => None,
                    };
                    let st = &mut self.trial[p][q][j];
                    // The own facet and the second flank trading places (a node crossing a
                    // valley line): each multiplier (estimate or unknown) and each status stays
                    // with its facet (the own status's change is counted against its facet's).
                    if let (Some((f, _, _)), Some((g, _, _))) = (&eval, &second)
                        && st.facet == Some(*g)
                        && st.second.facet == Some(*f)
                    {
                        std::mem::swap(&mut st.lambda_k, &mut st.second.lambda_k);
                        std::mem::swap(&mut st.active, &mut st.second.active);
                        st.second.traded = !st.second.traded;
                    }
                    let was_active = st.active;
                    moved += usize::from(follow_facet(st, eval.as_ref()));
                    if st.facet_frozen {
                        frozen += 1;
                    }
                    let out = (&mut *residual, &mut force[..], &mut *triplets);
                    match method {
                        ContactMethod::Penalty => {
                            penalty_node(st, was_active, eval.as_ref(), alpha, s, out)?;
                        }
                        ContactMethod::Augmented => {
                            augmented_node(st, was_active, eval.as_ref(), alpha, s, out)?;
                        }
                        ContactMethod::Multiplier => {
                            let ldof = n_nodal + self.offsets[p] + own_unknown(st, j, slaves);
                            let node = (s, ldof);
                            multiplier_node(st, was_active, eval.as_ref(), alpha, node, u, out)?;
                        }
                    }
                    // The second constraint (none with small sliding).
                    let out = (&mut *residual, &mut force[..], &mut *triplets);
                    if method == ContactMethod::Multiplier {
                        if !small {
                            let ldof = n_nodal + self.offsets[p] + second_unknown(st, j, slaves);
                            let node = (s, ldof);
                            second_multiplier(
                                &mut st.second,
                                second.as_ref(),
                                alpha,
                                node,
                                u,
                                out,
                            )?;
                        }
                    } else {
                        let augmented = method == ContactMethod::Augmented;
                        second_terms(&mut st.second, second.as_ref(), (augmented, alpha), s, out)?;
                    }
                    two += usize::from(st.active && st.second.active);
                    if st.held {
                        held += 1;
                    }
                    if st.closed() {
                        active_count += 1;
                    }
                    if st.active != was_active {
                        changed += 1;
                    }
                }
            }
        }
        self.trial_force = force;
        // A model without contact pairs has nothing to say per iteration.
        // Nodes that cycled: facets frozen (between flanks) and statuses held closed, apart.
        self.note = (!self.pairs.is_empty()).then(|| {
            let mut note =
                format!("contact: {active_count} closed, {changed} changed, {moved} changed facet");
            if two > 0 {
                note += &format!(", {two} on two flanks");
            }
            if frozen > 0 {
                note += &format!(", {frozen} facet(s) frozen");
            }
            if held > 0 {
                note += &format!(", {held} held closed");
            }
            if frozen + held > 0 {
                note += " (cycling)";
            }
            note
        });
        Ok(())
    }

    fn iteration_note(&self) -> Option<String> {
        self.note.clone()
    }

    fn after_converged(&mut self, u: &[f64]) -> Result<bool, String> {
        self.check_held_nodes()?;
        self.check_crossings(u)?;
        let mut done = true;
        self.outer = None;
        for (p, pair) in self.pairs.iter().enumerate() {
            if pair.method != ContactMethod::Augmented {
                continue;
            }
            // Closed nodes only, and their gaps either way: backing off, the estimates of the
            // loaded state hold nodes closed with their gaps open, still transmitting force.
            let largest = self.trial[p].iter().flatten().fold(0.0f64, |m, s| {
                let own = if s.active { s.gap.abs() } else { 0.0 };
                let second = if s.second.active {
                    s.second.gap.abs()
                } else {
                    0.0
                };
                m.max(own).max(second)
            });
            if largest > pair.tolerance {
                done = false;
                self.outer = Some(format!(
                    "contact '{}': largest gap |P| of a closed node {largest:.3e} still above \
                     tolerance × h = {:.3e}; raise its `tolerance`",
                    pair.name, pair.tolerance
                ));
                for st in self.trial[p].iter_mut().flatten() {
                    st.lambda_k = if st.active { st.lambda.min(0.0) } else { 0.0 };
                    let second = &mut st.second;
                    second.lambda_k = if second.active {
                        second.lambda.min(0.0)
                    } else {
                        0.0
                    };
                }
            }
        }
        // Measured for the reports once, at the solve that ends the increment (not at each
        // Uzawa re-solve: a tree per pass each time).
        if done {
            self.measure_flanks(u)?;
        }
        Ok(done)
    }

    fn outer_note(&self) -> Option<String> {
        self.outer.clone()
    }

    /// Each multiplier's constraint `c = P` (a length) weighs in the convergence norms as `αP`, a
    /// force, with the pair's penalty factor `α`, and its correction `δλ` (a force) as `δλ/α`.
    fn residual_scales(&self) -> Vec<f64> {
        let mut scales = Vec::with_capacity(self.n_extra);
        for pair in &self.pairs {
            scales.extend(std::iter::repeat_n(pair.penalty, multipliers(pair)));
        }
        scales
    }

    /// Closed multiplier nodes whose normal (or second flank's normal) lies entirely in
    /// prescribed components: their constraint rows hold master DOFs only, and repeat each other
    /// where they share master nodes; and nodes closed on two flanks whose two normals, in the
    /// components left free, are parallel: their two rows repeat each other at the node.
    fn singular_cause(&self, dm: &crate::assembly::DofMap) -> Option<String> {
        let mut causes = Vec::new();
        for (pair, states) in self.pairs.iter().zip(&self.trial) {
            if pair.method != ContactMethod::Multiplier {
                continue;
            }
            let (mut fixed, mut parallel) = (Vec::new(), Vec::new());
            for (&node, st) in pair.passes[0].slaves.iter().zip(&states[0]) {
                let own = free_part(&st.normal, node, dm);
                let second = free_part(&st.second.normal, node, dm);
                let prescribed = |w: &[f64; 3]| dot(w, w) <= 1e-12;
                if (st.active && prescribed(&own)) || (st.second.active && prescribed(&second)) {
                    fixed.push(self.node_tags[node]);
                } else if st.active && st.second.active {
                    let cos = dot(&own, &second) / (dot(&own, &own) * dot(&second, &second)).sqrt();
                    if cos.abs() > 1.0 - 1e-6 {
                        parallel.push(self.node_tags[node]);
                    }
                }
            }
            if !fixed.is_empty() {
                causes.push(format!(
                    "contact '{}': {} closed slave node(s) have every normal component prescribed \
                     (Gmsh nodes {}), so their constraints act on the master nodes alone and \
                     repeat each other: free those components or use method = \"penalty\"",
                    pair.name,
                    fixed.len(),
                    listed(&fixed)
                ));
            }
            if !parallel.is_empty() {
                causes.push(format!(
                    "contact '{}': {} slave node(s) closed on both flanks of a concave kink of the \
                     master have the two normals parallel in their free components (Gmsh nodes \
                     {}), so the two constraints repeat each other there: free those components, \
                     or use small_sliding = true (one constraint per node) or method = \"penalty\"",
                    pair.name,
                    parallel.len(),
                    listed(&parallel)
                ));
            }
        }
        causes.extend(self.repeated_constraints());
        (!causes.is_empty()).then(|| causes.join("; "))
    }

    fn commit(&mut self) {
        self.committed.clone_from(&self.trial);
        self.committed_force.clone_from(&self.trial_force);
    }

    fn restore(&mut self) {
        self.trial.clone_from(&self.committed);
        self.trial_force.clone_from(&self.committed_force);
    }

    fn point_fields(&self) -> Vec<PointField> {
        if self.pairs.is_empty() {
            Vec::new()
        } else {
            self.fields()
        }
    }

    fn history(&self) -> Vec<(String, f64)> {
        self.columns()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;

    /// The analysis of the example model `examples/<model>`.
    fn example(model: &str) -> Analysis {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples")
            .join(model);
        let model = Model::load(&path).expect("example model");
        let mesh = crate::gmsh::read_msh(&model.mesh_path()).expect("example mesh");
        Analysis::new(&model, mesh).expect("example analysis")
    }

    /// The multiplier patch model, its contact terms evaluated once at the reference state.
    fn patch_terms() -> ContactTerms {
        let an = example("patch/multiplier.toml");
        let mut terms = ContactTerms::new(&an);
        let u = vec![0.0; 3 * an.mesh.nodes.len() + terms.num_extra()];
        terms.begin_increment(&u).expect("begin");
        let (mut r, mut k) = (vec![0.0; u.len()], Vec::new());
        terms.add_terms(&u, &mut r, &mut k).expect("terms");
        terms
    }

    /// The V-groove example's model `model`, its contact terms begun at the reference state
    /// (displacements `u`, zero, multipliers included), and the place `j` of a node of its valley
    /// row among the slave nodes.
    fn valley_node(model: &str) -> (ContactTerms, Vec<f64>, usize) {
        let an = example(model);
        let mut terms = ContactTerms::new(&an);
        let u = vec![0.0; 3 * an.mesh.nodes.len() + terms.num_extra()];
        terms.begin_increment(&u).expect("begin");
        let slaves = &terms.pairs[0].passes[0].slaves;
        let j = (0..slaves.len())
            .find(|&j| {
                let x = an.mesh.nodes[slaves[j]];
                (x[0] - 1.0).abs() < 1e-12 && x[1] > 0.3 && x[1] < 0.4
            })
            .expect("a node on the valley line");
        (terms, u, j)
    }

    /// Slave `j` moved 0.008 below the valley line and 0.005 to one `side`: behind both flanks,
    /// in the projection region of the near one, within reach of the far one's. Returns its
    /// facet and its second flank after the terms are evaluated there.
    fn across(
        terms: &mut ContactTerms,
        u: &mut [f64],
        j: usize,
        side: f64,
    ) -> (Option<u32>, Option<u32>) {
        let s = terms.pairs[0].passes[0].slaves[j];
        u[3 * s] = 0.005 * side;
        u[3 * s + 2] = -0.008;
        let (mut r, mut k) = (vec![0.0; u.len()], Vec::new());
        terms.add_terms(u, &mut r, &mut k).expect("terms");
        let st = &terms.trial[0][0][j];
        (st.facet, st.second.facet)
    }

    /// A node of the V-groove example's valley row moved just below the valley line, to one side
    /// and then to the other: its own facet and its second flank trade places, and so do their
    /// augmented-Lagrangian multiplier estimates and their statuses.
    #[test]
    fn the_estimates_trade_places_when_the_facet_and_the_second_flank_do() {
        let (mut terms, mut u, j) = valley_node("v-groove/augmented.toml");
        let (own, second) = across(&mut terms, &mut u, j, -1.0);
        assert!(
            own.is_some() && second.is_some() && own != second,
            "{own:?} {second:?}"
        );
        terms.trial[0][0][j].lambda_k = -1.0;
        terms.trial[0][0][j].second.lambda_k = -2.0;
        // The statuses follow their facets too: the flank, open, becomes the node's facet and
        // closes, a change of its status, counted as one.
        let st = &mut terms.trial[0][0][j];
        (st.active, st.second.active, st.switches) = (true, false, 0);
        assert_eq!(across(&mut terms, &mut u, j, 1.0), (second, own));
        let st = &terms.trial[0][0][j];
        assert_eq!((st.lambda_k, st.second.lambda_k), (-2.0, -1.0));
        assert!(st.active && st.second.active);
        assert_eq!(st.switches, 1);
    }

    /// The same with Lagrange multipliers: the node's two multiplier unknowns stay with their
    /// facets, so that the own constraint reads, after the trade, the unknown its new facet had
    /// as the second flank (and back again after a second trade).
    #[test]
    fn the_multiplier_unknowns_stay_with_their_facets_when_these_trade_places() {
        let (mut terms, mut u, j) = valley_node("v-groove/multiplier.toml");
        let (n_nodal, slaves) = (
            3 * terms.reference.len(),
            terms.pairs[0].passes[0].slaves.len(),
        );
        assert_eq!(terms.num_extra(), 2 * slaves);
        u[n_nodal + j] = -1.0;
        u[n_nodal + slaves + j] = -2.0;
        let (own, second) = across(&mut terms, &mut u, j, -1.0);
        assert!(
            own.is_some() && second.is_some() && own != second,
            "{own:?} {second:?}"
        );
        let lambdas = |terms: &ContactTerms| {
            let st = &terms.trial[0][0][j];
            (st.lambda, st.second.lambda)
        };
        assert_eq!(lambdas(&terms), (-1.0, -2.0));
        assert_eq!(across(&mut terms, &mut u, j, 1.0), (second, own));
        assert_eq!(lambdas(&terms), (-2.0, -1.0));
        assert_eq!(across(&mut terms, &mut u, j, -1.0), (own, second));
        assert_eq!(lambdas(&terms), (-1.0, -2.0));
    }

    #[test]
    fn a_node_held_closed_may_not_pull_beyond_the_tolerance_or_a_share_of_the_push() {
        let mut terms = patch_terms();
        let u = vec![0.0; 3 * terms.reference.len()];
        terms.begin_increment(&u).expect("begin");
        assert_eq!(terms.after_converged(&u), Ok(true), "nothing held");
        let (alpha, tol) = (terms.pairs[0].penalty, terms.pairs[0].tolerance);
        let tag = terms.node_tags[terms.pairs[0].passes[0].slaves[3]];
        let st = &mut terms.trial[0][0][3];
        st.held = true;
        st.active = true;
        st.lambda = -5.0 * alpha * tol;
        assert_eq!(terms.after_converged(&u), Ok(true), "pressing");
        // A pull within the tolerance, and below a tenth of another node's push.
        let other = &mut terms.trial[0][0][2];
        other.active = true;
        other.lambda = -10.0 * alpha * tol;
        terms.trial[0][0][3].lambda = 0.5 * alpha * tol;
        assert_eq!(
            terms.after_converged(&u),
            Ok(true),
            "a pull within the tolerance"
        );
        // The same pull, more than a tenth of the largest push: a wrong status.
        terms.trial[0][0][2].lambda = -2.0 * alpha * tol;
        let err = terms
            .after_converged(&u)
            .expect_err("a pull beyond the share");
        assert!(
            err.contains(&format!("slave node {tag} "))
                && err.contains("more than a tenth of the largest push"),
            "{err}"
        );
        // A held node that presses counts as a push too.
        terms.trial[0][0][2].held = true;
        terms.trial[0][0][2].lambda = -10.0 * alpha * tol;
        assert_eq!(terms.after_converged(&u), Ok(true), "a held node presses");
        // With no node pressing (first touch, lift-off), the gap bound alone.
        terms.trial[0][0][2].active = false;
        assert_eq!(terms.after_converged(&u), Ok(true), "within the tolerance");
        terms.trial[0][0][2].active = true;
        terms.trial[0][0][2].held = false;
        terms.trial[0][0][3].lambda = 2.0 * alpha * tol;
        let err = terms
            .after_converged(&[])
            .expect_err("a pull beyond the tolerance");
        assert!(err.contains(&format!("slave node {tag} ")), "{err}");
        terms.trial[0][0][3].held = false;
        assert_eq!(
            terms.after_converged(&u),
            Ok(true),
            "not held: its own status"
        );
    }
}
