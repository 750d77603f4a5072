//! Resolution of a [`Model`] against a [`Mesh`]: bodies, materials, supports,
//! loads and steps as index data ready for assembly, plus validation.
//!
//! Validation collects every problem (unknown groups, materials, conflicting
//! supports, loads on nodes of no body, inverted or zero-volume elements)
//! instead of stopping at the first, so `tricontact check` can list them.
//! An element is *zero-volume* when `min |det J| ≤ 1e-8 h³` at its
//! integration points (`h` its largest corner distance) and *inverted* when
//! some `det J < 0`.

use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

use crate::contact::ContactPair;
use crate::element::jacobian_dets;
use crate::error::{FemError, Result};
use crate::loads;
use crate::material::{Law, Material};
use crate::mesh::{ElementKind, Mesh};
use crate::model::{Extrapolation, MaterialKind, Model, OutputDef};
use crate::shape::{self, QPoint};

/// A volume element taking part in the analysis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyElement {
    /// Index into [`Mesh::elements`].
    pub element: usize,
    /// Index into [`Analysis::materials`].
    pub material: usize,
}

/// A support or prescribed displacement on a node set.
#[derive(Clone, Debug, PartialEq)]
pub struct Boundary {
    /// Group name (history columns use it).
    pub name: String,
    /// Nodes (only nodes of bodies).
    pub nodes: Vec<usize>,
    /// Per component: `Some(target)` if constrained.
    pub values: [Option<f64>; 3],
    /// Active flag per step.
    pub active: Vec<bool>,
}

/// A dead load as nodal forces at amplitude 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Load {
    /// Group name.
    pub name: String,
    /// `(node, force)` pairs, sorted by node.
    pub forces: Vec<(usize, [f64; 3])>,
    /// Follower pressure `(p, oriented faces)`: in `nlgeom` steps it acts on
    /// the deformed surface instead of `forces`.
    pub follower: Option<(f64, Vec<(usize, f64)>)>,
    /// Active flag per step.
    pub active: Vec<bool>,
}

/// Step controls.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// Name.
    pub name: String,
    /// Initial number of increments.
    pub increments: usize,
    /// Newton iterations per increment.
    pub max_iterations: usize,
    /// Relative residual tolerance.
    pub residual_tolerance: f64,
    /// Relative correction tolerance.
    pub displacement_tolerance: f64,
    /// Finite strain.
    pub nlgeom: bool,
    /// Allowed halvings of an increment.
    pub max_cutbacks: usize,
    /// Newton's starting point of an increment.
    pub extrapolation: Extrapolation,
    /// Line search along Newton corrections ([`crate::newton`]).
    pub line_search: bool,
}

/// Everything the solver needs, resolved to indices.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The mesh.
    pub mesh: Mesh,
    /// Materials.
    pub materials: Vec<Material>,
    /// Volume elements in bodies.
    pub body: Vec<BodyElement>,
    /// Quadrature rules per volume kind.
    pub rules: Vec<(ElementKind, Vec<QPoint>)>,
    /// Nodes used by some body element.
    pub active_nodes: Vec<bool>,
    /// Supports.
    pub boundaries: Vec<Boundary>,
    /// Loads.
    pub loads: Vec<Load>,
    /// Steps.
    pub steps: Vec<Step>,
    /// Contact pairs.
    pub contacts: Vec<ContactPair>,
    /// Output settings.
    pub output: OutputDef,
    /// Resolved output folder.
    pub output_dir: PathBuf,
    /// Notes on the model as written (a material no body uses), for [`Analysis::notes`].
    model_notes: Vec<String>,
}

/// Most increments (and Newton iterations) a step may ask for.
pub const MAX_INCREMENTS: usize = 1_000_000;

/// Most halvings of an increment: 30 already make it 10⁻⁹ of the step.
pub const MAX_CUTBACKS: usize = 30;

/// Young's modulus accepted: `1/MAX_MODULUS < E < MAX_MODULUS`, far beyond any unit system at
/// both ends, so that the default penalty `10 E h`, the stiffness matrix and the Lamé constants
/// stay finite and nonzero.
pub const MAX_MODULUS: f64 = 1e100;

impl Analysis {
    /// Resolves and validates; fails with the single problem found or with
    /// [`FemError::Invalid`] listing all of them.
    ///
    /// # Errors
    /// Any validation problem.
    pub fn new(model: &Model, mesh: Mesh) -> Result<Self> {
        mesh.check()?;
        let (an, problems) = Self::build(model, mesh);
        match FemError::combine(problems) {
            None => Ok(an),
            Some(e) => Err(e),
        }
    }

    /// Quadrature rule of a volume kind.
    #[must_use]
    pub fn rule(&self, kind: ElementKind) -> &[QPoint] {
        self.rules
            .iter()
            .find(|(k, _)| *k == kind)
            .map_or(&[], |(_, r)| r.as_slice())
    }

    /// Remarks on the model that are not errors: a material no body uses, and, one per step and
    /// cause, a `line_search` that
    /// cannot apply (the residual is not an energy gradient: Lagrange multipliers, follower
    /// pressures), and a body part whose rigid motion neither its boundaries nor the normals of
    /// its contacts hold (frictionless contact holds a slave node, and the facet it faces, only
    /// along the facet normal; the normals are those at the start, of slave nodes within reach of
    /// a master facet). Without contact pairs such a body is an error, not a note.
    #[must_use]
    pub fn notes(&self) -> Vec<String> {
        let mut notes = self.model_notes.clone();
        notes.extend(self.line_search_notes());
        if self.contacts.is_empty() {
            return notes;
        }
        let held = self.initial_contact_normals();
        for (s, step) in self.steps.iter().enumerate() {
            let (mask, _) = crate::driver::step_constraints(self, s);
            if let Err(m) = crate::rigid::check_supports_with(self, &mask, &held) {
                notes.push(format!(
                    "step '{}': with its boundaries and the initial contact normals, {}; \
                     frictionless contact leaves such motion undetermined",
                    step.name,
                    m.trim_end_matches("; add supports")
                ));
            }
        }
        notes
    }

    /// `(node, normal)` for each slave node within reach of a master facet at the reference
    /// positions, and for the nodes of that facet.
    fn initial_contact_normals(&self) -> Vec<(usize, [f64; 3])> {
        let x: Vec<tricontact::Vec3> = self
            .mesh
            .nodes
            .iter()
            .map(|p| tricontact::Vec3::new(p[0], p[1], p[2]))
            .collect();
        let mut held = Vec::new();
        for pass in self.contacts.iter().flat_map(|c| &c.passes) {
            let Ok(bvh) = tricontact::search::Bvh::build(&pass.surface, &x, pass.radius) else {
                continue;
            };
            for &s in &pass.slaves {
                let Some((f, pair)) = u32::try_from(s).ok().and_then(|node| {
                    tricontact::contact::choose_facet(&pass.surface, &bvh, &x, node, pass.radius)
                }) else {
                    continue;
                };
                let w = pair.facet.normal();
                let w = [w[0], w[1], w[2]];
                held.push((s, w));
                for a in pass.surface.facets()[f as usize] {
                    held.push((a as usize, w));
                }
            }
        }
        held
    }

    fn line_search_notes(&self) -> Vec<String> {
        let multipliers: Vec<&str> = self
            .contacts
            .iter()
            .filter(|c| c.method == crate::model::ContactMethod::Multiplier)
            .map(|c| c.name.as_str())
            .collect();
        let mut notes = Vec::new();
        for (s, step) in self
            .steps
            .iter()
            .enumerate()
            .filter(|(_, st)| st.line_search)
        {
            let followers: Vec<&str> = self
                .loads
                .iter()
                .filter(|l| l.follower.is_some() && l.active[s])
                .map(|l| l.name.as_str())
                .collect();
            for (what, names) in [
                ("Lagrange-multiplier contact", &multipliers),
                ("follower pressure", &followers),
            ] {
                if !names.is_empty() {
                    notes.push(format!(
                        "step '{}': line_search is ignored with {what} ({}): the residual is not \
                         the gradient of an energy",
                        step.name,
                        names.join(", ")
                    ));
                }
            }
        }
        notes
    }

    /// Number of nodal degrees of freedom (`3 × nodes`, inactive included).
    #[must_use]
    pub fn num_nodal_dofs(&self) -> usize {
        3 * self.mesh.nodes.len()
    }

    /// Reference coordinates and displacements of the nodes of mesh element `element`, taken from
    /// the global displacement vector `u` (`3a + i`).
    #[must_use]
    pub fn element_state(&self, element: usize, u: &[f64]) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let nodes = &self.mesh.elements[element].nodes;
        let x0 = nodes.iter().map(|&a| self.mesh.nodes[a]).collect();
        let ue = nodes
            .iter()
            .map(|&a| [u[3 * a], u[3 * a + 1], u[3 * a + 2]])
            .collect();
        (x0, ue)
    }

    /// Resolves the model, returning the analysis and every problem found. The mesh must pass
    /// [`Mesh::check`] (the Gmsh reader's meshes do; [`Analysis::new`] checks it).
    #[must_use]
    pub fn build(model: &Model, mut mesh: Mesh) -> (Self, Vec<FemError>) {
        let mut problems: Vec<FemError> = Vec::new();
        let unknown =
            |at: String, kind: &'static str, name: &str, mesh: &Mesh| FemError::UnknownGroup {
                at,
                kind,
                name: name.to_string(),
                available: mesh.group_list(),
            };
        let invalid = |s: String| FemError::Invalid(vec![s]);
        // The place of a key in the model file, to start a message with.
        let src = &model.source;

        // Steps.
        if model.steps.is_empty() {
            problems.push(invalid("no [[step]] defined".into()));
        }
        let steps: Vec<Step> = model
            .steps
            .iter()
            .enumerate()
            .map(|(i, s)| Step {
                name: model.step_name(i),
                increments: s.increments,
                max_iterations: s.max_iterations,
                residual_tolerance: s.residual_tolerance,
                displacement_tolerance: s.displacement_tolerance,
                nlgeom: s.nlgeom,
                max_cutbacks: s.max_cutbacks,
                extrapolation: s.extrapolation,
                line_search: s.line_search,
            })
            .collect();
        for (i, s) in steps.iter().enumerate() {
            if s.name.trim().is_empty() {
                problems.push(invalid(format!(
                    "{}step {}: the name is empty",
                    src.at("step", i, "name"),
                    i + 1
                )));
            }
            if steps[..i].iter().any(|t| t.name == s.name) {
                problems.push(invalid(format!(
                    "{}step name '{}' is used twice (`steps = [...]` must name one step)",
                    src.at("step", i, "name"),
                    s.name
                )));
            }
            for (key, value, low, high) in [
                ("increments", s.increments, 1, MAX_INCREMENTS),
                ("max_iterations", s.max_iterations, 1, MAX_INCREMENTS),
                ("max_cutbacks", s.max_cutbacks, 0, MAX_CUTBACKS),
            ] {
                if !(low..=high).contains(&value) {
                    problems.push(invalid(format!(
                        "{}step '{}': {key} must be from {low} to {high} (got {value})",
                        src.at("step", i, key),
                        s.name
                    )));
                }
            }
            for (key, value) in [
                ("residual_tolerance", s.residual_tolerance),
                ("displacement_tolerance", s.displacement_tolerance),
            ] {
                if !(value > 0.0 && value < 1.0) {
                    problems.push(invalid(format!(
                        "{}step '{}': {key} must be > 0 and < 1 (got {value})",
                        src.at("step", i, key),
                        s.name
                    )));
                }
            }
        }
        let step_mask = |steps_opt: &Option<Vec<String>>,
                         what: &str,
                         problems: &mut Vec<FemError>|
         -> Vec<bool> {
            match steps_opt {
                None => vec![true; steps.len()],
                Some(names) => {
                    if names.is_empty() {
                        problems.push(invalid(format!(
                            "{what}: `steps = []` names no step, so it would never act (omit `steps` for every step)"
                        )));
                    }
                    for (i, n) in names.iter().enumerate() {
                        if names[..i].contains(n) {
                            problems.push(invalid(format!("{what}: step '{n}' is listed twice")));
                        }
                        if !steps.iter().any(|s| &s.name == n) {
                            problems.push(invalid(format!(
                                "{what}: unknown step '{n}' (steps: {})",
                                steps
                                    .iter()
                                    .map(|s| s.name.as_str())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            )));
                        }
                    }
                    steps.iter().map(|s| names.contains(&s.name)).collect()
                }
            }
        };

        // Materials.
        let mut materials = Vec::new();
        let mut mat_index = HashMap::new();
        for (i, m) in model.materials.iter().enumerate() {
            if m.name.trim().is_empty() {
                problems.push(invalid(format!(
                    "{}material {}: the name is empty",
                    src.at("material", i, "name"),
                    i + 1
                )));
            }
            let valid = m.e > 1.0 / MAX_MODULUS && m.e < MAX_MODULUS && m.nu > -1.0 && m.nu < 0.5;
            if !valid {
                let modulus_valid = m.e > 1.0 / MAX_MODULUS && m.e < MAX_MODULUS;
                let keys: &[&str] = if modulus_valid {
                    &["nu", "poisson_ratio"]
                } else {
                    &["E", "youngs_modulus"]
                };
                problems.push(invalid(format!(
                    "{}material '{}': need 1e-100 < E < 1e100 and -1 < nu < 0.5 (got E = {:e}, nu = {})",
                    src.at_first("material", i, keys),
                    m.name,
                    m.e,
                    // Plain for the usual values, in exponent form for absurd ones (1e300 was
                    // printed with its 301 digits).
                    if m.nu.abs() < 1e6 {
                        m.nu.to_string()
                    } else {
                        format!("{:e}", m.nu)
                    }
                )));
            }
            if mat_index.insert(m.name.clone(), materials.len()).is_some() {
                problems.push(invalid(format!(
                    "{}material '{}' defined twice",
                    src.at("material", i, "name"),
                    m.name
                )));
            }
            let law = match m.kind {
                MaterialKind::LinearElastic => Law::LinearElastic,
                MaterialKind::NeoHooke => Law::NeoHooke,
            };
            materials.push(Material::from_e_nu(law, m.e, m.nu));
        }

        // Bodies. When one cannot be resolved, the checks that depend on which nodes belong to a
        // body (supports, loads, contact) are skipped: they would only repeat the problem.
        let before_bodies = problems.len();
        let mut body = Vec::new();
        let mut owner: Vec<Option<usize>> = vec![None; mesh.elements.len()];
        if model.bodies.is_empty() {
            problems.push(invalid("no [[body]] defined".into()));
        }
        // Elements claimed by two bodies: (first body, second body) -> (count, first tag).
        let mut shared: BTreeMap<(usize, usize), (usize, u64)> = BTreeMap::new();
        let mut owner_def: Vec<usize> = vec![usize::MAX; mesh.elements.len()];
        for (bi, b) in model.bodies.iter().enumerate() {
            if model.bodies[..bi].iter().any(|c| c.group == b.group) {
                problems.push(invalid(format!(
                    "{}body group '{}' is listed twice",
                    src.at("body", bi, "group"),
                    b.group
                )));
                continue;
            }
            let Some(&mi) = mat_index.get(&b.material) else {
                problems.push(invalid(format!(
                    "{}body '{}': unknown material '{}' (materials: {})",
                    src.at("body", bi, "material"),
                    b.group,
                    b.material,
                    model
                        .materials
                        .iter()
                        .map(|m| m.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
                continue;
            };
            let here = src.at("body", bi, "group");
            match mesh.lookup(&b.group, Some(3)) {
                Err(m) => problems.push(invalid(format!("{here}body: {m}"))),
                Ok(Some(g)) if g.dim == 3 && g.elements.is_empty() => problems.push(invalid(
                    format!("{here}body '{}': the volume group has no elements", b.group),
                )),
                Ok(Some(g)) if g.dim == 3 => {
                    for &e in &g.elements {
                        if owner[e].is_some() {
                            let entry = shared
                                .entry((owner_def[e], bi))
                                .or_insert((0, mesh.elements[e].tag));
                            entry.0 += 1;
                            continue;
                        }
                        owner[e] = Some(body.len());
                        owner_def[e] = bi;
                        body.push(BodyElement {
                            element: e,
                            material: mi,
                        });
                    }
                }
                Ok(Some(g)) => problems.push(invalid(format!(
                    "{here}body group '{}' has dimension {}, a volume (3D) group is needed",
                    g.name, g.dim
                ))),
                Ok(None) => problems.push(unknown(here, "volume", &b.group, &mesh)),
            }
        }
        for ((a, b), (count, tag)) in shared {
            problems.push(invalid(format!(
                "{}bodies '{}' and '{}' share {count} element(s) (the first: Gmsh tag {tag}); an element belongs to one body",
                src.at("body", b, "group"),
                model.bodies[a].group,
                model.bodies[b].group
            )));
        }
        let bodies_ok = problems.len() == before_bodies;
        let mut active_nodes = vec![false; mesh.nodes.len()];
        for be in &body {
            for &a in &mesh.elements[be.element].nodes {
                active_nodes[a] = true;
            }
        }
        let mut kinds: Vec<ElementKind> =
            body.iter().map(|b| mesh.elements[b.element].kind).collect();
        kinds.sort_unstable();
        kinds.dedup();
        let rules: Vec<(ElementKind, Vec<QPoint>)> =
            kinds.iter().map(|&k| (k, shape::rule(k))).collect();

        // Element quality.
        let mut bad = 0usize;
        for (bi, be) in body.iter().enumerate() {
            let el = &mesh.elements[be.element];
            let x0: Vec<[f64; 3]> = el.nodes.iter().map(|&a| mesh.nodes[a]).collect();
            let rule = &rules
                .iter()
                .find(|(k, _)| *k == el.kind)
                .expect("rule exists")
                .1;
            let dets = jacobian_dets(rule, &x0);
            let corners = &x0[..el.kind.num_corners()];
            let mut h = 0.0f64;
            for p in corners {
                for q in corners {
                    h = h.max(
                        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2))
                            .sqrt(),
                    );
                }
            }
            let min_abs = dets.iter().fold(f64::INFINITY, |m, d| m.min(d.abs()));
            let min_det = dets.iter().fold(f64::INFINITY, |m, &d| m.min(d));
            let problem = if min_abs <= 1e-8 * h.powi(3) {
                Some(FemError::ZeroVolume {
                    element: bi,
                    tag: el.tag,
                    det_j: min_abs / h.powi(3).max(f64::MIN_POSITIVE),
                })
            } else if min_det < 0.0 {
                Some(FemError::InvertedElement {
                    element: bi,
                    tag: el.tag,
                    det_j: min_det,
                })
            } else {
                None
            };
            if let Some(p) = problem {
                bad += 1;
                if bad <= 10 {
                    problems.push(p);
                }
            }
        }
        if bad > 10 {
            problems.push(invalid(format!(
                "{} more inverted or zero-volume elements",
                bad - 10
            )));
        }

        // Contact pairs (may move adjusted slave nodes; rigid master nodes become active).
        let in_body = active_nodes.clone();
        let mut rigid = vec![false; mesh.nodes.len()];
        let mut contacts = Vec::new();
        let before_contacts = problems.len();
        {
            let youngs: Vec<f64> = body
                .iter()
                .map(|b| {
                    let m = &materials[b.material];
                    m.mu * (3.0 * m.lambda + 2.0 * m.mu) / (m.lambda + m.mu)
                })
                .collect();
            let mut moved = mesh.clone();
            let bodies = crate::contact::pair::Bodies {
                elements: body.iter().map(|b| &mesh.elements[b.element]).collect(),
                youngs,
            };
            for (i, c) in model.contacts.iter().enumerate() {
                let name = format!("{}-{}", c.slave, c.master);
                if c.slave == c.master {
                    problems.push(invalid(format!(
                        "{}contact '{name}': slave and master are the same group (self-contact is not supported)",
                        src.at("contact", i, "master")
                    )));
                    continue;
                }
                if model.contacts[..i]
                    .iter()
                    .any(|d| d.slave == c.slave && d.master == c.master)
                {
                    problems.push(invalid(format!(
                        "{}contact '{name}' is defined twice (its force would be applied twice)",
                        src.at("contact", i, "")
                    )));
                    continue;
                }
                if !bodies_ok {
                    continue;
                }
                let at = |key: &str| src.at("contact", i, key);
                match crate::contact::pair::resolve(
                    c, &mut moved, &bodies, &in_body, &mut rigid, &at,
                ) {
                    Ok(p) => contacts.push(p),
                    Err(list) => problems.extend(list.into_iter().map(&invalid)),
                }
            }
            drop(bodies);
            mesh.nodes = moved.nodes;
        }
        for (a, &r) in rigid.iter().enumerate() {
            if r {
                active_nodes[a] = true;
            }
        }

        // Nodes belong to a body, or to a rigid master, only once both resolved.
        let nodes_known = bodies_ok && problems.len() == before_contacts;

        // Boundaries.
        let mut boundaries = Vec::new();
        // The index in the model of each resolved boundary (one with an unknown group is left
        // out of `boundaries`).
        let mut boundary_defs = Vec::new();
        for (bi, b) in model.boundaries.iter().enumerate() {
            let at = |key: &str| src.at("boundary", bi, key);
            let active = step_mask(
                &b.steps,
                &format!("{}boundary '{}'", at("steps"), b.group),
                &mut problems,
            );
            let g = match mesh.lookup(&b.group, None) {
                Ok(Some(g)) => g,
                Ok(None) => {
                    problems.push(unknown(at("group"), "node", &b.group, &mesh));
                    continue;
                }
                Err(m) => {
                    problems.push(invalid(format!("{}boundary: {m}", at("group"))));
                    continue;
                }
            };
            let mut values = [None; 3];
            for c in &b.fix {
                if values[c.index()].is_some() {
                    problems.push(invalid(format!(
                        "{}boundary '{}': component {} is listed twice in `fix`",
                        at("fix"),
                        b.group,
                        ["x", "y", "z"][c.index()]
                    )));
                }
                values[c.index()] = Some(0.0);
            }
            if let Some(d) = &b.displacement {
                for (i, v) in [d.x, d.y, d.z].into_iter().enumerate() {
                    if let Some(v) = v {
                        if values[i].is_some() {
                            problems.push(invalid(format!(
                                "{}boundary '{}': component {} is both fixed and prescribed",
                                at(&format!("displacement.{}", ["x", "y", "z"][i])),
                                b.group,
                                ["x", "y", "z"][i]
                            )));
                        }
                        if !v.is_finite() {
                            problems.push(invalid(format!(
                                "{}boundary '{}': non-finite displacement",
                                at(&format!("displacement.{}", ["x", "y", "z"][i])),
                                b.group
                            )));
                        }
                        values[i] = Some(v);
                    }
                }
            }
            if values.iter().all(Option::is_none) {
                problems.push(invalid(format!(
                    "{}boundary '{}': give `fix` components or a `displacement`",
                    at(""),
                    b.group
                )));
            }
            let nodes: Vec<usize> = g
                .nodes
                .iter()
                .copied()
                .filter(|&a| active_nodes[a])
                .collect();
            if nodes.is_empty() && nodes_known {
                problems.push(invalid(format!(
                    "{}boundary '{}': the group has no node of any body",
                    at("group"),
                    b.group
                )));
            }
            boundary_defs.push(bi);
            boundaries.push(Boundary {
                name: b.group.clone(),
                nodes,
                values,
                active,
            });
        }
        // Conflicting prescribed values on a shared DOF within a step: one message per step and
        // pair of boundaries (numbered as in the model), with the count and the first node.
        for s in 0..steps.len() {
            let mut seen: HashMap<(usize, usize), (f64, usize)> = HashMap::new();
            let mut clashes: BTreeMap<(usize, usize), (usize, u64)> = BTreeMap::new();
            for (bi, b) in boundaries.iter().enumerate().filter(|(_, b)| b.active[s]) {
                for &a in &b.nodes {
                    for (i, v) in b.values.iter().enumerate() {
                        let Some(v) = *v else { continue };
                        match seen.get(&(a, i)) {
                            Some(&(w, other)) if w != v => {
                                let c =
                                    clashes.entry((other, bi)).or_insert((0, mesh.node_tags[a]));
                                c.0 += 1;
                            }
                            Some(_) => {}
                            None => {
                                seen.insert((a, i), (v, bi));
                            }
                        }
                    }
                }
            }
            for ((a, b), (count, node)) in clashes {
                let (da, db) = (boundary_defs[a], boundary_defs[b]);
                problems.push(invalid(format!(
                    "{}step '{}': boundaries {} ('{}') and {} ('{}') prescribe different values on {count} node component(s), the first at node {node}",
                    src.at("boundary", db, ""),
                    steps[s].name,
                    da + 1,
                    boundaries[a].name,
                    db + 1,
                    boundaries[b].name
                )));
            }
        }

        // Rigid master nodes (no volume element) must be fully prescribed in every step: each
        // of x, y and z by some boundary (a bit per component, so that two boundaries holding
        // the same component do not count as two).
        for s in 0..steps.len() {
            let mut held = vec![0u8; mesh.nodes.len()];
            for b in boundaries.iter().filter(|b| b.active[s]) {
                for &a in &b.nodes {
                    for (i, v) in b.values.iter().enumerate() {
                        if v.is_some() {
                            held[a] |= 1 << i;
                        }
                    }
                }
            }
            if let Some(a) = (0..mesh.nodes.len()).find(|&a| rigid[a] && held[a] != 0b111) {
                // The message points at the first pair whose master holds the node.
                let pair = model.contacts.iter().position(|c| {
                    matches!(mesh.lookup(&c.master, Some(2)), Ok(Some(g)) if g.nodes.contains(&a))
                });
                let free: Vec<&str> = (0..3)
                    .filter(|i| held[a] & (1 << i) == 0)
                    .map(|i| ["x", "y", "z"][i])
                    .collect();
                problems.push(invalid(format!(
                    "{}step '{}': node {} of a rigid contact surface (no volume element) must have x, y and z prescribed ({} free)",
                    pair.map(|i| src.at("contact", i, "master")).unwrap_or_default(),
                    steps[s].name,
                    mesh.node_tags[a],
                    free.join(", ")
                )));
            }
        }

        // Loads.
        let body_refs: Vec<&crate::mesh::Element> =
            body.iter().map(|b| &mesh.elements[b.element]).collect();
        let node_elems = loads::node_to_elements(mesh.nodes.len(), &body_refs);
        let mut load_list = Vec::new();
        for (li, l) in model.loads.iter().enumerate() {
            let at = |key: &str| src.at("load", li, key);
            let active = step_mask(
                &l.steps,
                &format!("{}load '{}'", at("steps"), l.group),
                &mut problems,
            );
            let g = match mesh.lookup(&l.group, l.pressure.is_some().then_some(2)) {
                Ok(Some(g)) => g,
                Ok(None) => {
                    let kind = if l.pressure.is_some() {
                        "surface"
                    } else {
                        "node"
                    };
                    problems.push(unknown(at("group"), kind, &l.group, &mesh));
                    continue;
                }
                Err(m) => {
                    problems.push(invalid(format!("{}load: {m}", at("group"))));
                    continue;
                }
            };
            if l.force.is_some() == l.pressure.is_some() {
                problems.push(invalid(format!(
                    "{}load '{}': give exactly one of `force` or `pressure`",
                    at(""),
                    l.group
                )));
                continue;
            }
            let force_finite = l.force.is_none_or(|f| f.iter().all(|c| c.is_finite()));
            if !force_finite || !l.pressure.is_none_or(f64::is_finite) {
                let key = if force_finite { "pressure" } else { "force" };
                problems.push(invalid(format!(
                    "{}load '{}': non-finite {key}",
                    at(key),
                    l.group
                )));
                continue;
            }
            let mut follower = None;
            if l.follower && l.pressure.is_none() {
                problems.push(invalid(format!(
                    "{}load '{}': `follower` applies to a pressure only",
                    at("follower"),
                    l.group
                )));
            }
            let forces = match (l.force, l.pressure) {
                (Some(f), None) => {
                    let faces: Vec<usize> = if g.dim == 2 {
                        g.elements.clone()
                    } else {
                        Vec::new()
                    };
                    let nodes: Vec<usize> = g
                        .nodes
                        .iter()
                        .copied()
                        .filter(|&a| active_nodes[a])
                        .collect();
                    if faces.is_empty() && nodes.is_empty() && nodes_known {
                        problems.push(invalid(format!(
                            "{}load '{}': the group has no node of any body",
                            at("group"),
                            l.group
                        )));
                    }
                    loads::total_force(&mesh, &faces, &nodes, f)
                }
                (None, Some(p)) => {
                    if g.dim != 2 {
                        problems.push(invalid(format!(
                            "{}load '{}': pressure needs a surface (2D) group, '{}' has dimension {}",
                            at("group"),
                            l.group,
                            g.name,
                            g.dim
                        )));
                        continue;
                    }
                    if g.elements.is_empty() {
                        problems.push(invalid(format!(
                            "{}load '{}': the surface group has no faces",
                            at("group"),
                            l.group
                        )));
                        continue;
                    }
                    if let Some((a, b)) = loads::repeated_face(&mesh, &g.elements) {
                        problems.push(invalid(format!(
                            "{}load '{}': elements {a} and {b} (Gmsh tags) are the same face: its pressure would count twice",
                            at("group"),
                            l.group
                        )));
                        continue;
                    }
                    match loads::outward_faces(&mesh, &g.elements, &body_refs, &node_elems) {
                        Ok(faces) => {
                            let f = loads::pressure_forces(&mesh, &faces, p);
                            if l.follower {
                                follower = Some((p, faces));
                            }
                            f
                        }
                        Err(tag) => {
                            if nodes_known {
                                problems.push(invalid(format!(
                                    "{}load '{}': face {tag} is not on the surface of a body",
                                    at("group"),
                                    l.group
                                )));
                            }
                            continue;
                        }
                    }
                }
                _ => unreachable!("exactly one of force and pressure, checked above"),
            };
            if forces.keys().any(|&a| !active_nodes[a]) && nodes_known {
                problems.push(invalid(format!(
                    "{}load '{}': applied to nodes of no body",
                    at("group"),
                    l.group
                )));
            }
            let mut forces: Vec<(usize, [f64; 3])> = forces.into_iter().collect();
            forces.sort_by_key(|(a, _)| *a);
            load_list.push(Load {
                name: l.group.clone(),
                forces,
                follower,
                active,
            });
        }
        if model.output.every == 0 {
            problems.push(invalid(format!(
                "{}output.every must be ≥ 1",
                src.at("output", 0, "every")
            )));
        }
        if model.output.folder.as_os_str().is_empty() {
            problems.push(invalid(format!(
                "{}output.folder is empty (give a folder; \".\" for the model's own)",
                src.at("output", 0, "folder")
            )));
        }

        // A material no body uses is most likely a body given the wrong one.
        let model_notes = model
            .materials
            .iter()
            .enumerate()
            .filter(|(_, m)| !model.bodies.iter().any(|b| b.material == m.name))
            .map(|(i, m)| {
                format!(
                    "{}material '{}' is used by no body",
                    src.at("material", i, "name"),
                    m.name
                )
            })
            .collect();
        let an = Self {
            model_notes,
            mesh,
            materials,
            body,
            rules,
            active_nodes,
            boundaries,
            loads: load_list,
            contacts,
            steps,
            output: model.output.clone(),
            output_dir: model.output_dir(),
        };
        (an, problems)
    }
}
