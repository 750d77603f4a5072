//! Consistent nodal forces of the model loads (dead loads: computed once in
//! the reference configuration and scaled by the load amplitude; follower
//! pressures are in [`crate::follower`]).
//!
//! Pressure `p` on a face: `f_a = −p ∫ N_a n dA`, with `n` the unit normal
//! pointing out of the adjacent body element, so a positive pressure pushes
//! into the body. The area element is `(∂X/∂ξ × ∂X/∂η) dξ dη`.
//! Total force `F` on a group with faces: distributed as a uniform traction,
//! `f_a = F ∫ N_a dA / A`; on a group without faces (points, edges, node
//! sets): `F / (number of nodes)` per node.

use std::collections::HashMap;

use crate::mesh::{Element, Mesh};
use crate::shape;

/// For each node, the body elements (indices into `body_elems`) using it.
#[must_use]
pub fn node_to_elements(n_nodes: usize, elements: &[&Element]) -> Vec<Vec<usize>> {
    let mut map = vec![Vec::new(); n_nodes];
    for (e, el) in elements.iter().enumerate() {
        for &a in &el.nodes {
            map[a].push(e);
        }
    }
    map
}

/// The Gmsh tags of the first two of `faces` (indices into the mesh's elements) on the same nodes,
/// if any: a face listed twice would carry its pressure twice.
#[must_use]
pub fn repeated_face(mesh: &Mesh, faces: &[usize]) -> Option<(u64, u64)> {
    let mut seen: HashMap<Vec<usize>, u64> = HashMap::with_capacity(faces.len());
    for &f in faces {
        let el = &mesh.elements[f];
        let mut nodes = el.nodes.clone();
        nodes.sort_unstable();
        if let Some(&first) = seen.get(&nodes) {
            return Some((first, el.tag));
        }
        seen.insert(nodes, el.tag);
    }
    None
}

/// Area vector `∂X/∂ξ × ∂X/∂η` and shape functions at every face quadrature
/// point: `(weight · area vector, N)`.
fn face_points(mesh: &Mesh, face: &Element) -> Vec<([f64; 3], [f64; shape::MAX_NODES])> {
    shape::rule(face.kind)
        .iter()
        .map(|q| {
            let mut t = [[0.0; 3]; 2];
            for (a, &node) in face.nodes.iter().enumerate() {
                for j in 0..2 {
                    for i in 0..3 {
                        t[j][i] += mesh.nodes[node][i] * q.shape.dn[a][j];
                    }
                }
            }
            let c = [
                t[0][1] * t[1][2] - t[0][2] * t[1][1],
                t[0][2] * t[1][0] - t[0][0] * t[1][2],
                t[0][0] * t[1][1] - t[0][1] * t[1][0],
            ];
            ([c[0] * q.w, c[1] * q.w, c[2] * q.w], q.shape.n)
        })
        .collect()
}

fn centroid(mesh: &Mesh, nodes: &[usize]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &a in nodes {
        for i in 0..3 {
            c[i] += mesh.nodes[a][i] / nodes.len() as f64;
        }
    }
    c
}

/// Outward sign of each face's area vector `∂X/∂ξ × ∂X/∂η` relative to
/// the body element it bounds: `(face element, ±1)`.
///
/// # Errors
/// The Gmsh tag of the first face without an adjacent body element.
pub fn outward_faces(
    mesh: &Mesh,
    faces: &[usize],
    body: &[&Element],
    node_elems: &[Vec<usize>],
) -> Result<Vec<(usize, f64)>, u64> {
    faces
        .iter()
        .map(|&fi| {
            let face = &mesh.elements[fi];
            let corners = &face.nodes[..face.kind.num_corners()];
            let owner = node_elems[corners[0]]
                .iter()
                .copied()
                .find(|&e| corners.iter().all(|c| body[e].nodes.contains(c)))
                .ok_or(face.tag)?;
            let ec = centroid(mesh, &body[owner].nodes);
            let fc = centroid(mesh, corners);
            let a_sum: [f64; 3] = face_points(mesh, face).iter().fold([0.0; 3], |s, (a, _)| {
                [s[0] + a[0], s[1] + a[1], s[2] + a[2]]
            });
            let outward = (0..3).map(|i| a_sum[i] * (fc[i] - ec[i])).sum::<f64>();
            Ok((fi, if outward < 0.0 { -1.0 } else { 1.0 }))
        })
        .collect()
}

/// Nodal forces of a dead pressure `p` on oriented `faces` (see
/// [`outward_faces`]).
#[must_use]
pub fn pressure_forces(mesh: &Mesh, faces: &[(usize, f64)], p: f64) -> HashMap<usize, [f64; 3]> {
    let mut out: HashMap<usize, [f64; 3]> = HashMap::new();
    for &(fi, sign) in faces {
        let face = &mesh.elements[fi];
        for (a, n) in face_points(mesh, face) {
            for (k, &node) in face.nodes.iter().enumerate() {
                let f = out.entry(node).or_insert([0.0; 3]);
                for i in 0..3 {
                    f[i] -= p * sign * n[k] * a[i];
                }
            }
        }
    }
    out
}

/// Nodal forces of a total force `force` spread over a group: area-weighted
/// over `faces` if there are any, else equally over `nodes`.
#[must_use]
pub fn total_force(
    mesh: &Mesh,
    faces: &[usize],
    nodes: &[usize],
    force: [f64; 3],
) -> HashMap<usize, [f64; 3]> {
    let mut out: HashMap<usize, [f64; 3]> = HashMap::new();
    let mut weights: HashMap<usize, f64> = HashMap::new();
    let mut area = 0.0;
    for &fi in faces {
        let face = &mesh.elements[fi];
        for (a, n) in face_points(mesh, face) {
            // Without squaring: areas of faces with edges past 10¹⁵⁴ (coordinates go to 10¹⁰⁰)
            // overflowed in the squares, and the force came out NaN.
            let da = a[0].hypot(a[1]).hypot(a[2]);
            area += da;
            for (k, &node) in face.nodes.iter().enumerate() {
                *weights.entry(node).or_insert(0.0) += n[k] * da;
            }
        }
    }
    if area > 0.0 {
        for (node, w) in weights {
            out.insert(node, force.map(|f| f * w / area));
        }
    } else if !nodes.is_empty() {
        let share = 1.0 / nodes.len() as f64;
        for &a in nodes {
            out.insert(a, force.map(|f| f * share));
        }
    }
    out
}
