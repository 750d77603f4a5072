//! Contact pairs: each `[[contact]]` resolved against the bodies (see
//! [`crate::contact::pair::resolve`]), which may move slave nodes the model asks to adjust onto
//! their master and marks the nodes of rigid master surfaces.

use super::{BodyElement, invalid};
use crate::contact::ContactPair;
use crate::error::FemError;
use crate::material::Material;
use crate::mesh::Mesh;
use crate::model::Model;

/// The model's contact pairs and, per node, whether it belongs to a rigid master surface. Slave
/// nodes adjusted onto their master move in `mesh`; `in_body` marks the nodes of `body`. When
/// not every body resolved (`bodies_ok` false), only the pairs' own definitions are checked.
pub(super) fn resolve(
    model: &Model,
    mesh: &mut Mesh,
    body: &[BodyElement],
    materials: &[Material],
    in_body: &[bool],
    bodies_ok: bool,
    problems: &mut Vec<FemError>,
) -> (Vec<ContactPair>, Vec<bool>) {
    let src = &model.source;
    let mut rigid = vec![false; mesh.nodes.len()];
    let mut contacts = Vec::new();
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
        match crate::contact::pair::resolve(c, &mut moved, &bodies, in_body, &mut rigid, &at) {
            Ok(p) => contacts.push(p),
            Err(list) => problems.extend(list.into_iter().map(&invalid)),
        }
    }
    drop(bodies);
    mesh.nodes = moved.nodes;
    (contacts, rigid)
}
