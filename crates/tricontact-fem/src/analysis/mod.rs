//! Resolution of a [`Model`] against a [`Mesh`]: bodies, materials, supports,
//! loads and steps as index data ready for assembly, plus validation.
//!
//! Validation collects every problem (unknown groups, materials, conflicting
//! supports, loads on nodes of no body, inverted or zero-volume elements)
//! instead of stopping at the first, so `tricontact check` can list them.
//!
//! [`Analysis::build`] takes the model's sections in order, one file each: the steps
//! (`steps.rs`), the materials and bodies with the quality of their elements (`bodies.rs`), the
//! contact pairs (`contacts.rs`), the boundaries (`boundaries.rs`) and the loads (`loading.rs`).

mod bodies;
mod boundaries;
mod contacts;
mod loading;
mod steps;

use std::path::PathBuf;

use crate::contact::ContactPair;
use crate::error::{FemError, Result};
use crate::material::Material;
use crate::mesh::{ElementKind, Mesh};
use crate::model::{Extrapolation, LineSearchMode, Model, OutputDef};
use crate::shape::QPoint;

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
    /// When Newton's corrections are line-searched ([`crate::newton`], [`crate::driver`]).
    pub line_search: LineSearchMode,
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

/// A body part of the first step that only contact across a gap holds (see
/// [`Analysis::open_gap_support`]).
#[derive(Debug, Clone, PartialEq)]
pub struct OpenGap {
    /// The first step's name.
    pub step: String,
    /// The part and its free rigid-body modes, as [`crate::rigid::check_supports`] names them.
    pub free: String,
    /// The pair of the slave node nearest the master among the part's own that are apart from
    /// it (its slave nodes, or the slave nodes facing its facets).
    pub pair: String,
    /// That node's Gmsh tag.
    pub node: u64,
    /// Its gap at the start.
    pub gap: f64,
}

impl OpenGap {
    /// The note `check` and `run` print.
    #[must_use]
    pub fn note(&self) -> String {
        format!(
            "step '{}': with its boundaries and the slave nodes that touch the master at the \
             start, {} until contact closes (the nearest slave node not yet touching, node {} \
             of contact '{}', is {:.3e} from the master); a force or a pressure on it makes the \
             first increment fail (an inverted element, a singular tangent or no convergence): \
             prescribe its motion by a displacement boundary until it touches (a first step), \
             start it touching, or give the pair `adjust = {:.3e}` or more (the nodes of a \
             slave surface facing the master within it are moved onto it)",
            self.step,
            self.free,
            self.node,
            self.pair,
            self.gap,
            self.gap * (1.0 + 1e-3)
        )
    }

    /// What a first step that fails before its first increment adds to its message.
    #[must_use]
    pub fn hint(&self) -> String {
        format!(
            "; {} while contact '{}' is open (a gap of {:.3e} at node {}): prescribe its motion \
             until it touches, start it touching, or give the pair `adjust`",
            self.free, self.pair, self.gap, self.node
        )
    }
}

/// A slave node within reach of a master facet at the reference positions: its contact pair
/// (index), the nodes of the facet it faces, that facet's normal and the gap `P`.
struct Reach {
    pair: usize,
    slave: usize,
    facet: [u32; 3],
    normal: [f64; 3],
    gap: f64,
}

/// `(node, normal)` for each slave node of `reach` that `keep` keeps, and for the nodes of the
/// facet it faces: the directions frictionless contact holds them along.
fn held_along(reach: &[Reach], keep: impl Fn(&Reach) -> bool) -> Vec<(usize, [f64; 3])> {
    let mut held = Vec::new();
    for r in reach.iter().filter(|r| keep(r)) {
        held.push((r.slave, r.normal));
        held.extend(r.facet.iter().map(|&a| (a as usize, r.normal)));
    }
    held
}

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
    /// a master facet). Without contact pairs such a body is an error, not a note. In the first
    /// step, a body part that those normals hold only where the slave nodes are still apart from
    /// the master is noted too ([`Analysis::open_gap_support`]).
    #[must_use]
    pub fn notes(&self) -> Vec<String> {
        let mut notes = self.model_notes.clone();
        notes.extend(self.line_search_notes());
        if self.contacts.is_empty() {
            return notes;
        }
        let reach = self.initial_reach();
        let held = held_along(&reach, |_| true);
        for (s, step) in self.steps.iter().enumerate() {
            let (mask, _) = crate::driver::step_constraints(self, s);
            if let Some(m) = crate::rigid::first_free_part(self, &mask, &held) {
                notes.push(format!(
                    "step '{}': with its boundaries and the initial contact normals, {m}; \
                     frictionless contact leaves such motion undetermined",
                    step.name,
                ));
            } else if s == 0 {
                notes.extend(self.open_gaps(&reach, &mask).iter().map(OpenGap::note));
            }
        }
        notes
    }

    /// The first step's body parts that only contact across a gap holds: its boundaries and the
    /// normals of the slave nodes within reach of a master facet at the start hold them, but
    /// not with the normals of the slave nodes that touch the master (a gap of round-off,
    /// `10⁻¹²` of the pair's facet size, or less) alone. Nothing holds such a part until the gap
    /// closes, and the first increment's tangent is singular for it: Newton then fails (an
    /// inverted element, a singular tangent, no convergence), which names neither the part nor
    /// the gap. Each comes with the nearest slave node not yet touching among those of its
    /// pairs (the part's own slave nodes, or the slave nodes facing its facets). A note of
    /// `check` and `run` ([`OpenGap::note`]), and a hint in the message of a first step that
    /// fails before its first increment ([`OpenGap::hint`]). The normals count as held in
    /// space: a part touching another that is itself only held across a gap is not named.
    #[must_use]
    pub fn open_gap_support(&self) -> Vec<OpenGap> {
        if self.contacts.is_empty() || self.steps.is_empty() {
            return Vec::new();
        }
        let reach = self.initial_reach();
        let (mask, _) = crate::driver::step_constraints(self, 0);
        if crate::rigid::first_free_part(self, &mask, &held_along(&reach, |_| true)).is_some() {
            return Vec::new();
        }
        self.open_gaps(&reach, &mask)
    }

    /// [`Analysis::open_gap_support`] from the slave nodes within reach at the start and the
    /// first step's prescribed DOFs `mask`, which with all of them hold every part.
    fn open_gaps(&self, reach: &[Reach], mask: &[bool]) -> Vec<OpenGap> {
        let touching = |r: &Reach| r.gap <= 1e-12 * self.contacts[r.pair].facet_size;
        let free = crate::rigid::free_parts(self, mask, &held_along(reach, touching));
        free.into_iter()
            .filter_map(|(nodes, message)| {
                let part: std::collections::HashSet<usize> = nodes.into_iter().collect();
                let nearest = reach
                    .iter()
                    .filter(|r| !touching(r))
                    .filter(|r| {
                        part.contains(&r.slave)
                            || r.facet.iter().any(|&a| part.contains(&(a as usize)))
                    })
                    .min_by(|a, b| a.gap.total_cmp(&b.gap))?;
                Some(OpenGap {
                    step: self.steps[0].name.clone(),
                    free: message,
                    pair: self.contacts[nearest.pair].name.clone(),
                    node: self.mesh.node_tags[nearest.slave],
                    gap: nearest.gap,
                })
            })
            .collect()
    }

    /// Each slave node within reach of a master facet at the reference positions, with the
    /// facet it faces (see [`tricontact::contact::choose_facet`]).
    fn initial_reach(&self) -> Vec<Reach> {
        let x: Vec<tricontact::Vec3> = self
            .mesh
            .nodes
            .iter()
            .map(|p| tricontact::Vec3::new(p[0], p[1], p[2]))
            .collect();
        let mut reach = Vec::new();
        for (c, pair) in self.contacts.iter().enumerate() {
            for pass in &pair.passes {
                let Ok(bvh) = tricontact::search::Bvh::build(&pass.surface, &x, pass.radius) else {
                    continue;
                };
                for (j, &s) in pass.slaves.iter().enumerate() {
                    let Some((f, nf)) = pass.choose(&bvh, &x, j) else {
                        continue;
                    };
                    let w = nf.facet.normal();
                    reach.push(Reach {
                        pair: c,
                        slave: s,
                        facet: pass.surface.facets()[f as usize],
                        normal: [w[0], w[1], w[2]],
                        gap: nf.gap(),
                    });
                }
            }
        }
        reach
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
            .filter(|(_, st)| st.line_search == LineSearchMode::On)
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
    ///
    /// When a body cannot be resolved, the checks that depend on which nodes belong to a body
    /// (supports, loads, contact) are skipped: they would only repeat the problem.
    #[must_use]
    pub fn build(model: &Model, mut mesh: Mesh) -> (Self, Vec<FemError>) {
        let mut problems: Vec<FemError> = Vec::new();
        let p = &mut problems;
        let steps = steps::resolve(model, p);
        let (materials, by_name) = bodies::materials(model, p);
        let (body, bodies_ok) = bodies::resolve(model, &mesh, &by_name, p);
        let mut active_nodes = bodies::nodes(&mesh, &body);
        let rules = bodies::rules(&mesh, &body);
        bodies::check_quality(&model.mesh_path(), &mesh, &body, &rules, p);
        // Contact pairs may move adjusted slave nodes; rigid master nodes become active.
        let before_contacts = p.len();
        let (contacts, rigid) = contacts::resolve(
            model,
            &mut mesh,
            &body,
            &materials,
            &active_nodes,
            bodies_ok,
            p,
        );
        for (a, &r) in rigid.iter().enumerate() {
            if r {
                active_nodes[a] = true;
            }
        }
        // Nodes belong to a body, or to a rigid master, only once both resolved.
        let nodes_known = bodies_ok && p.len() == before_contacts;
        let (boundaries, boundary_defs) =
            boundaries::resolve(model, &mesh, &steps, &active_nodes, nodes_known, p);
        boundaries::check_conflicts(model, &mesh, &steps, &boundaries, &boundary_defs, p);
        boundaries::check_rigid_nodes(model, &mesh, &steps, &boundaries, &rigid, p);
        let loads = loading::resolve(model, &mesh, &steps, &body, &active_nodes, nodes_known, p);
        check_output(model, p);
        let an = Self {
            model_notes: unused_materials(model),
            mesh,
            materials,
            body,
            rules,
            active_nodes,
            boundaries,
            loads,
            contacts,
            steps,
            output: model.output.clone(),
            output_dir: model.output_dir(),
        };
        (an, problems)
    }
}

/// A problem described by one message.
fn invalid(s: String) -> FemError {
    FemError::Invalid(vec![s])
}

/// A group of `kind` named `name` that the mesh does not have, at the model's place `at`.
fn unknown(at: String, kind: &'static str, name: &str, mesh: &Mesh) -> FemError {
    FemError::UnknownGroup {
        at,
        kind,
        name: name.to_string(),
        available: mesh.group_list(),
    }
}

/// The `[output]` settings that cannot be used.
fn check_output(model: &Model, problems: &mut Vec<FemError>) {
    let src = &model.source;
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
}

/// A note for each material no body uses: most likely a body given the wrong one.
fn unused_materials(model: &Model) -> Vec<String> {
    let src = &model.source;
    model
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
        .collect()
}
