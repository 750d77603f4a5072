//! Follower pressure: a pressure acting on the *deformed* surface, with its
//! consistent (unsymmetric) load stiffness.
//!
//! On a face with current position `x = X + u`, the area vector is
//! `a = x_ξ × x_η` (`x_ξ = Σ_b ∂N_b/∂ξ x_b`) and the external force is
//! `f_a = −p s Σ_gp w N_a a`, where `s = ±1` orients `a` outward (fixed from
//! the reference configuration). With `r = f_int − f_ext`, the residual gets
//! `+p s Σ w N_a a` and the tangent
//! `∂r_ai/∂u_bk = p s Σ w N_a (∂N_b/∂ξ (e_k × x_η)_i + ∂N_b/∂η (x_ξ × e_k)_i)`.
//! At `u = 0` the force equals the dead pressure of [`crate::loads`].

use crate::mesh::Mesh;
use crate::shape;

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Adds the follower-pressure residual (and tangent triplets in global DOF
/// numbering, if requested) of pressure `p` on `faces` = `(face element,
/// outward sign)` at displacements `u`.
pub fn pressure_terms(
    mesh: &Mesh,
    faces: &[(usize, f64)],
    p: f64,
    u: &[f64],
    residual: &mut [f64],
    mut triplets: Option<&mut Vec<(usize, usize, f64)>>,
) {
    for &(fi, sign) in faces {
        let face = &mesh.elements[fi];
        let x: Vec<[f64; 3]> = face
            .nodes
            .iter()
            .map(|&a| {
                let xa = mesh.nodes[a];
                [xa[0] + u[3 * a], xa[1] + u[3 * a + 1], xa[2] + u[3 * a + 2]]
            })
            .collect();
        for q in shape::rule(face.kind) {
            let mut t = [[0.0; 3]; 2];
            for (b, xb) in x.iter().enumerate() {
                for j in 0..2 {
                    for i in 0..3 {
                        t[j][i] += xb[i] * q.shape.dn[b][j];
                    }
                }
            }
            let area = cross(t[0], t[1]);
            let c = p * sign * q.w;
            for (a, &na) in face.nodes.iter().enumerate() {
                for i in 0..3 {
                    residual[3 * na + i] += c * q.shape.n[a] * area[i];
                }
            }
            if let Some(trip) = triplets.as_deref_mut() {
                for (b, &nb) in face.nodes.iter().enumerate() {
                    for k in 0..3 {
                        let mut e = [0.0; 3];
                        e[k] = 1.0;
                        let d1 = cross(e, t[1]);
                        let d2 = cross(t[0], e);
                        let da: [f64; 3] = std::array::from_fn(|i| {
                            q.shape.dn[b][0] * d1[i] + q.shape.dn[b][1] * d2[i]
                        });
                        for (a, &na) in face.nodes.iter().enumerate() {
                            for i in 0..3 {
                                let v = c * q.shape.n[a] * da[i];
                                if v != 0.0 {
                                    trip.push((3 * na + i, 3 * nb + k, v));
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Element, ElementKind};

    fn one_face_mesh(kind: ElementKind) -> Mesh {
        let nodes: Vec<[f64; 3]> = shape::node_coords(kind)
            .iter()
            .map(|p| {
                [
                    1.3 * p[0] + 0.2 * p[1],
                    0.9 * p[1] + 0.1,
                    0.3 * p[0] - 0.2 * p[1] + 0.5,
                ]
            })
            .collect();
        let n = nodes.len();
        Mesh {
            node_tags: (1..=n as u64).collect(),
            nodes,
            elements: vec![Element {
                kind,
                nodes: (0..n).collect(),
                tag: 1,
            }],
            groups: Vec::new(),
        }
    }

    #[test]
    fn load_stiffness_matches_central_differences() {
        for kind in [ElementKind::Tri3, ElementKind::Tri6, ElementKind::Quad4] {
            let mesh = one_face_mesh(kind);
            let nd = 3 * mesh.nodes.len();
            let u: Vec<f64> = (0..nd)
                .map(|i| 0.05 * ((i * 7 % 11) as f64 - 5.0) / 5.0)
                .collect();
            let faces = [(0, -1.0)];
            let mut r = vec![0.0; nd];
            let mut trip = Vec::new();
            pressure_terms(&mesh, &faces, 2.5, &u, &mut r, Some(&mut trip));
            let mut k = vec![0.0; nd * nd];
            for (i, j, v) in trip {
                k[i * nd + j] += v;
            }
            let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let h = 1e-6;
            let mut err = 0.0f64;
            for j in 0..nd {
                let (mut up, mut um) = (u.clone(), u.clone());
                up[j] += h;
                um[j] -= h;
                let (mut rp, mut rm) = (vec![0.0; nd], vec![0.0; nd]);
                pressure_terms(&mesh, &faces, 2.5, &up, &mut rp, None);
                pressure_terms(&mesh, &faces, 2.5, &um, &mut rm, None);
                for i in 0..nd {
                    err = err.max(((rp[i] - rm[i]) / (2.0 * h) - k[i * nd + j]).abs());
                }
            }
            assert!(
                err / kmax <= 1e-6,
                "{kind:?}: relative error {:e}",
                err / kmax
            );
        }
    }
}
