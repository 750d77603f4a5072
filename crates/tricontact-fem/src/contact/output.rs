//! Contact result fields and history columns.
//!
//! Point fields (over all mesh nodes, zero where a node is not in contact — no sentinels):
//! * `contact_force`: contact force on the node (3 components), `−` the contact part of the
//!   internal force: `−λW` on a slave node, `λ N_a W` on the facet nodes;
//! * `contact_pressure`: `|contact_force| / A` with `A = ∫N_a dA` the node's lumped area on its
//!   contact surface; at the corners of tri6 faces, where `∫N_a dA = 0`, the mean over the
//!   mid-side nodes next to it (0 for other nodes without area);
//! * `contact_gap`: the slave node's gap `P` (first pass; 0 without facet), near a concave kink
//!   the smaller of its own and its second flank's;
//! * `contact_status`: 1 closed (on its own constraint or on a second flank), 0 open (slave
//!   nodes);
//! * `contact_facet`: Gmsh tag of the master face a closed slave node is on (its own facet's, or
//!   its second flank's where only that is closed; 0 when open).
//!
//! History columns per pair `<slave>-<master>`: `_normal_force` (`Σ −λ` over all slave nodes and
//! passes, a second flank's `λ` included), `_active` (nodes closed on either constraint, of both
//! passes with `two_pass`), `_max_penetration` (`max(0, −P)` over every slave node with a facet, open
//! or closed, so that a node left open inside the master shows), `_area`
//! (lumped area of the closed nodes; with `two_pass`, the mean of the two sides'; with
//! self-contact, half, both sides being slaves), `_min_pressure` and `_max_pressure` (`contact_pressure` over
//! the closed slave nodes that have an area; 0 when there are none).

use super::ContactTerms;
use crate::assembly::PointField;

impl ContactTerms {
    /// `|contact force| / A` of node `a` at the committed state; at a corner of tri6 faces (no
    /// area of its own) the mean over the mid-side nodes next to it; `None` for a node without
    /// area.
    fn pressure(&self, a: usize) -> Option<f64> {
        let own = |a: usize| {
            let f = &self.committed_force[3 * a..3 * a + 3];
            // Without squaring: forces past 10¹⁵⁴ (large models in small units) overflowed.
            let m = f[0].hypot(f[1]).hypot(f[2]);
            (self.areas[a] > 0.0).then(|| m / self.areas[a])
        };
        if self.areas[a] > 0.0 || self.proxies[a].is_empty() {
            return own(a);
        }
        let near: Vec<f64> = self.proxies[a].iter().filter_map(|&b| own(b)).collect();
        (!near.is_empty()).then(|| near.iter().sum::<f64>() / near.len() as f64)
    }

    /// The point fields at the committed state.
    #[must_use]
    pub fn fields(&self) -> Vec<PointField> {
        let n = self.reference.len();
        let mut gap = vec![0.0; n];
        let mut status = vec![0.0; n];
        let mut facet = vec![0.0; n];
        let mut pressure = vec![0.0; n];
        for (p, pair) in self.pairs.iter().enumerate() {
            for (q, pass) in pair.passes.iter().enumerate() {
                for (j, &s) in pass.slaves.iter().enumerate() {
                    let st = &self.committed[p][q][j];
                    if q == 0 {
                        // Near a concave kink the master is the union of the two flanks'
                        // half-spaces: the node's gap is the smaller.
                        gap[s] = match st.second.facet {
                            Some(_) => st.gap.min(st.second.gap),
                            None => st.gap,
                        };
                    }
                    if st.closed() {
                        status[s] = 1.0;
                        // The face it is on: its own, else its second flank's.
                        let on = if st.active { st.facet } else { st.second.facet };
                        if q == 0 {
                            facet[s] = on.map_or(0.0, |f| pass.face_tags[f as usize] as f64);
                        }
                    }
                }
            }
        }
        for (a, p) in pressure.iter_mut().enumerate() {
            *p = self.pressure(a).unwrap_or(0.0);
        }
        let field = |name: &str, components, values, integer| PointField {
            name: name.into(),
            components,
            values,
            integer,
        };
        vec![
            field("contact_force", 3, self.committed_force.clone(), false),
            field("contact_pressure", 1, pressure, false),
            field("contact_gap", 1, gap, false),
            field("contact_status", 1, status, true),
            field("contact_facet", 1, facet, true),
        ]
    }

    /// History columns at the committed state.
    #[must_use]
    pub fn columns(&self) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        for (p, pair) in self.pairs.iter().enumerate() {
            let (mut force, mut active, mut pen, mut area) = (0.0, 0usize, 0.0f64, 0.0);
            let (mut p_min, mut p_max) = (f64::INFINITY, 0.0f64);
            for (q, pass) in pair.passes.iter().enumerate() {
                for (j, st) in self.committed[p][q].iter().enumerate() {
                    force -= st.lambda + st.second.lambda;
                    if st.facet.is_some() {
                        pen = pen.max(-st.gap).max(st.flank);
                    }
                    if st.closed() {
                        active += 1;
                        area += pass.areas[j];
                        if let Some(p) = self.pressure(pass.slaves[j]) {
                            p_min = p_min.min(p);
                            p_max = p_max.max(p);
                        }
                    }
                }
            }
            out.push((format!("{}_normal_force", pair.name), force));
            out.push((format!("{}_active", pair.name), active as f64));
            out.push((format!("{}_max_penetration", pair.name), pen));
            // Each pass measures the contact area on its own slave side: their mean, not their
            // sum (two passes counted the interface twice). Self-contact has both sides of each
            // touching region in its one pass: half.
            let sides = if pair.is_self_contact() {
                2
            } else {
                pair.passes.len().max(1)
            };
            out.push((format!("{}_area", pair.name), area / sides as f64));
            out.push((format!("{}_min_pressure", pair.name), p_min.min(p_max)));
            out.push((format!("{}_max_pressure", pair.name), p_max));
        }
        out
    }
}
