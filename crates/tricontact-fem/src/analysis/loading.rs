//! Loads: each `[[load]]` resolved to nodal forces at amplitude 1 (a force spread over a group's
//! nodes or faces, a pressure over the outward faces of a surface group, see [`crate::loads`]),
//! with the steps it acts in.

use std::collections::HashMap;

use super::{BodyElement, Load, Step, invalid, steps, unknown};
use crate::error::FemError;
use crate::loads;
use crate::mesh::{Element, Group, Mesh};
use crate::model::Model;

/// The model's loads (one whose group, values or faces cannot be used is left out; its problem
/// is added to `problems`). `active_nodes` marks the nodes of bodies and rigid masters; only when
/// `nodes_known` (both resolved) are loads on other nodes, or on faces of no body, a problem.
pub(super) fn resolve(
    model: &Model,
    mesh: &Mesh,
    steps: &[Step],
    body: &[BodyElement],
    active_nodes: &[bool],
    nodes_known: bool,
    problems: &mut Vec<FemError>,
) -> Vec<Load> {
    let body_refs: Vec<&Element> = body.iter().map(|b| &mesh.elements[b.element]).collect();
    let bodies = Bodies {
        mesh,
        node_elems: loads::node_to_elements(mesh.nodes.len(), &body_refs),
        elements: body_refs,
        active_nodes,
        nodes_known,
    };
    (0..model.loads.len())
        .filter_map(|li| resolve_one(model, li, steps, &bodies, problems))
        .collect()
}

/// What a load is resolved against: the mesh, the body elements (and those around each node),
/// the nodes of bodies and rigid masters, and whether those are known (see [`resolve`]).
struct Bodies<'a> {
    mesh: &'a Mesh,
    elements: Vec<&'a Element>,
    node_elems: Vec<Vec<usize>>,
    active_nodes: &'a [bool],
    nodes_known: bool,
}

/// `[[load]]` number `li` of `model`, or `None` with its problems added to `problems`.
fn resolve_one(
    model: &Model,
    li: usize,
    steps: &[Step],
    bodies: &Bodies<'_>,
    problems: &mut Vec<FemError>,
) -> Option<Load> {
    let l = &model.loads[li];
    let at = |key: &str| model.source.at("load", li, key);
    // A problem of this load with the model key `key`.
    let problem =
        |key: &str, what: String| invalid(format!("{}load '{}': {what}", at(key), l.group));
    let active = steps::mask(
        steps,
        l.steps.as_deref(),
        &format!("{}load '{}'", at("steps"), l.group),
        problems,
    );
    let mesh = bodies.mesh;
    let g = match mesh.lookup(&l.group, l.pressure.is_some().then_some(2)) {
        Ok(Some(g)) => g,
        Ok(None) => {
            let kind = if l.pressure.is_some() {
                "surface"
            } else {
                "node"
            };
            problems.push(unknown(at("group"), kind, &l.group, mesh));
            return None;
        }
        Err(m) => {
            problems.push(invalid(format!("{}load: {m}", at("group"))));
            return None;
        }
    };
    let force_finite = l.force.is_none_or(|f| f.iter().all(|c| c.is_finite()));
    let unusable = if l.force.is_some() == l.pressure.is_some() {
        Some(("", "give exactly one of `force` or `pressure`".to_string()))
    } else if !force_finite || !l.pressure.is_none_or(f64::is_finite) {
        let key = if force_finite { "pressure" } else { "force" };
        Some((key, format!("non-finite {key}")))
    } else {
        None
    };
    if let Some((key, what)) = unusable {
        problems.push(problem(key, what));
        return None;
    }
    if l.follower && l.pressure.is_none() {
        problems.push(problem(
            "follower",
            "`follower` applies to a pressure only".into(),
        ));
    }
    let (forces, follower) = match (l.force, l.pressure) {
        (Some(f), _) => {
            let forces = group_force(g, f, bodies);
            if forces.is_none() {
                problems.push(problem("group", "the group has no node of any body".into()));
            }
            (forces?, None)
        }
        (None, p) => {
            let p = p?;
            let faces = pressure_faces(g, bodies)
                .map_err(|what| problems.extend(what.map(|w| problem("group", w))))
                .ok()?;
            let forces = loads::pressure_forces(mesh, &faces, p);
            (forces, l.follower.then_some((p, faces)))
        }
    };
    if forces.keys().any(|&a| !bodies.active_nodes[a]) && bodies.nodes_known {
        problems.push(problem("group", "applied to nodes of no body".into()));
    }
    let mut forces: Vec<(usize, [f64; 3])> = forces.into_iter().collect();
    forces.sort_by_key(|(a, _)| *a);
    Some(Load {
        name: l.group.clone(),
        forces,
        follower,
        active,
    })
}

/// The nodal forces of the total force `f` spread over group `g` (its faces if it is a surface
/// group, else its nodes of bodies); `None` when it has neither and the nodes are known.
fn group_force(g: &Group, f: [f64; 3], bodies: &Bodies<'_>) -> Option<HashMap<usize, [f64; 3]>> {
    let faces: Vec<usize> = if g.dim == 2 {
        g.elements.clone()
    } else {
        Vec::new()
    };
    let nodes: Vec<usize> = g.nodes_in(bodies.active_nodes);
    if faces.is_empty() && nodes.is_empty() && bodies.nodes_known {
        return None;
    }
    Some(loads::total_force(bodies.mesh, &faces, &nodes, f))
}

/// The faces of the surface group `g` a pressure acts on, each with its outward sign; `Err` with
/// the problem (`None` where it is not one yet: a face on no known body before the bodies are
/// resolved).
fn pressure_faces(g: &Group, bodies: &Bodies<'_>) -> Result<Vec<(usize, f64)>, Option<String>> {
    let mesh = bodies.mesh;
    if g.dim != 2 {
        return Err(Some(format!(
            "pressure needs a surface (2D) group, '{}' has dimension {}",
            g.name, g.dim
        )));
    }
    if g.elements.is_empty() {
        return Err(Some("the surface group has no faces".into()));
    }
    if let Some((a, b)) = loads::repeated_face(mesh, &g.elements) {
        return Err(Some(format!(
            "elements {a} and {b} (Gmsh tags) are the same face: its pressure would count twice"
        )));
    }
    loads::outward_faces(mesh, &g.elements, &bodies.elements, &bodies.node_elems).map_err(|tag| {
        bodies
            .nodes_known
            .then(|| format!("face {tag} is not on the surface of a body"))
    })
}
