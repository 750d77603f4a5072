//! Supports and prescribed displacements: each `[[boundary]]` resolved to the nodes of bodies
//! in its group, with its components and the steps it acts in; then, step by step, two boundaries
//! prescribing different values on one node component, and rigid master nodes left free.

use std::collections::{BTreeMap, HashMap};

use super::{Boundary, Step, invalid, steps, unknown};
use crate::error::FemError;
use crate::mesh::Mesh;
use crate::model::Model;

/// The model's boundaries, with the index in the model of each (a boundary whose group is not
/// found is left out). `active_nodes` marks the nodes of bodies and rigid masters; only when
/// `nodes_known` (both resolved) is a group without such nodes a problem.
pub(super) fn resolve(
    model: &Model,
    mesh: &Mesh,
    steps: &[Step],
    active_nodes: &[bool],
    nodes_known: bool,
    problems: &mut Vec<FemError>,
) -> (Vec<Boundary>, Vec<usize>) {
    let src = &model.source;
    let mut boundaries = Vec::new();
    // The index in the model of each resolved boundary (one with an unknown group is left
    // out of `boundaries`).
    let mut boundary_defs = Vec::new();
    for (bi, b) in model.boundaries.iter().enumerate() {
        let at = |key: &str| src.at("boundary", bi, key);
        let active = steps::mask(
            steps,
            b.steps.as_deref(),
            &format!("{}boundary '{}'", at("steps"), b.group),
            problems,
        );
        let g = match mesh.lookup(&b.group, None) {
            Ok(Some(g)) => g,
            Ok(None) => {
                problems.push(unknown(at("group"), "node", &b.group, mesh));
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
        let nodes: Vec<usize> = g.nodes_in(active_nodes);
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
    (boundaries, boundary_defs)
}

/// Conflicting prescribed values on a shared node component within a step: one message per step
/// and pair of boundaries (numbered as in the model, `boundary_defs` giving each one's index
/// there), with the count and the first node.
pub(super) fn check_conflicts(
    model: &Model,
    mesh: &Mesh,
    steps: &[Step],
    boundaries: &[Boundary],
    boundary_defs: &[usize],
    problems: &mut Vec<FemError>,
) {
    let src = &model.source;
    for s in 0..steps.len() {
        let mut seen: HashMap<(usize, usize), (f64, usize)> = HashMap::new();
        let mut clashes: BTreeMap<(usize, usize), (usize, u64)> = BTreeMap::new();
        for (bi, b) in boundaries.iter().enumerate().filter(|(_, b)| b.active[s]) {
            for &a in &b.nodes {
                for (i, v) in b.values.iter().enumerate() {
                    let Some(v) = *v else { continue };
                    match seen.get(&(a, i)) {
                        Some(&(w, other)) if w != v => {
                            let c = clashes.entry((other, bi)).or_insert((0, mesh.node_tags[a]));
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
}

/// Rigid master nodes (`rigid`; no volume element) must be fully prescribed in every step: each
/// of x, y and z by some boundary (a bit per component, so that two boundaries holding the same
/// component do not count as two). One message per step, at the first such node left free.
pub(super) fn check_rigid_nodes(
    model: &Model,
    mesh: &Mesh,
    steps: &[Step],
    boundaries: &[Boundary],
    rigid: &[bool],
    problems: &mut Vec<FemError>,
) {
    let src = &model.source;
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
            let pair = model.contacts.iter().position(
                |c| matches!(mesh.lookup(&c.master, Some(2)), Ok(Some(g)) if g.nodes.contains(&a)),
            );
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
}
