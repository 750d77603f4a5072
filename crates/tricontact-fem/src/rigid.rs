//! Detection of unsupported rigid-body motion before factorizing.
//!
//! For each connected body component (nodes linked through elements), the
//! six rigid modes `ψ = [e_i, e_i × (X − X_c)/L]` are restricted to the
//! component's prescribed DOFs; the supports remove all modes iff the 6×6
//! Gram matrix `G = Σ ψᵀψ` over those DOFs has full rank (smallest
//! eigenvalue > 1e-10 × largest). Otherwise the stiffness matrix is
//! singular and the model is reported as such instead of solving.

use nalgebra::{Matrix6, SymmetricEigen};

use crate::analysis::Analysis;

fn find(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

/// Checks that the `prescribed` DOFs remove every rigid mode of every body
/// component; returns a message naming the free modes otherwise.
///
/// # Errors
/// A description of the under-supported component.
pub fn check_supports(an: &Analysis, prescribed: &[bool]) -> Result<(), String> {
    let n = an.mesh.nodes.len();
    let mut parent: Vec<usize> = (0..n).collect();
    for be in &an.body {
        let nodes = &an.mesh.elements[be.element].nodes;
        let r0 = find(&mut parent, nodes[0]);
        for &a in &nodes[1..] {
            let r = find(&mut parent, a);
            if r != r0 {
                parent[r] = r0;
            }
        }
    }
    let mut comps: std::collections::BTreeMap<usize, Vec<usize>> =
        std::collections::BTreeMap::new();
    for a in 0..n {
        if an.active_nodes[a] {
            let r = find(&mut parent, a);
            comps.entry(r).or_default().push(a);
        }
    }
    for nodes in comps.values() {
        let mut c = [0.0; 3];
        for &a in nodes {
            for i in 0..3 {
                c[i] += an.mesh.nodes[a][i] / nodes.len() as f64;
            }
        }
        let mut l = 0.0f64;
        for &a in nodes {
            for i in 0..3 {
                l = l.max((an.mesh.nodes[a][i] - c[i]).abs());
            }
        }
        let l = if l > 0.0 { l } else { 1.0 };
        let mut g = Matrix6::<f64>::zeros();
        for &a in nodes {
            let x = [
                (an.mesh.nodes[a][0] - c[0]) / l,
                (an.mesh.nodes[a][1] - c[1]) / l,
                (an.mesh.nodes[a][2] - c[2]) / l,
            ];
            for i in 0..3 {
                if !prescribed[3 * a + i] {
                    continue;
                }
                // Row of the rigid-mode matrix for DOF (a, i): translation e_i,
                // rotation ω: (ω × x)_i.
                let mut row = [0.0; 6];
                row[i] = 1.0;
                match i {
                    0 => {
                        row[4] = x[2];
                        row[5] = -x[1];
                    }
                    1 => {
                        row[3] = -x[2];
                        row[5] = x[0];
                    }
                    _ => {
                        row[3] = x[1];
                        row[4] = -x[0];
                    }
                }
                for p in 0..6 {
                    for q in 0..6 {
                        g[(p, q)] += row[p] * row[q];
                    }
                }
            }
        }
        let eig = SymmetricEigen::new(g).eigenvalues;
        let max = eig.iter().fold(0.0f64, |m, v| m.max(*v));
        let free = eig.iter().filter(|&&v| v <= 1e-10 * max.max(1.0)).count();
        if free > 0 {
            return Err(format!(
                "the body part containing node {} has {free} unconstrained rigid-body mode(s); add supports",
                an.mesh.node_tags[nodes[0]]
            ));
        }
    }
    Ok(())
}
