//! Materials and bodies: each material's constants checked, each body's volume group resolved to
//! its elements (an element belongs to one body), and the quality of those elements.
//!
//! An element is *zero-volume* when `min |det J| ≤ 1e-8 h³` at its integration points (`h` its
//! largest corner distance) and *inverted* when some `det J < 0`; the first ten are reported by
//! element, the rest counted.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::{BodyElement, MAX_MODULUS, invalid, unknown};
use crate::element::jacobian_dets;
use crate::error::FemError;
use crate::material::{Law, Material};
use crate::mesh::{ElementKind, Mesh};
use crate::model::{MaterialKind, Model};
use crate::shape::{self, QPoint};

/// The model's materials, in its order, and the index of each by name.
pub(super) fn materials(
    model: &Model,
    problems: &mut Vec<FemError>,
) -> (Vec<Material>, HashMap<String, usize>) {
    let src = &model.source;
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
    (materials, mat_index)
}

/// The elements of the model's bodies with their materials (`mat_index`: a material's index by
/// name), and whether every body resolved.
pub(super) fn resolve(
    model: &Model,
    mesh: &Mesh,
    mat_index: &HashMap<String, usize>,
    problems: &mut Vec<FemError>,
) -> (Vec<BodyElement>, bool) {
    let src = &model.source;
    let before_bodies = problems.len();
    let mut body = Vec::new();
    let mut owner: Vec<Option<usize>> = vec![None; mesh.elements.len()];
    if model.bodies.is_empty() {
        problems.push(invalid(format!("{}no [[body]] defined", src.file())));
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
            Ok(Some(g)) if g.dim == 3 && g.elements.is_empty() => problems.push(invalid(format!(
                "{here}body '{}': the volume group has no elements",
                b.group
            ))),
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
            Ok(None) => problems.push(unknown(here, "volume", &b.group, mesh)),
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
    (body, problems.len() == before_bodies)
}

/// `true` for each node of some element of `body`.
pub(super) fn nodes(mesh: &Mesh, body: &[BodyElement]) -> Vec<bool> {
    let mut active_nodes = vec![false; mesh.nodes.len()];
    for be in body {
        for &a in &mesh.elements[be.element].nodes {
            active_nodes[a] = true;
        }
    }
    active_nodes
}

/// The quadrature rule of each kind of element in `body`.
pub(super) fn rules(mesh: &Mesh, body: &[BodyElement]) -> Vec<(ElementKind, Vec<QPoint>)> {
    let mut kinds: Vec<ElementKind> = body.iter().map(|b| mesh.elements[b.element].kind).collect();
    kinds.sort_unstable();
    kinds.dedup();
    kinds.iter().map(|&k| (k, shape::rule(k))).collect()
}

/// Zero-volume and inverted elements of `body` (see the module documentation).
pub(super) fn check_quality(
    path: &Path,
    mesh: &Mesh,
    body: &[BodyElement],
    rules: &[(ElementKind, Vec<QPoint>)],
    problems: &mut Vec<FemError>,
) {
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
                    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt(),
                );
            }
        }
        let min_abs = dets.iter().fold(f64::INFINITY, |m, d| m.min(d.abs()));
        let min_det = dets.iter().fold(f64::INFINITY, |m, &d| m.min(d));
        let problem = if min_abs <= 1e-8 * h.powi(3) {
            Some(FemError::ZeroVolume {
                mesh: path.to_path_buf(),
                element: bi,
                tag: el.tag,
                det_j: min_abs / h.powi(3).max(f64::MIN_POSITIVE),
            })
        } else if min_det < 0.0 {
            Some(FemError::InvertedElement {
                mesh: path.to_path_buf(),
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
}
