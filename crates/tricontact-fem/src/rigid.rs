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

/// The parts of a mesh of `n` nodes linked through the elements whose node lists `elements`
/// gives: each node's union-find parent (its part is [`find`] of it) and whether it belongs to
/// an element at all.
pub(crate) fn parts<'a>(
    n: usize,
    elements: impl Iterator<Item = &'a [usize]>,
) -> (Vec<usize>, Vec<bool>) {
    let mut parent: Vec<usize> = (0..n).collect();
    let mut in_element = vec![false; n];
    for nodes in elements {
        for &a in nodes {
            in_element[a] = true;
        }
        let r0 = find(&mut parent, nodes[0]);
        for &a in &nodes[1..] {
            let r = find(&mut parent, a);
            if r != r0 {
                parent[r] = r0;
            }
        }
    }
    (parent, in_element)
}

/// The root of `a`'s part (path halving).
pub(crate) fn find(parent: &mut [usize], mut a: usize) -> usize {
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
///
/// # Panics
/// If `prescribed` does not hold one flag per nodal DOF of the mesh (3 per node).
pub fn check_supports(an: &Analysis, prescribed: &[bool]) -> Result<(), String> {
    check_supports_with(an, prescribed, &[])
}

/// [`check_supports`] with further constraints `(node, direction)`: the node's motion along the
/// (unit) direction is held, as frictionless contact holds a slave node along its facet normal.
///
/// # Errors
/// A description of the under-supported component.
///
/// # Panics
/// As [`check_supports`]; and if a `held` node is not a node of the mesh.
pub fn check_supports_with(
    an: &Analysis,
    prescribed: &[bool],
    held: &[(usize, [f64; 3])],
) -> Result<(), String> {
    match first_free_part(an, prescribed, held) {
        Some(m) => Err(format!("{m}; add supports")),
        None => Ok(()),
    }
}

/// The description of the first body component [`free_parts`] finds, `None` when every one is
/// held.
///
/// # Panics
/// As [`check_supports_with`].
pub(crate) fn first_free_part(
    an: &Analysis,
    prescribed: &[bool],
    held: &[(usize, [f64; 3])],
) -> Option<String> {
    free_parts(an, prescribed, held)
        .into_iter()
        .next()
        .map(|(_, m)| m)
}

/// Every body component that the `prescribed` DOFs and the `held` directions leave with a free
/// rigid-body mode: its nodes and a description ("the body part containing node 7 has 3
/// unconstrained rigid-body mode(s)"; [`check_supports_with`] adds what to do).
///
/// # Panics
/// As [`check_supports_with`].
pub(crate) fn free_parts(
    an: &Analysis,
    prescribed: &[bool],
    held: &[(usize, [f64; 3])],
) -> Vec<(Vec<usize>, String)> {
    let mut directions: std::collections::HashMap<usize, Vec<[f64; 3]>> =
        std::collections::HashMap::new();
    for &(a, d) in held {
        directions.entry(a).or_default().push(d);
    }
    let n = an.mesh.nodes.len();
    assert_eq!(
        prescribed.len(),
        3 * n,
        "check_supports: one prescribed flag per nodal DOF (3 per node)"
    );
    let elements = an
        .body
        .iter()
        .map(|be| an.mesh.elements[be.element].nodes.as_slice());
    let (mut parent, in_element) = parts(n, elements);
    let mut comps: std::collections::BTreeMap<usize, Vec<usize>> =
        std::collections::BTreeMap::new();
    for a in 0..n {
        if an.active_nodes[a] {
            let r = find(&mut parent, a);
            comps.entry(r).or_default().push(a);
        }
    }
    let mut free_parts = Vec::new();
    for nodes in comps.into_values() {
        let mut c = [0.0; 3];
        for &a in &nodes {
            for i in 0..3 {
                c[i] += an.mesh.nodes[a][i] / nodes.len() as f64;
            }
        }
        let mut l = 0.0f64;
        for &a in &nodes {
            for i in 0..3 {
                l = l.max((an.mesh.nodes[a][i] - c[i]).abs());
            }
        }
        let l = if l > 0.0 { l } else { 1.0 };
        // G over the held DOFs and directions; G_all over every DOF, whose null space holds the
        // modes the part does not have at all (rotations of a lone node, as the nodes of a rigid
        // master without elements are).
        let (mut g, mut g_all) = (Matrix6::<f64>::zeros(), Matrix6::<f64>::zeros());
        for &a in &nodes {
            let x = [
                (an.mesh.nodes[a][0] - c[0]) / l,
                (an.mesh.nodes[a][1] - c[1]) / l,
                (an.mesh.nodes[a][2] - c[2]) / l,
            ];
            for i in 0..3 {
                let row = mode_row(&unit(i), &x);
                add_outer(&mut g_all, &row);
                if prescribed[3 * a + i] {
                    add_outer(&mut g, &row);
                }
            }
            for n in directions.get(&a).into_iter().flatten() {
                add_outer(&mut g, &mode_row(n, &x));
            }
        }
        let free = nullity(g).saturating_sub(nullity(g_all));
        if free > 0 {
            let tag = an.mesh.node_tags[nodes[0]];
            // A node of no element is one of a rigid contact surface's, a part of its own.
            let part = if in_element[nodes[0]] {
                format!("the body part containing node {tag}")
            } else {
                format!("node {tag} of a rigid contact surface (no volume element)")
            };
            let message = format!("{part} has {free} unconstrained rigid-body mode(s)");
            free_parts.push((nodes, message));
        }
    }
    free_parts
}

/// The unit vector along axis `i`.
fn unit(i: usize) -> [f64; 3] {
    let mut e = [0.0; 3];
    e[i] = 1.0;
    e
}

/// The rigid modes seen along direction `n` at the (scaled) position `x`:
/// `n·(t + ω × x) = [n, x × n]·[t, ω]`.
fn mode_row(n: &[f64; 3], x: &[f64; 3]) -> [f64; 6] {
    [
        n[0],
        n[1],
        n[2],
        x[1] * n[2] - x[2] * n[1],
        x[2] * n[0] - x[0] * n[2],
        x[0] * n[1] - x[1] * n[0],
    ]
}

fn add_outer(g: &mut Matrix6<f64>, row: &[f64; 6]) {
    for p in 0..6 {
        for q in 0..6 {
            g[(p, q)] += row[p] * row[q];
        }
    }
}

/// Eigenvalues of the Gram matrix `g` at most `10⁻¹⁰` of the largest (or of 1).
fn nullity(g: Matrix6<f64>) -> usize {
    let eig = SymmetricEigen::new(g).eigenvalues;
    let max = eig.iter().fold(0.0f64, |m, v| m.max(*v));
    eig.iter().filter(|&&v| v <= 1e-10 * max.max(1.0)).count()
}
