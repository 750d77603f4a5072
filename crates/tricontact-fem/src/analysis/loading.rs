//! Loads: each `[[load]]` resolved to nodal forces at amplitude 1 (a force spread over a group's
//! nodes or faces, a pressure over the outward faces of a surface group, see [`crate::loads`]),
//! with the steps it acts in.

use super::{BodyElement, Load, Step, invalid, steps, unknown};
use crate::error::FemError;
use crate::loads;
use crate::mesh::Mesh;
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
    let src = &model.source;
    let body_refs: Vec<&crate::mesh::Element> =
        body.iter().map(|b| &mesh.elements[b.element]).collect();
    let node_elems = loads::node_to_elements(mesh.nodes.len(), &body_refs);
    let mut load_list = Vec::new();
    for (li, l) in model.loads.iter().enumerate() {
        let at = |key: &str| src.at("load", li, key);
        let active = steps::mask(
            steps,
            l.steps.as_deref(),
            &format!("{}load '{}'", at("steps"), l.group),
            problems,
        );
        let g = match mesh.lookup(&l.group, l.pressure.is_some().then_some(2)) {
            Ok(Some(g)) => g,
            Ok(None) => {
                let kind = if l.pressure.is_some() {
                    "surface"
                } else {
                    "node"
                };
                problems.push(unknown(at("group"), kind, &l.group, mesh));
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
                loads::total_force(mesh, &faces, &nodes, f)
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
                if let Some((a, b)) = loads::repeated_face(mesh, &g.elements) {
                    problems.push(invalid(format!(
                        "{}load '{}': elements {a} and {b} (Gmsh tags) are the same face: its pressure would count twice",
                        at("group"),
                        l.group
                    )));
                    continue;
                }
                match loads::outward_faces(mesh, &g.elements, &body_refs, &node_elems) {
                    Ok(faces) => {
                        let f = loads::pressure_forces(mesh, &faces, p);
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
    load_list
}
