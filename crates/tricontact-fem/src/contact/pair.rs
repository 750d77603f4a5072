//! A `[[contact]]` table resolved against the mesh: slave nodes, master facets, method and
//! parameters, validated.
//!
//! # Facets and orientation
//! Master faces become triangular facets: a tri3 as is, a quad4 `(a, b, c, d)` as `(a, b, c)` and
//! `(a, c, d)`, a tri6 as its four corner/mid-node sub-triangles. The facet normal
//! `W = (x_j − x_i) × (x_k − x_i) / |…|` must point **out of the master body** (the gap
//! `P = (x_l − x_i)·W` is positive outside). A face bounding a body element is flipped if its node
//! order gives an inward normal. A face of a rigid tool (no volume element) keeps the node order of
//! the mesh, so its right-hand normal must point towards the slave. Either way the surface must be
//! consistently oriented: no directed edge may appear in two facets (two neighbours with opposite
//! normals); otherwise the model is rejected naming the faces.
//!
//! # Default penalty
//! `α = 10 E h`, with `E = √(E_m E_s)` the geometric mean of the Young's moduli of the body the
//! first master face bounds and of the body of the first slave node (the slave body's for a rigid
//! master) and `h` the mean edge length of the master facets: the penalty spring of a node is
//! about ten times the stiffness of an element of size `h` of a body of modulus `E`, so the
//! penetration under a contact pressure `p` is about `0.1 h p / E` per node. Between bodies of
//! different moduli the springs are then as many times stiffer than the soft side's elements as
//! they are softer than the stiff side's. The master's modulus alone (the default until
//! 2026-12-05) made them stiffer than a softer slave's elements by the whole ratio, which cost
//! Newton iterations and cutbacks; the smaller modulus alone costs penalty runs accuracy and an
//! unloading augmented run cutbacks (measured in the README, "The default penalty").
//!
//! With self-contact, `E` is the geometric mean of the smallest and largest moduli of the bodies
//! the group's faces bound (for two bodies, what a pair between them takes; taking the first
//! face's body for both sides made a group over a stiff base and a soft block ten times too stiff,
//! and its run failed where the two-pass pair converged).
//!
//! A given `penalty` below 10⁻² or above 10⁴ times that default ([`PENALTY_NOTE_RANGE`]) is
//! reported (not refused): such a factor most often comes from a modulus or a length in other
//! units than the mesh's. Far below, penetrations are that many times larger than the default's;
//! far above, the tangent is about that many times worse conditioned.
//!
//! # Self-contact
//! A pair whose slave and master are one surface group is the contact of that surface with
//! itself (a body folding onto itself, or several bodies' faces named as one group). One pass:
//! every node of the group is a slave against every facet of the group but its own, and only
//! against the facets that **face** its own side of the surface, `W` within 60° of `−n̂` with `n`
//! the node's angle-weighted outward normal at the current positions
//! ([`tricontact::contact::choose_facet_facing`]); the rest of its own side, which a node near a
//! bend can lie behind, is left out. Since both sides of a touching region are slaves, each is
//! held against the other as with `two_pass` (hence `two_pass` is refused as redundant, and so is
//! `method = "multiplier"`, as for `two_pass`); `adjust` is refused too (it would move nodes of
//! both sides onto each other). The group is a surface, as every master is. A group holding both
//! faces of a part thinner than the search radius puts each face's nodes behind the other face,
//! which faces them: initial penetrations deeper than a hundredth (`SELF_OVERLAP`) of the mean
//! edge are refused, with that reason. (A part that thins below the radius under load is not
//! caught.) `tricontact export` refuses self-contact.
//!
//! # Adjust
//! With `adjust = d`, every slave node whose initial gap is `−d ≤ P < 0` is moved along `W` onto the
//! master surface in the reference configuration (no strain). Deeper penetrations are kept and
//! reported (count, largest, node).

use std::collections::HashMap;

use tricontact::Vec3;
use tricontact::contact::{PROJECTION_TOLERANCE, choose_facet, choose_facet_facing};
use tricontact::search::{Bvh, Surface};

use crate::loads::{node_to_elements, outward_faces};
use crate::mesh::{Element, ElementKind, Group, Mesh};
use crate::model::{ContactDef, ContactMethod};
use crate::rigid::{find, parts};

/// One search pass: slave nodes against the facets of a surface.
#[derive(Clone, Debug)]
pub struct Pass {
    /// Slave nodes (mesh node indices).
    pub slaves: Vec<usize>,
    /// Tributary area of each slave node (`∫N_a dA` over its surface faces; 0 for a node group,
    /// and for the corners of tri6 faces).
    pub areas: Vec<f64>,
    /// For each slave node at a corner of tri6 faces, the mid-side nodes next to it, whose mean
    /// pressure is its pressure (empty otherwise).
    pub proxies: Vec<Vec<usize>>,
    /// Facets over mesh node indices, oriented outwards.
    pub surface: Surface,
    /// Gmsh tag of the face each facet comes from.
    pub face_tags: Vec<u64>,
    /// Search radius: the longest facet edge.
    pub radius: f64,
    /// Self-contact: for each slave node, the facets of `surface` around it, whose normals give
    /// its outward normal ([`Pass::facing`]); `None` for a pass between two groups.
    pub fans: Option<Vec<Vec<u32>>>,
}

impl Pass {
    /// With self-contact, the outward normal of slave `j`'s own surface at positions `x`: the
    /// facets' unit normals around the node weighted by their angles at it (of no particular
    /// length); `None` for a pass between two groups. Weighted by angle, the normal of a node on
    /// a box's edge bisects its two faces and that of a corner is the diagonal, whatever the
    /// facets' sizes (weighted by area, a node on the edge of a block standing on another, its
    /// side faces' facets twice the size of its bottom's, did not face the block below).
    #[must_use]
    pub fn facing(&self, j: usize, x: &[Vec3]) -> Option<Vec3> {
        let fan = self.fans.as_ref()?.get(j)?;
        Some(fan_normal(&self.surface, fan, *self.slaves.get(j)?, x))
    }

    /// The facet slave `j` is constrained against at positions `x` (`bvh` the surface's tree
    /// there) and the pair: [`choose_facet`], or with self-contact
    /// [`tricontact::contact::choose_facet_facing`] with the node's [`Pass::facing`] normal.
    #[must_use]
    pub fn choose(&self, bvh: &Bvh, x: &[Vec3], j: usize) -> Option<(u32, tricontact::NodeFacet)> {
        let fan = match &self.fans {
            Some(fans) => Some(fans.get(j)?.as_slice()),
            None => None,
        };
        choose_for(
            &self.surface,
            bvh,
            x,
            (*self.slaves.get(j)?, fan),
            self.radius,
        )
    }
}

/// The facet node `s` is constrained against on `surface` at positions `x` (`bvh` its tree
/// there), within `radius`, and the pair: [`choose_facet`], or with self-contact (`fan`, the
/// facets around the node) [`choose_facet_facing`] with the node's [`fan_normal`].
fn choose_for(
    surface: &Surface,
    bvh: &Bvh,
    x: &[Vec3],
    (s, fan): (usize, Option<&[u32]>),
    radius: f64,
) -> Option<(u32, tricontact::NodeFacet)> {
    let node = u32::try_from(s).ok()?;
    match fan {
        Some(fan) => {
            let n = fan_normal(surface, fan, s, x);
            choose_facet_facing(surface, bvh, x, node, radius, n)
        }
        None => choose_facet(surface, bvh, x, node, radius),
    }
}

impl ContactPair {
    /// `true` for the contact of a surface group with itself (slave = master).
    #[must_use]
    pub fn is_self_contact(&self) -> bool {
        self.slave_group == self.master_group
    }
}

/// The unit normals of the facets `fan` of `surface` around node `s`, at positions `x`, weighted
/// by their angles at `s` (see [`Pass::facing`]).
fn fan_normal(surface: &Surface, fan: &[u32], s: usize, x: &[Vec3]) -> Vec3 {
    fan.iter().fold(Vec3::zeros(), |n, &f| {
        let nodes = surface.facets()[f as usize];
        let [a, b, c] = surface.corners(f, x);
        // The corner at the node, then the two others.
        let (o, p, q) = match nodes.iter().position(|&v| v as usize == s) {
            Some(0) => (a, b, c),
            Some(1) => (b, c, a),
            _ => (c, a, b),
        };
        // A degenerate facet (a sliver, whose normal is round-off) adds nothing.
        match tricontact::Facet::new(a, b, c) {
            Ok(facet) => n + (p - o).angle(&(q - o)) * facet.normal(),
            Err(_) => n,
        }
    })
}

/// Self-contact: an initial penetration deeper than this share of the mean edge is refused (a
/// part thinner than the search radius with both faces in the group, whose nodes lie behind the
/// other face: contact would push its faces apart).
const SELF_OVERLAP: f64 = 0.01;

/// For each of `slaves`, the facets of `surface` around it.
fn fans(slaves: &[usize], surface: &Surface) -> Vec<Vec<u32>> {
    let place: HashMap<usize, usize> = slaves.iter().enumerate().map(|(j, &a)| (a, j)).collect();
    let mut fans = vec![Vec::new(); slaves.len()];
    for (f, nodes) in (0u32..).zip(surface.facets()) {
        for a in nodes {
            if let Some(&j) = place.get(&(*a as usize)) {
                fans[j].push(f);
            }
        }
    }
    fans
}

/// A resolved contact pair.
#[derive(Clone, Debug)]
pub struct ContactPair {
    /// `slave-master`, used in history columns.
    pub name: String,
    /// The slave group (surface or node set) as named in the model.
    pub slave_group: String,
    /// The master surface group as named in the model.
    pub master_group: String,
    /// Enforcement method.
    pub method: ContactMethod,
    /// Penalty factor `α` (force per length).
    pub penalty: f64,
    /// Largest gap `|P|` of a closed node allowed by the augmented Lagrangian (length).
    pub tolerance: f64,
    /// Mean master facet edge length.
    pub facet_size: f64,
    /// Keep facet and triad from the start of the increment.
    pub small_sliding: bool,
    /// Slave against master, then (two pass) master against slave.
    pub passes: Vec<Pass>,
    /// Messages on initial penetrations and adjusted nodes.
    pub report: Vec<String>,
}

/// Linear sub-triangles of a face (mesh node indices, mesh order).
fn triangles(el: &Element) -> Vec<[usize; 3]> {
    let n = &el.nodes;
    match el.kind {
        ElementKind::Tri3 => vec![[n[0], n[1], n[2]]],
        ElementKind::Quad4 => vec![[n[0], n[1], n[2]], [n[0], n[2], n[3]]],
        ElementKind::Tri6 => vec![
            [n[0], n[3], n[5]],
            [n[3], n[1], n[4]],
            [n[5], n[4], n[2]],
            [n[3], n[4], n[5]],
        ],
        _ => Vec::new(),
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> Vec3 {
    Vec3::new(a[0] - b[0], a[1] - b[1], a[2] - b[2])
}

/// Oriented facets of the faces of a 2D group: `(facets, face tags)`, or a message.
fn oriented_facets(
    mesh: &Mesh,
    group: &str,
    faces: &[usize],
    body: &[&Element],
    node_elems: &[Vec<usize>],
) -> Result<(Vec<[u32; 3]>, Vec<u64>), String> {
    let mut facets = Vec::new();
    let mut tags = Vec::new();
    for &f in faces {
        let el = &mesh.elements[f];
        let tris = triangles(el);
        if tris.is_empty() {
            return Err(format!(
                "contact surface '{group}': face {} is a {}, contact needs tri3, tri6 or quad4 faces",
                el.tag,
                el.kind.name()
            ));
        }
        let sign = match outward_faces(mesh, &[f], body, node_elems) {
            Ok(v) => v[0].1,
            Err(_) => 1.0, // rigid tool: mesh order
        };
        for t in tris {
            let t = if sign < 0.0 { [t[0], t[2], t[1]] } else { t };
            let mut idx = [0u32; 3];
            for (k, &a) in t.iter().enumerate() {
                idx[k] = u32::try_from(a).map_err(|_| "too many nodes for contact".to_string())?;
            }
            facets.push(idx);
            tags.push(el.tag);
        }
    }
    // Consistent orientation: every directed edge at most once.
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    for (i, t) in facets.iter().enumerate() {
        for k in 0..3 {
            let e = (t[k], t[(k + 1) % 3]);
            if let Some(&j) = edges.get(&e)
                && tags[j] != tags[i]
            {
                return Err(format!(
                    "contact surface '{group}' is inconsistently oriented: faces {} and {} have opposite normals across a shared edge (reorient the surface in the mesh)",
                    tags[j], tags[i]
                ));
            }
            edges.insert(e, i);
        }
    }
    Ok((facets, tags))
}

/// Areas of the nodes of `faces`, `∫N_a dA`: `A/3` for a tri3, `A/4` for a quad4 (exact for
/// parallelograms), and for a tri6 (area `A` of its four sub-triangles) `0` at the corners and
/// `A/3` at the mid-side nodes, the consistent values: a uniform pressure `p` loads a tri6 with
/// `0` and `pA/3`. (Areas from the sub-triangles, `A/12` and `A/4`, put the pressure at 0 on the
/// corners and `4p/3` on the mid-side nodes.) With the areas, for each tri6 corner the mid-side
/// nodes next to it: a corner carries no force of its own, and its pressure is their mean.
fn nodal_areas(mesh: &Mesh, faces: &[usize]) -> (HashMap<usize, f64>, HashMap<usize, Vec<usize>>) {
    let mut out = HashMap::new();
    let mut proxies: HashMap<usize, Vec<usize>> = HashMap::new();
    for &f in faces {
        let el = &mesh.elements[f];
        let tris = triangles(el);
        let tri_area = |t: &[usize; 3]| {
            let x = |k: usize| mesh.nodes[t[k]];
            0.5 * sub(x(1), x(0)).cross(&sub(x(2), x(0))).norm()
        };
        let area: f64 = tris.iter().map(tri_area).sum();
        let n = &el.nodes;
        match el.kind {
            ElementKind::Quad4 => {
                for &a in n {
                    *out.entry(a).or_insert(0.0) += area / 4.0;
                }
            }
            ElementKind::Tri6 => {
                for (corner, sides) in [(0, [3, 5]), (1, [3, 4]), (2, [4, 5])] {
                    out.entry(n[corner]).or_insert(0.0);
                    let near = proxies.entry(n[corner]).or_default();
                    near.extend(sides.map(|k| n[k]));
                }
                for &a in &n[3..6] {
                    *out.entry(a).or_insert(0.0) += area / 3.0;
                }
            }
            _ => {
                for &a in n {
                    *out.entry(a).or_insert(0.0) += area / 3.0;
                }
            }
        }
    }
    for near in proxies.values_mut() {
        near.sort_unstable();
        near.dedup();
    }
    (out, proxies)
}

fn edge_lengths(mesh: &Mesh, facets: &[[u32; 3]]) -> (f64, f64) {
    let (mut sum, mut max, mut n) = (0.0, 0.0f64, 0usize);
    for t in facets {
        for k in 0..3 {
            let l = sub(
                mesh.nodes[t[(k + 1) % 3] as usize],
                mesh.nodes[t[k] as usize],
            )
            .norm();
            sum += l;
            max = max.max(l);
            n += 1;
        }
    }
    (sum / n.max(1) as f64, max)
}

/// The search surface of `facets` (of the faces `face_tags`), or its error in the mesh's terms (a
/// facet by the Gmsh tag of its face, a node by its tag) after `place`, the model line of the key
/// that names the surface.
fn search_surface(
    name: &str,
    facets: Vec<[u32; 3]>,
    face_tags: &[u64],
    mesh: &Mesh,
    place: &str,
) -> Result<Surface, Vec<String>> {
    Surface::new(facets, mesh.nodes.len()).map_err(|e| {
        vec![format!(
            "{place}{}",
            surface_error(name, &e, face_tags, mesh)
        )]
    })
}

/// A surface error in the mesh's terms: a facet by the Gmsh tag of its face, a node by its tag.
fn surface_error(
    name: &str,
    e: &tricontact::search::SurfaceError,
    face_tags: &[u64],
    mesh: &Mesh,
) -> String {
    match e {
        tricontact::search::SurfaceError::RepeatedNode { facet, node } => format!(
            "contact '{name}': face {} repeats node {} (a degenerate face)",
            face_tags.get(*facet).copied().unwrap_or_default(),
            mesh.node_tags
                .get(*node as usize)
                .copied()
                .unwrap_or_default()
        ),
        other => format!("contact '{name}': {other}"),
    }
}

/// Area-weighted outward normal at each node of `facets` (oriented out of their body), at node
/// positions `x`.
fn outward_normals(x: &[Vec3], facets: &[[u32; 3]]) -> HashMap<usize, Vec3> {
    let mut normals: HashMap<usize, Vec3> = HashMap::new();
    for &[i, j, k] in facets {
        let [xi, xj, xk] = [i, j, k].map(|a| x[a as usize]);
        let w = (xj - xi).cross(&(xk - xi));
        for a in [i, j, k] {
            *normals.entry(a as usize).or_insert_with(Vec3::zeros) += w;
        }
    }
    normals
}

/// The mesh's node coordinates as kernel vectors.
pub(crate) fn positions(mesh: &Mesh) -> Vec<Vec3> {
    mesh.nodes
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect()
}

/// Inputs of the resolution besides the mesh.
pub struct Bodies<'a> {
    /// Volume elements of the bodies.
    pub elements: Vec<&'a Element>,
    /// Young's modulus of each body element.
    pub youngs: Vec<f64>,
}

/// Resolves one `[[contact]]` table; moves adjusted slave nodes in `mesh`; marks rigid master nodes
/// in `rigid` (nodes of no body that must be fully prescribed).
///
/// `at(key)` is the prefix of a message about one of the table's keys (its place in the model
/// file, `""` when unknown): see [`crate::source::SourceMap::at`].
///
/// # Errors
/// Every problem found, as messages.
pub fn resolve(
    def: &ContactDef,
    mesh: &mut Mesh,
    bodies: &Bodies<'_>,
    in_body: &[bool],
    rigid: &mut [bool],
    at: &dyn Fn(&str) -> String,
) -> Result<ContactPair, Vec<String>> {
    let name = format!("{}-{}", def.slave, def.master);
    let mut problems = check_parameters(def, &name, at);
    let self_contact = def.is_self_contact();
    let node_elems = node_to_elements(mesh.nodes.len(), &bodies.elements);
    let Some(sides) = sides(
        def,
        mesh,
        bodies,
        (&node_elems, in_body),
        (&name, at),
        &mut problems,
    ) else {
        return Err(problems);
    };
    mark_rigid(&sides.m_facets, in_body, rigid);
    // A rigid tool's nodes do not move against each other: they cannot poke between slave nodes.
    let rigid_master = is_rigid(&sides.m_facets, in_body);
    let e = if self_contact {
        self_contact_modulus(mesh, bodies, &node_elems, &sides.master.elements)
    } else {
        youngs_modulus(
            mesh,
            bodies,
            &node_elems,
            &sides.master.elements,
            &sides.slaves,
        )
    };
    let (h_mean, h_max) = edge_lengths(mesh, &sides.m_facets);
    let default_penalty = 10.0 * e * h_mean;
    let penalty = def.penalty.unwrap_or(default_penalty);
    problems.extend(default_penalty_problem(
        def,
        (default_penalty, e, h_mean),
        &name,
        at,
    ));
    if !problems.is_empty() {
        return Err(problems);
    }
    let surface = search_surface(&name, sides.m_facets, &sides.m_tags, mesh, &at("master"))?;
    let mut report = initial_penetrations(
        def,
        &name,
        mesh,
        &surface,
        &Slaves {
            nodes: &sides.slaves,
            facets: &sides.s_facets,
            in_body,
        },
        (h_mean, h_max),
        at,
    )?;
    report.extend(penalty_note(
        def.penalty,
        def.method,
        (default_penalty, e, h_mean),
        &name,
    ));
    if !def.two_pass && !rigid_master && !self_contact && !sides.s_facets.is_empty() {
        let (s_mean, _) = edge_lengths(mesh, &sides.s_facets);
        if s_mean > COARSE_SLAVE * h_mean {
            report.push(format!(
                "contact '{name}': the slave's facets are {:.1}× the master's (mean edge {s_mean:.3e} against {h_mean:.3e}): master nodes can pass between slave nodes unseen; make the finer surface the slave, or set two_pass = true (penalty, augmented)",
                s_mean / h_mean
            ));
        }
    }
    if !self_contact
        && one_part(
            mesh.nodes.len(),
            &bodies.elements,
            &sides.slaves,
            surface.facets(),
        )
    {
        report.push(format!(
            "contact '{name}': slave '{}' and master '{}' lie on one connected part of the mesh (self-contact); if the pair is meant between two bodies, check the group names",
            def.slave, def.master
        ));
    }
    let mut first = pass(
        mesh,
        Some(sides.slaves),
        &sides.slave_faces,
        surface,
        sides.m_tags,
        h_max,
    );
    if self_contact {
        first.fans = Some(fans(&first.slaves, &first.surface));
    }
    let mut passes = vec![first];
    if def.two_pass {
        // The master's nodes against the slave's facets.
        let (_, s_max) = edge_lengths(mesh, &sides.s_facets);
        let surface = search_surface(&name, sides.s_facets, &sides.s_tags, mesh, &at("slave"))?;
        passes.push(pass(
            mesh,
            None,
            &sides.master.elements,
            surface,
            sides.s_tags,
            s_max,
        ));
    }
    Ok(ContactPair {
        name,
        slave_group: def.slave.clone(),
        master_group: def.master.clone(),
        method: def.method,
        penalty,
        tolerance: def.tolerance * h_mean,
        facet_size: h_mean,
        small_sliding: def.small_sliding,
        passes,
        report,
    })
}

/// A one-pass pair with a deformable master whose slave surface's mean edge exceeds the
/// master's by more than this is noted: one pass holds only the slave's nodes, and a master much
/// finer than the slave passes between them (a coarse block on a master ten times finer stopped
/// at a fifth of its load with nodes "gone through"; two passes held it).
const COARSE_SLAVE: f64 = 2.0;

/// `true` when the slave nodes and the master facets' nodes all lie on one part of the mesh
/// (nodes linked through body elements): a self-contact pair, or two groups of one body named by
/// mistake. A master of no body element (a rigid tool) is a part of its own.
fn one_part(nodes: usize, elements: &[&Element], slaves: &[usize], facets: &[[u32; 3]]) -> bool {
    let (mut parent, in_element) = parts(nodes, elements.iter().map(|e| e.nodes.as_slice()));
    let mut all = slaves
        .iter()
        .copied()
        .chain(facets.iter().flatten().map(|&a| a as usize));
    let Some(first) = all.next() else {
        return false;
    };
    let part = find(&mut parent, first);
    in_element[first] && all.all(|a| in_element[a] && find(&mut parent, a) == part)
}

/// The two sides of a pair as the mesh gives them: the master group, its oriented facets and
/// their faces' tags; the slave's faces (none for a node set), facets and tags, and its nodes that
/// belong to a body.
struct Sides {
    master: Group,
    m_facets: Vec<[u32; 3]>,
    m_tags: Vec<u64>,
    slave_faces: Vec<usize>,
    s_facets: Vec<[u32; 3]>,
    s_tags: Vec<u64>,
    slaves: Vec<usize>,
}

/// The sides of the pair `def` (named `name`; `at` as for [`resolve`]), with every problem found
/// pushed onto `problems`; `None` when a group or a surface cannot be read (nothing more to
/// check).
fn sides(
    def: &ContactDef,
    mesh: &Mesh,
    bodies: &Bodies<'_>,
    (node_elems, in_body): (&[Vec<usize>], &[bool]),
    (name, at): (&str, &dyn Fn(&str) -> String),
    problems: &mut Vec<String>,
) -> Option<Sides> {
    let (Some(master), Some(slave)) = (
        master_group(def, mesh, name, at, problems),
        slave_group(def, mesh, name, at, problems),
    ) else {
        return None;
    };
    let facets = |group: &Group, elements: &[usize], key: &str| {
        oriented_facets(mesh, &group.name, elements, &bodies.elements, node_elems)
            .map_err(|m| format!("{}{m}", at(key)))
    };
    let (m_facets, m_tags) = match facets(&master, &master.elements, "master") {
        Ok(v) if v.0.is_empty() => {
            problems.push(format!(
                "{}contact '{name}': master surface has no faces",
                at("master")
            ));
            return None;
        }
        Ok(v) => v,
        Err(m) => {
            problems.push(m);
            return None;
        }
    };
    // A node set has no faces.
    let slave_faces = if slave.dim == 2 {
        slave.elements.clone()
    } else {
        Vec::new()
    };
    let (s_facets, s_tags) = match facets(&slave, &slave_faces, "slave") {
        Ok(v) => v,
        Err(m) => {
            problems.push(m);
            return None;
        }
    };
    if def.two_pass && s_facets.is_empty() {
        problems.push(format!(
            "{}contact '{name}': two_pass needs a surface (2D) slave group",
            at("slave")
        ));
    }
    let slaves: Vec<usize> = slave.nodes_in(in_body);
    if slaves.is_empty() {
        problems.push(format!(
            "{}contact '{name}': the slave group has no node of any body",
            at("slave")
        ));
    }
    Some(Sides {
        master,
        m_facets,
        m_tags,
        slave_faces,
        s_facets,
        s_tags,
        slaves,
    })
}

/// `true` when no node of the master `facets` belongs to a body: a rigid tool.
fn is_rigid(facets: &[[u32; 3]], in_body: &[bool]) -> bool {
    facets.iter().flatten().all(|&a| !in_body[a as usize])
}

/// Marks the nodes of the master `facets` that belong to no body as rigid (they must be fully
/// prescribed).
fn mark_rigid(facets: &[[u32; 3]], in_body: &[bool], rigid: &mut [bool]) {
    for &a in facets.iter().flatten() {
        if !in_body[a as usize] {
            rigid[a as usize] = true;
        }
    }
}

/// The problem with the `default` penalty `10 E h` (`e`, `h_mean`) when no `penalty` is given
/// and the default is not a positive finite number although `E` is (a tiny or huge modulus or
/// mesh).
fn default_penalty_problem(
    def: &ContactDef,
    (penalty, e, h_mean): (f64, f64, f64),
    name: &str,
    at: &dyn Fn(&str) -> String,
) -> Option<String> {
    // A valid material has a finite, positive modulus: any other `e` comes from a material that
    // is reported invalid with its own key (`nu = 0.5` gives `E = NaN` here), and the model is
    // rejected for it, so this pair does not report it again.
    let modulus_valid = e > 0.0 && e.is_finite();
    (def.penalty.is_none() && modulus_valid && !(penalty > 0.0 && penalty.is_finite())).then(|| {
        format!(
            "{}contact '{name}': the default penalty 10 E h is {penalty:e} (E = {e:e}, h = {h_mean:e}); give `penalty`",
            at("penalty")
        )
    })
}

/// The range of a given penalty, as a multiple of the default `10 E h`, outside which it is
/// reported (see the module documentation).
pub const PENALTY_NOTE_RANGE: (f64, f64) = (1e-2, 1e4);

/// What to report about a given `penalty` far from the `default`, `10 E h` (`e`, `h`), for a
/// pair enforced by `method`, if anything.
fn penalty_note(
    penalty: Option<f64>,
    method: ContactMethod,
    (default, e, h): (f64, f64, f64),
    name: &str,
) -> Option<String> {
    let a = penalty?;
    let ratio = a / default;
    let (low, high) = PENALTY_NOTE_RANGE;
    // A positive penalty so far below the default that the ratio underflows to zero.
    let underflow = ratio == 0.0 && a > 0.0 && default.is_finite();
    if !ratio.is_finite() || (ratio == 0.0 && !underflow) || (low..=high).contains(&ratio) {
        return None;
    }
    let (times, inverse) = if underflow {
        (
            format!("less than {:.1e}", f64::MIN_POSITIVE),
            format!("more than {:.1e}", f64::MAX),
        )
    } else {
        (format!("{ratio:.1e}"), format!("{:.1e}", 1.0 / ratio))
    };
    let effect = match (method, ratio < low) {
        (ContactMethod::Multiplier, _) => {
            "which scales the multipliers' equations as far from the rest of the tangent"
                .to_string()
        }
        (_, true) => format!(
            "which makes penetrations (about p/α under a pressure p) {inverse} times the default's"
        ),
        (_, false) => "which makes the tangent about as many times worse conditioned".to_string(),
    };
    Some(format!(
        "contact '{name}': penalty {a:e} is {times} times the default 10 E h = {default:.4e} \
         (E = {e:.4e}, h = {h:.4e}), {effect}; check its units"
    ))
}

/// Young's modulus for the default penalty (see the module documentation): the geometric mean of
/// the master's (that of the element bounded by the first of `master_faces` that bounds a body
/// element) and the slave's (that of the first slave node's first element); the one there is for
/// a rigid master; else 1.
fn youngs_modulus(
    mesh: &Mesh,
    bodies: &Bodies<'_>,
    node_elems: &[Vec<usize>],
    master_faces: &[usize],
    slaves: &[usize],
) -> f64 {
    let master_e = master_faces
        .iter()
        .find_map(|&f| face_modulus(mesh, bodies, node_elems, f));
    let slave_e = slaves
        .first()
        .and_then(|&a| node_elems[a].first().map(|&e| bodies.youngs[e]));
    match (master_e, slave_e) {
        (Some(m), Some(s)) => (m * s).sqrt(),
        (m, s) => m.or(s).unwrap_or(1.0),
    }
}

/// The Young's modulus of the body element face `f` bounds, if any.
fn face_modulus(
    mesh: &Mesh,
    bodies: &Bodies<'_>,
    node_elems: &[Vec<usize>],
    f: usize,
) -> Option<f64> {
    let c = &mesh.elements[f].nodes;
    node_elems[c[0]]
        .iter()
        .find(|&&e| c.iter().all(|a| bodies.elements[e].nodes.contains(a)))
        .map(|&e| bodies.youngs[e])
}

/// Young's modulus for the default penalty of a self-contact pair whose faces are `faces`: the
/// geometric mean of the smallest and largest moduli of the body elements they bound (the rule of
/// two groups, master's and slave's, when the group spans two bodies; a body's own modulus for
/// one); 1 if they bound none.
fn self_contact_modulus(
    mesh: &Mesh,
    bodies: &Bodies<'_>,
    node_elems: &[Vec<usize>],
    faces: &[usize],
) -> f64 {
    let (low, high) = faces
        .iter()
        .filter_map(|&f| face_modulus(mesh, bodies, node_elems, f))
        .fold((f64::INFINITY, 0.0f64), |(l, h), e| (l.min(e), h.max(e)));
    if low <= high {
        (low * high).sqrt()
    } else {
        1.0
    }
}

/// One search pass against `surface` (from faces of Gmsh tags `face_tags`, search radius
/// `radius`): the slave `nodes` (`None`: every node of `faces`, by index) with their tributary
/// areas and tri6 proxies over `faces`.
fn pass(
    mesh: &Mesh,
    nodes: Option<Vec<usize>>,
    faces: &[usize],
    surface: Surface,
    face_tags: Vec<u64>,
    radius: f64,
) -> Pass {
    let (areas_of, proxies_of) = nodal_areas(mesh, faces);
    let slaves = nodes.unwrap_or_else(|| {
        let mut all: Vec<usize> = areas_of.keys().copied().collect();
        all.sort_unstable();
        all
    });
    let areas = slaves
        .iter()
        .map(|a| areas_of.get(a).copied().unwrap_or(0.0))
        .collect();
    let proxies = slaves
        .iter()
        .map(|a| proxies_of.get(a).cloned().unwrap_or_default())
        .collect();
    Pass {
        slaves,
        areas,
        proxies,
        surface,
        face_tags,
        radius,
        fans: None,
    }
}

/// The checks of a `[[contact]]` table's own values, as messages.
fn check_parameters(def: &ContactDef, name: &str, at: &dyn Fn(&str) -> String) -> Vec<String> {
    let mut problems = Vec::new();
    if def.is_self_contact() {
        problems.extend(self_contact_problems(def, name, at));
    } else if def.two_pass && def.method == ContactMethod::Multiplier {
        problems.push(format!(
            "{}contact '{name}': two_pass with method = \"multiplier\" gives redundant constraints (each node pair constrained twice, a singular saddle-point system); use single pass or the penalty or augmented method",
            at("two_pass")
        ));
    }
    if let Some(a) = def.penalty
        && !(a > 0.0 && a.is_finite())
    {
        problems.push(format!(
            "{}contact '{name}': penalty must be > 0 (got {a})",
            at("penalty")
        ));
    }
    if !(def.tolerance > 0.0 && def.tolerance.is_finite()) {
        problems.push(format!(
            "{}contact '{name}': tolerance must be > 0 (got {})",
            at("tolerance"),
            def.tolerance
        ));
    }
    if let Some(d) = def.adjust
        && !(d >= 0.0 && d.is_finite())
    {
        problems.push(format!(
            "{}contact '{name}': adjust must be ≥ 0 (got {d})",
            at("adjust")
        ));
    }
    problems
}

/// What a self-contact pair (slave = master) refuses: two passes (one already holds both sides),
/// multipliers (both sides' constraints repeat each other, as with `two_pass`) and `adjust`
/// (it would move both sides' nodes onto each other).
fn self_contact_problems(def: &ContactDef, name: &str, at: &dyn Fn(&str) -> String) -> Vec<String> {
    let mut problems = Vec::new();
    if def.two_pass {
        problems.push(format!(
            "{}contact '{name}': self-contact (slave = master) needs no two_pass (remove it): every node of the group is already a slave against the group's facets that face it",
            at("two_pass")
        ));
    }
    if def.method == ContactMethod::Multiplier {
        problems.push(format!(
            "{}contact '{name}': self-contact (slave = master) with method = \"multiplier\" gives redundant constraints (both sides of a touching region are slaves, each node pair constrained twice, a singular saddle-point system); use the penalty or augmented method",
            at("method")
        ));
    }
    if def.adjust.is_some() {
        problems.push(format!(
            "{}contact '{name}': adjust is not available with self-contact (slave = master; remove it): it would move the nodes of both sides onto each other",
            at("adjust")
        ));
    }
    problems
}

/// The master surface group of `def`, or a problem.
fn master_group(
    def: &ContactDef,
    mesh: &Mesh,
    name: &str,
    at: &dyn Fn(&str) -> String,
    problems: &mut Vec<String>,
) -> Option<Group> {
    match mesh.lookup(&def.master, Some(2)) {
        Err(m) => {
            problems.push(format!("{}contact '{name}': master: {m}", at("master")));
            None
        }
        Ok(Some(g)) if g.dim == 2 => Some(g.clone()),
        Ok(Some(g)) => {
            problems.push(format!(
                "{}contact '{name}': master '{}' has dimension {}, a surface (2D) group is needed",
                at("master"),
                g.name,
                g.dim
            ));
            None
        }
        Ok(None) => {
            problems.push(format!(
                "{}contact '{name}': unknown master surface group '{}' (groups: {})",
                at("master"),
                def.master,
                mesh.group_list()
            ));
            None
        }
    }
}

/// The slave group of `def` (a surface or a node set), or a problem.
fn slave_group(
    def: &ContactDef,
    mesh: &Mesh,
    name: &str,
    at: &dyn Fn(&str) -> String,
    problems: &mut Vec<String>,
) -> Option<Group> {
    match mesh.lookup(&def.slave, Some(2)) {
        Ok(Some(g)) => Some(g.clone()),
        Ok(None) => {
            problems.push(format!(
                "{}contact '{name}': unknown slave group '{}' (groups: {})",
                at("slave"),
                def.slave,
                mesh.group_list()
            ));
            None
        }
        Err(m) => {
            problems.push(format!("{}contact '{name}': slave: {m}", at("slave")));
            None
        }
    }
}

/// The slave side of a pair, for [`initial_penetrations`]: its nodes, its facets (none for a node
/// set) and which nodes belong to a body.
struct Slaves<'a> {
    nodes: &'a [usize],
    facets: &'a [[u32; 3]],
    in_body: &'a [bool],
}

/// The slave nodes that start inside the master `surface` or near it: those within `adjust` of it
/// (inside, or apart from it with their foot on a facet and their slave surface facing it) are
/// moved onto it in `mesh`, the deeper ones are counted; returns what to report. Only nodes
/// within the search radius `h_max` of a facet are seen. A rigid master whose normals
/// point into the slave surface is refused. `(h_mean, h_max)`: the master's mean and longest
/// edge (the search radius).
fn initial_penetrations(
    def: &ContactDef,
    name: &str,
    mesh: &mut Mesh,
    surface: &Surface,
    slave: &Slaves<'_>,
    (h_mean, h_max): (f64, f64),
    at: &dyn Fn(&str) -> String,
) -> Result<Vec<String>, Vec<String>> {
    let (slaves, s_facets, in_body) = (slave.nodes, slave.facets, slave.in_body);
    let mut report = Vec::new();
    let x = positions(mesh);
    let bvh = Bvh::build(surface, &x, h_max).map_err(|e| vec![format!("{}{e}", at("master"))])?;
    let adjust = def.adjust.unwrap_or(0.0);
    let (mut moved, mut closed, mut deep, mut largest, mut worst) =
        (0usize, 0usize, 0usize, 0.0f64, 0usize);
    let mut moves = Vec::new();
    // A rigid master keeps the mesh's node order: count the slave nodes whose facet's normal
    // points the way the slave surface's outward normal does (into the slave body).
    let rigid_master = is_rigid(surface.facets(), in_body);
    let slave_normals = outward_normals(&x, s_facets);
    let (mut facing, mut away) = (0usize, 0usize);
    let fans = def.is_self_contact().then(|| fans(slaves, surface));
    for (k, &a) in slaves.iter().enumerate() {
        // Self-contact: only the facets facing the node's own side of the surface.
        let fan = fans.as_ref().map(|fans| fans[k].as_slice());
        let Some((_, pair)) = choose_for(surface, &bvh, &x, (a, fan), h_max) else {
            continue;
        };
        // Only where the two surfaces are roughly parallel (|cos| > 1/2): a slave face at
        // right angles to the master (a symmetry plane) says nothing.
        let cos = slave_normals
            .get(&a)
            .and_then(|n| n.try_normalize(0.0))
            .map(|n| pair.facet.normal().dot(&n));
        if let Some(cos) = cos {
            facing += usize::from(cos < -0.5);
            away += usize::from(cos > 0.5);
        }
        let p = pair.gap();
        // Within `adjust` on either side: onto the master; a node apart from it only where its
        // foot is on the facet (not past the master's edge) and its slave surface faces the
        // master (not a side face, nor a node set's inner nodes, which would crush elements).
        let near = p.abs() <= adjust
            && p != 0.0
            && (p < 0.0
                || (pair.projection.is_inside(PROJECTION_TOLERANCE)
                    && cos.is_some_and(|c| c < -0.5)));
        if near {
            moves.push((a, -p * pair.facet.normal()));
            moved += usize::from(p < 0.0);
            closed += usize::from(p > 0.0);
        } else if -p > 1e-12 * h_mean {
            deep += 1;
            if -p > largest {
                largest = -p;
                worst = a;
            }
        }
    }
    if rigid_master && away > facing {
        return Err(vec![format!(
            "{}contact '{name}': the normals of the rigid master '{}' point into the slave surface at {away} of the {} slave nodes facing it; a face of no body element keeps the mesh's node order, and its normal (x_j − x_i) × (x_k − x_i) must point towards the slave: reverse the order of its nodes",
            at("master"),
            def.master,
            away + facing
        )]);
    }
    for (a, d) in moves {
        for i in 0..3 {
            mesh.nodes[a][i] += d[i];
        }
    }
    if moved + closed > 0 {
        report.push(format!(
            "contact '{name}': {} slave nodes moved onto the master surface ({moved} penetrating it, {closed} apart from it; adjust = {adjust:e})",
            moved + closed
        ));
    }
    if def.is_self_contact() && largest > SELF_OVERLAP * h_mean {
        return Err(vec![format!(
            "{}contact '{name}': {deep} nodes of the group start behind facets of the group that face them, largest {largest:.3e} (more than {SELF_OVERLAP} of the mean edge {h_mean:.3e}) at node {} ({:.4e}, {:.4e}, {:.4e}): the group holds both faces of a part thinner than the search radius {h_max:.3e} (its longest edge), or surfaces that overlap at the start; in self-contact name only the faces that are to meet",
            at("master"),
            mesh.node_tags[worst],
            mesh.nodes[worst][0],
            mesh.nodes[worst][1],
            mesh.nodes[worst][2]
        )]);
    }
    if deep > 0 {
        let beyond = match def.adjust {
            Some(a) => format!("deeper than adjust = {a:e}"),
            None => "(no adjust given)".to_string(),
        };
        report.push(format!(
            "contact '{name}': {deep} slave nodes initially penetrate the master {beyond}, largest {largest:.3e} at node {} ({:.4e}, {:.4e}, {:.4e})",
            mesh.node_tags[worst], mesh.nodes[worst][0], mesh.nodes[worst][1], mesh.nodes[worst][2]
        ));
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A given penalty is reported only outside `PENALTY_NOTE_RANGE` times `10 E h`, with what it
    /// does for the pair's method; never the default.
    #[test]
    fn a_penalty_far_from_the_default_is_reported() {
        let (e, h) = (2.0e5, 0.5);
        let default = 10.0 * e * h;
        let note = |a: Option<f64>, method| penalty_note(a, method, (default, e, h), "p");
        let (low, high) = PENALTY_NOTE_RANGE;
        for method in [ContactMethod::Penalty, ContactMethod::Augmented] {
            assert_eq!(note(None, method), None);
            for a in [low * default, default, high * default] {
                assert_eq!(note(Some(a), method), None, "{a}");
            }
            let soft = note(Some(0.5 * low * default), method).expect("soft");
            assert!(
                soft.starts_with(
                    "contact 'p': penalty 5e3 is 5.0e-3 times the default 10 E h = 1.0000e6"
                ) && soft.contains("penetrations (about p/α under a pressure p) 2.0e2 times"),
                "{soft}"
            );
            let stiff = note(Some(2.0 * high * default), method).expect("stiff");
            assert!(
                stiff.contains("is 2.0e4 times") && stiff.contains("worse conditioned"),
                "{stiff}"
            );
        }
        // A positive penalty whose ratio to the default underflows to zero is noted too.
        let tiny = note(Some(1e-320), ContactMethod::Penalty).expect("underflow");
        assert!(
            tiny.contains("is less than 2.2e-308 times the default")
                && tiny.contains("more than 1.8e308 times the default's"),
            "{tiny}"
        );
        let multiplier = note(Some(1e-3 * low * default), ContactMethod::Multiplier).expect("far");
        assert!(
            multiplier.contains("multipliers' equations"),
            "{multiplier}"
        );
    }
}
