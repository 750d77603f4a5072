//! Export of a resolved model to a CalculiX (Abaqus-format) input deck, `.inp`.
//!
//! The deck describes the same problem on the same mesh, so that results and run times can be
//! checked against CalculiX's `ccx` (`tricontact export MODEL`, `scripts/compare-calculix.sh`).
//!
//! # What maps one to one
//! * nodes (number = mesh index + 1, coordinates after any contact `adjust`), body elements
//!   (number = position among the body elements + 1): tet4 → `C3D4`, hex8 → `C3D8` (same node
//!   order as Gmsh), tet10 → `C3D10` (Gmsh's nodes 9 and 10 swapped: Gmsh puts edge 3–4 before
//!   edge 2–4, CalculiX after);
//! * linear elastic materials → `*ELASTIC` with `E = μ(3λ + 2μ)/(λ + μ)`, `ν = λ/(2(λ + μ))`
//!   (Saint-Venant–Kirchhoff under `NLGEOM` in both codes);
//! * supports and prescribed displacements, per step (`*BOUNDARY, OP=NEW`): the values are the
//!   targets at the end of the step, reached linearly over it, as here;
//! * loads as the very nodal forces this solver assembles (`*CLOAD, OP=NEW`, ramped over the
//!   step from the previous step's value, as here);
//! * steps: `*STATIC` with increments of `1/n` of the step, cut down to `1/(n·2^max_cutbacks)`,
//!   `NLGEOM` when `nlgeom = true`.
//!
//! # What is approximated (each case is listed in [`InpDeck::notes`])
//! * neo-Hooke → CalculiX's `NEO HOOKE` with `C10 = μ/2`, `D1 = 2/K`, `K = λ + 2μ/3`: the same
//!   small-strain moduli, but an isochoric/volumetric split `C10(Ī₁ − 3) + (J − 1)²/D1` instead of
//!   `μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)²`, so finite-strain answers differ;
//! * contact → CalculiX's node-to-surface penalty springs with a linear pressure–overclosure law
//!   (slave nodes as a node-based surface). CalculiX's slope `K` is a pressure per length: a node
//!   of tributary area `A` gets the spring stiffness `K·A`, whereas here every node gets the
//!   penalty `α` (force per length). The deck uses `K = α/A_min`, `A_min` the smallest area of
//!   the slave nodes that start within the search radius of the master (those likely to touch):
//!   equal stiffness on a uniform slave mesh, and no node softer than here on a graded one.
//!   Multiplier and augmented-Lagrangian pairs are exported as that penalty (CalculiX has no
//!   node-to-surface multipliers); a two-pass pair becomes two pairs. The springs' tension at
//!   large clearance is set to `2.5·10⁻⁵ E` (CalculiX asks for a small value);
//! * a master surface without volume (a rigid surface, every node held) becomes a layer of
//!   six-node wedges (`C3D6`) extruded away from the slave side by the mean facet edge; the
//!   extruded nodes are held as their originals are.
//!
//! # Not exportable
//! Follower pressures acting in an `nlgeom` step, and a master surface with faces of no body
//! element whose nodes are not all held in every step (a rigid surface always is: the model check
//! requires it; a surface mixing body faces with other faces may not be): [`write()`] returns an
//! error naming them.
//!
//! Set names are the group names reduced to letters, digits and `_` (CalculiX names are
//! case-insensitive), prefixed by the kind of set and its position, so that they stay unique.

use std::collections::HashMap;
use std::fmt::Write as _;

use tricontact::search::{Bvh, Query};

use crate::analysis::Analysis;
use crate::contact::ContactPair;
use crate::material::Law;
use crate::mesh::{Element, ElementKind};
use crate::model::ContactMethod;

/// An exported deck and the approximations it makes.
#[derive(Clone, Debug, PartialEq)]
pub struct InpDeck {
    /// The input deck.
    pub text: String,
    /// One line per approximation (also written as comments at the top of the deck).
    pub notes: Vec<String>,
}

/// Why a model cannot be exported.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("cannot export to .inp: {0}")]
pub struct InpError(pub String);

/// Corner positions of each face of a CalculiX volume element, faces `S1, S2, …` in order.
const TET_FACES: [&[usize]; 4] = [&[0, 1, 2], &[0, 1, 3], &[1, 2, 3], &[0, 2, 3]];
const HEX_FACES: [&[usize]; 6] = [
    &[0, 1, 2, 3],
    &[4, 5, 6, 7],
    &[0, 1, 4, 5],
    &[1, 2, 5, 6],
    &[2, 3, 6, 7],
    &[0, 3, 4, 7],
];

/// Lines of at most this many numbers in node and element lists.
const PER_LINE: usize = 16;

/// Writes the deck of `an` (see the module doc); `title` goes into `*HEADING`.
///
/// # Errors
/// [`InpError`] naming the load or contact surface that cannot be expressed.
pub fn write(an: &Analysis, title: &str) -> Result<InpDeck, InpError> {
    let mut deck = Deck::new(an);
    deck.check_followers()?;
    deck.nodes_and_elements();
    deck.materials();
    for (p, pair) in an.contacts.iter().enumerate() {
        deck.contact(p, pair)?;
    }
    deck.steps();
    let mut text = String::new();
    let _ = writeln!(text, "*HEADING\n{}", title.replace('\n', " "));
    let _ = writeln!(
        text,
        "** Written by tricontact {} (`tricontact export`).",
        env!("CARGO_PKG_VERSION")
    );
    for note in &deck.notes {
        let _ = writeln!(text, "** Note: {note}");
    }
    text.push_str(&deck.model);
    text.push_str(&deck.history);
    Ok(InpDeck {
        text,
        notes: deck.notes,
    })
}

/// The deck being written: model data, then history (steps).
struct Deck<'a> {
    an: &'a Analysis,
    model: String,
    history: String,
    notes: Vec<String>,
    /// Extruded copies of rigid master nodes: mesh node → deck node number.
    copies: HashMap<usize, usize>,
    /// Next free deck node and element numbers.
    next_node: usize,
    next_element: usize,
    /// Body elements around each mesh node (positions in `an.body`).
    around: Vec<Vec<usize>>,
    /// Wedge surfaces already written, by group (a rigid surface in several pairs is extruded once).
    wedged: HashMap<String, String>,
}

impl<'a> Deck<'a> {
    fn new(an: &'a Analysis) -> Self {
        let mut around = vec![Vec::new(); an.mesh.nodes.len()];
        for (b, be) in an.body.iter().enumerate() {
            for &a in &an.mesh.elements[be.element].nodes {
                around[a].push(b);
            }
        }
        Self {
            an,
            model: String::new(),
            history: String::new(),
            notes: Vec::new(),
            copies: HashMap::new(),
            next_node: an.mesh.nodes.len() + 1,
            next_element: an.body.len() + 1,
            around,
            wedged: HashMap::new(),
        }
    }

    fn check_followers(&self) -> Result<(), InpError> {
        for l in &self.an.loads {
            let nlgeom_step = (0..self.an.steps.len())
                .any(|s| (l.active[s] || (s > 0 && l.active[s - 1])) && self.an.steps[s].nlgeom);
            if l.follower.is_some() && nlgeom_step {
                return Err(InpError(format!(
                    "load '{}' is a follower pressure in an nlgeom step",
                    l.name
                )));
            }
        }
        Ok(())
    }

    /// `*NODE` (nodes of bodies and rigid surfaces) and one `*ELEMENT` block per body and type.
    fn nodes_and_elements(&mut self) {
        let an = self.an;
        let _ = writeln!(self.model, "*NODE, NSET=NALL");
        for (a, x) in an.mesh.nodes.iter().enumerate() {
            if an.active_nodes[a] {
                let _ = writeln!(
                    self.model,
                    "{}, {:.12e}, {:.12e}, {:.12e}",
                    a + 1,
                    x[0],
                    x[1],
                    x[2]
                );
            }
        }
        for (m, _) in an.materials.iter().enumerate() {
            for kind in [ElementKind::Tet4, ElementKind::Tet10, ElementKind::Hex8] {
                let members: Vec<usize> = (0..an.body.len())
                    .filter(|&b| {
                        an.body[b].material == m
                            && an.mesh.elements[an.body[b].element].kind == kind
                    })
                    .collect();
                if members.is_empty() {
                    continue;
                }
                let _ = writeln!(
                    self.model,
                    "*ELEMENT, TYPE={}, ELSET=EMAT{}",
                    ccx_type(kind),
                    m + 1
                );
                for b in members {
                    let nodes = ccx_nodes(&an.mesh.elements[an.body[b].element]);
                    let list: Vec<String> = nodes.iter().map(|a| (a + 1).to_string()).collect();
                    let _ = writeln!(self.model, "{}, {}", b + 1, list.join(", "));
                }
            }
        }
    }

    fn materials(&mut self) {
        for (m, mat) in self.an.materials.iter().enumerate() {
            // A material no body uses has no element set: CalculiX rejects a section without one.
            if !self.an.body.iter().any(|b| b.material == m) {
                continue;
            }
            let (lambda, mu) = (mat.lambda, mat.mu);
            let _ = writeln!(self.model, "*MATERIAL, NAME=MAT{}", m + 1);
            match mat.law {
                Law::LinearElastic => {
                    let e = youngs_modulus(mat);
                    let nu = lambda / (2.0 * (lambda + mu));
                    let _ = writeln!(self.model, "*ELASTIC\n{e:.12e}, {nu:.12e}");
                }
                Law::NeoHooke => {
                    let bulk = lambda + 2.0 * mu / 3.0;
                    let _ = writeln!(
                        self.model,
                        "*HYPERELASTIC, NEO HOOKE\n{:.12e}, {:.12e}",
                        mu / 2.0,
                        2.0 / bulk
                    );
                    self.notes.push(format!(
                        "material {}: neo-Hooke exported as CalculiX's NEO HOOKE (C10 = μ/2, D1 = 2/K): same small-strain moduli, another volumetric term at finite strain",
                        m + 1
                    ));
                }
            }
            let _ = writeln!(
                self.model,
                "*SOLID SECTION, ELSET=EMAT{0}, MATERIAL=MAT{0}",
                m + 1
            );
        }
    }

    /// Surfaces, interaction and pair(s) of contact pair `p`.
    fn contact(&mut self, p: usize, pair: &ContactPair) -> Result<(), InpError> {
        if pair.is_self_contact() {
            return Err(InpError(format!(
                "contact '{}': self-contact (slave = master) is not exported: CalculiX's node-to-surface pairs would constrain each node against its own side of the surface, which tricontact leaves out",
                pair.name
            )));
        }
        let pass = &pair.passes[0];
        let slope = self.slope(pair)?;
        if pair.method != ContactMethod::Penalty {
            self.notes.push(format!(
                "contact '{}': method {} exported as CalculiX's node-to-surface penalty with α = {:e}",
                pair.name, pair.method, pair.penalty
            ));
        }
        let tension = 2.5e-5
            * self
                .an
                .materials
                .iter()
                .map(youngs_modulus)
                .fold(0.0, f64::max);
        let master = self.face_surface(p, "M", &pair.master_group, pass)?;
        let slave = self.node_surface(p, &pair.slave_group, &pass.slaves);
        let _ = writeln!(
            self.model,
            "*SURFACE INTERACTION, NAME=SI{0}\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{slope:.12e}, {tension:.12e}",
            p + 1
        );
        let sliding = if pair.small_sliding {
            ", SMALL SLIDING"
        } else {
            ""
        };
        let mut pairs = vec![(slave.clone(), master.clone())];
        if pair.passes.len() > 1 {
            // Second pass: the master's nodes against the slave's faces.
            let back = self.face_surface(p, "N", &pair.slave_group, &pair.passes[1])?;
            let nodes =
                self.node_surface_named(&format!("SURF{}_SN", p + 1), &pair.passes[1].slaves);
            pairs.push((nodes, back));
        }
        for (s, m) in pairs {
            let _ = writeln!(
                self.model,
                "*CONTACT PAIR, INTERACTION=SI{}, TYPE=NODE TO SURFACE{sliding}\n{s}, {m}",
                p + 1
            );
        }
        Ok(())
    }

    /// CalculiX's spring slope `K` (pressure per length) for the pair's penalty `α` (force per
    /// length): `K·A` is a slave node's spring stiffness, `A` its tributary area, so
    /// `K = α/A_min` with `A_min` the smallest area of the slave nodes within the search radius of
    /// the master surface at the start (all slave nodes if none is), the nodes likely to touch:
    /// none of them is softer than here.
    fn slope(&mut self, pair: &ContactPair) -> Result<f64, InpError> {
        let pass = &pair.passes[0];
        let x = crate::contact::pair::positions(&self.an.mesh);
        let bvh = Bvh::build(&pass.surface, &x, pass.radius)
            .map_err(|e| InpError(format!("contact '{}': {e}", pair.name)))?;
        let near: Vec<f64> = pass
            .slaves
            .iter()
            .zip(&pass.areas)
            .filter(|&(&a, _)| {
                let q = Query::point(x[a]);
                bvh.closest(&pass.surface, &q, pass.radius).is_some()
            })
            .map(|(_, &area)| area)
            .collect();
        let areas = if near.is_empty() { &pass.areas } else { &near };
        let least = areas
            .iter()
            .copied()
            .filter(|&a| a > 0.0)
            .fold(f64::INFINITY, f64::min);
        if least.is_finite() {
            self.notes.push(format!(
                "contact '{}': spring slope K = α/A_min = {:.4e} (α = {:.4e}, A_min = {:.4e}, the smallest tributary area of {} slave nodes near the master)",
                pair.name,
                pair.penalty / least,
                pair.penalty,
                least,
                areas.len()
            ));
            Ok(pair.penalty / least)
        } else {
            self.notes.push(format!(
                "contact '{}': slave nodes without area, spring slope K = α",
                pair.name
            ));
            Ok(pair.penalty)
        }
    }

    /// The master surface of a pass: faces of body elements, or extruded wedges for a surface
    /// without volume.
    fn face_surface(
        &mut self,
        p: usize,
        tag: &str,
        group: &str,
        pass: &crate::contact::pair::Pass,
    ) -> Result<String, InpError> {
        let Some(g) = self.an.mesh.lookup(group, Some(2)).ok().flatten() else {
            return Err(InpError(format!("unknown surface group '{group}'")));
        };
        let faces: Option<Vec<(usize, usize)>> = g
            .elements
            .iter()
            .map(|&f| self.body_face(&self.an.mesh.elements[f]))
            .collect();
        match faces {
            Some(faces) => Ok(self.body_face_surface(p, tag, group, &faces)),
            None => self.wedge_surface(p, tag, group, pass),
        }
    }

    /// `(body position, face number 1-based)` of the body element whose face is `face`.
    fn body_face(&self, face: &Element) -> Option<(usize, usize)> {
        let corners = &face.nodes[..face.kind.num_corners()];
        self.around[corners[0]].iter().find_map(|&b| {
            let el = &self.an.mesh.elements[self.an.body[b].element];
            calculix_face(el, corners).map(|s| (b, s))
        })
    }

    /// The surface `(body element, face number)` of `faces`, named after `group`.
    fn body_face_surface(
        &mut self,
        p: usize,
        tag: &str,
        group: &str,
        faces: &[(usize, usize)],
    ) -> String {
        let name = surface_name(p, tag, group);
        let _ = writeln!(self.model, "*SURFACE, NAME={name}");
        for (b, s) in faces {
            let _ = writeln!(self.model, "{}, S{s}", b + 1);
        }
        name
    }

    /// A volume-less (rigid) master: one wedge per facet, extruded inwards.
    fn wedge_surface(
        &mut self,
        p: usize,
        tag: &str,
        group: &str,
        pass: &crate::contact::pair::Pass,
    ) -> Result<String, InpError> {
        if let Some(name) = self.wedged.get(group) {
            return Ok(name.clone());
        }
        let an = self.an;
        let facets = pass.surface.facets();
        let x = |a: usize| nalgebra::Vector3::from(an.mesh.nodes[a]);
        // Every node of the surface must be held in every step.
        let masks: Vec<Vec<bool>> = (0..an.steps.len())
            .map(|s| crate::driver::step_constraints(an, s).0)
            .collect();
        for &[i, j, k] in facets {
            for a in [i, j, k].map(|a| a as usize) {
                if !masks.iter().all(|m| m[3 * a..3 * a + 3].iter().all(|&h| h)) {
                    return Err(InpError(format!(
                        "surface '{group}' has faces of no body element (exported as wedges) and its node {} is not held in every step",
                        an.mesh.node_tags[a]
                    )));
                }
            }
        }
        // Inward direction per node: minus the sum of its facets' outward area normals.
        let mut inward: HashMap<usize, nalgebra::Vector3<f64>> = HashMap::new();
        let mut edge = 0.0;
        for &[i, j, k] in facets {
            let (a, b, c) = (x(i as usize), x(j as usize), x(k as usize));
            let n = (b - a).cross(&(c - a));
            edge += (b - a).norm() + (c - b).norm() + (a - c).norm();
            for v in [i, j, k] {
                *inward.entry(v as usize).or_default() -= n;
            }
        }
        let thickness = edge / (3.0 * facets.len().max(1) as f64);
        let mut new_nodes: Vec<usize> = inward.keys().copied().collect();
        new_nodes.sort_unstable();
        let _ = writeln!(self.model, "*NODE, NSET=NALL");
        for a in new_nodes {
            let d = inward[&a].normalize() * thickness;
            let y = x(a) + d;
            let id = self.next_node;
            self.next_node += 1;
            self.copies.insert(a, id);
            let _ = writeln!(
                self.model,
                "{id}, {:.12e}, {:.12e}, {:.12e}",
                y[0], y[1], y[2]
            );
        }
        let elset = format!("EWEDGE{}_{tag}", p + 1);
        let _ = writeln!(self.model, "*ELEMENT, TYPE=C3D6, ELSET={elset}");
        let mut wedges = Vec::new();
        for &[i, j, k] in facets {
            // (i, k, j): its right-hand normal points into the wedge, where nodes 4–6 lie.
            let base = [i, k, j].map(|a| a as usize);
            let id = self.next_element;
            self.next_element += 1;
            wedges.push(id);
            let _ = writeln!(
                self.model,
                "{id}, {}, {}, {}, {}, {}, {}",
                base[0] + 1,
                base[1] + 1,
                base[2] + 1,
                self.copies[&base[0]],
                self.copies[&base[1]],
                self.copies[&base[2]]
            );
        }
        // Held in every step, so any written material will do: that of the first body element.
        let material = self.an.body.first().map_or(0, |b| b.material) + 1;
        let _ = writeln!(
            self.model,
            "*SOLID SECTION, ELSET={elset}, MATERIAL=MAT{material}"
        );
        self.notes.push(format!(
            "surface '{group}' has no volume: exported as {} held wedges of thickness {thickness:.4e}",
            facets.len()
        ));
        let name = surface_name(p, tag, group);
        let _ = writeln!(self.model, "*SURFACE, NAME={name}");
        for id in wedges {
            let _ = writeln!(self.model, "{id}, S1");
        }
        self.wedged.insert(group.to_string(), name.clone());
        Ok(name)
    }

    fn node_surface(&mut self, p: usize, group: &str, nodes: &[usize]) -> String {
        self.node_surface_named(&surface_name(p, "S", group), nodes)
    }

    fn node_surface_named(&mut self, name: &str, nodes: &[usize]) -> String {
        let set = format!("N{name}");
        write_nset(&mut self.model, &set, nodes.iter().map(|a| a + 1));
        let _ = writeln!(self.model, "*SURFACE, NAME={name}, TYPE=NODE\n{set}");
        name.to_string()
    }

    /// Boundary node sets (with the extruded copies of their nodes), then one `*STEP` per step.
    fn steps(&mut self) {
        let an = self.an;
        for (k, b) in an.boundaries.iter().enumerate() {
            let mut ids: Vec<usize> = b.nodes.iter().map(|a| a + 1).collect();
            ids.extend(b.nodes.iter().filter_map(|a| self.copies.get(a).copied()));
            write_nset(&mut self.model, &boundary_set(k, &b.name), ids.into_iter());
        }
        for (s, step) in an.steps.iter().enumerate() {
            let nlgeom = if step.nlgeom { ", NLGEOM" } else { "" };
            let dt = 1.0 / step.increments as f64;
            let dt_min = dt / 2f64.powi(step.max_cutbacks.min(60) as i32);
            let h = &mut self.history;
            let _ = writeln!(
                h,
                "** Step {}: {}\n*STEP{nlgeom}, INC={}\n*STATIC\n{dt:.12e}, 1., {dt_min:.12e}, {dt:.12e}",
                s + 1,
                step.name,
                1000 + step.increments * (1 << step.max_cutbacks.min(10))
            );
            let _ = writeln!(h, "*BOUNDARY, OP=NEW");
            for (k, b) in an
                .boundaries
                .iter()
                .enumerate()
                .filter(|(_, b)| b.active[s])
            {
                for (c, v) in b.values.iter().enumerate() {
                    if let Some(v) = v {
                        let _ = writeln!(
                            h,
                            "{}, {}, {}, {v:.12e}",
                            boundary_set(k, &b.name),
                            c + 1,
                            c + 1
                        );
                    }
                }
            }
            let mut forces: Vec<([f64; 3], usize)> = Vec::new();
            let mut index: HashMap<usize, usize> = HashMap::new();
            for l in an.loads.iter().filter(|l| l.active[s]) {
                for &(a, f) in &l.forces {
                    let slot = *index.entry(a).or_insert_with(|| {
                        forces.push(([0.0; 3], a));
                        forces.len() - 1
                    });
                    for c in 0..3 {
                        forces[slot].0[c] += f[c];
                    }
                }
            }
            forces.sort_by_key(|f| f.1);
            let _ = writeln!(h, "*CLOAD, OP=NEW");
            for (f, a) in forces {
                for (c, v) in f.iter().enumerate() {
                    if *v != 0.0 {
                        let _ = writeln!(h, "{}, {}, {v:.12e}", a + 1, c + 1);
                    }
                }
            }
            let _ = writeln!(h, "*NODE FILE\nU\n*EL FILE\nS");
            for (k, b) in an
                .boundaries
                .iter()
                .enumerate()
                .filter(|(_, b)| b.active[s])
            {
                let _ = writeln!(
                    h,
                    "*NODE PRINT, NSET={}, TOTALS=ONLY\nRF",
                    boundary_set(k, &b.name)
                );
            }
            let _ = writeln!(h, "*END STEP");
        }
    }
}

/// Young's modulus `E = μ(3λ + 2μ)/(λ + μ)` of a material given by its Lamé constants.
fn youngs_modulus(m: &crate::material::Material) -> f64 {
    m.mu * (3.0 * m.lambda + 2.0 * m.mu) / (m.lambda + m.mu)
}

fn boundary_set(k: usize, name: &str) -> String {
    format!("NB{}_{}", k + 1, clean(name))
}

fn write_nset(out: &mut String, name: &str, ids: impl Iterator<Item = usize>) {
    let _ = writeln!(out, "*NSET, NSET={name}");
    let ids: Vec<String> = ids.map(|i| i.to_string()).collect();
    for line in ids.chunks(PER_LINE) {
        let _ = writeln!(out, "{}", line.join(", "));
    }
}

/// The deck's name of the surface of group `group` in contact pair `p` (`tag`: slave or master).
fn surface_name(p: usize, tag: &str, group: &str) -> String {
    format!("SURF{}_{tag}_{}", p + 1, clean(group))
}

/// A group name reduced to what CalculiX accepts in a set name.
fn clean(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_uppercase()
            } else {
                '_'
            }
        })
        .take(40)
        .collect()
}

/// The number (1-based, `S1`, `S2`, …) of the face of CalculiX element `el` (mesh node indices,
/// Gmsh order; tet4, tet10 or hex8) whose corners include all of `corners`, if any.
#[must_use]
pub fn calculix_face(el: &Element, corners: &[usize]) -> Option<usize> {
    let own = &el.nodes[..el.kind.num_corners()];
    let local: Option<Vec<usize>> = corners
        .iter()
        .map(|a| own.iter().position(|n| n == a))
        .collect();
    let local = local?;
    let faces: &[&[usize]] = match el.kind {
        ElementKind::Hex8 => &HEX_FACES,
        ElementKind::Tet4 | ElementKind::Tet10 => &TET_FACES,
        _ => return None,
    };
    faces
        .iter()
        .position(|f| local.iter().all(|c| f.contains(c)))
        .map(|s| s + 1)
}

fn ccx_type(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Tet10 => "C3D10",
        ElementKind::Hex8 => "C3D8",
        _ => "C3D4",
    }
}

/// The element's nodes in CalculiX order (mesh indices).
fn ccx_nodes(el: &Element) -> Vec<usize> {
    let mut nodes = el.nodes.clone();
    if el.kind == ElementKind::Tet10 {
        nodes.swap(8, 9);
    }
    nodes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tet10_swaps_the_last_two_edge_nodes() {
        let el = Element {
            kind: ElementKind::Tet10,
            nodes: (0..10).collect(),
            tag: 1,
        };
        assert_eq!(ccx_nodes(&el), vec![0, 1, 2, 3, 4, 5, 6, 7, 9, 8]);
    }

    #[test]
    fn names_are_reduced_to_letters_digits_and_underscores() {
        assert_eq!(clean("block-top face"), "BLOCK_TOP_FACE");
    }
}
