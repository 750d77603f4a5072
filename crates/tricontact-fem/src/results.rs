//! Derived result fields: element-mean Cauchy stress, von Mises stress, and
//! their nodal averages (unweighted mean over the body elements sharing a
//! node), reactions summed per boundary group.

use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::analysis::Analysis;
use crate::element::mean_cauchy_stress;
use crate::material::von_mises;

/// Stress fields of one state.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StressFields {
    /// Per body element, 6 components `XX YY ZZ XY YZ XZ`.
    pub cell_stress: Vec<f64>,
    /// Per body element.
    pub cell_von_mises: Vec<f64>,
    /// Per node, 6 components.
    pub point_stress: Vec<f64>,
    /// Per node.
    pub point_von_mises: Vec<f64>,
}

fn voigt(s: &Matrix3<f64>) -> [f64; 6] {
    [
        s[(0, 0)],
        s[(1, 1)],
        s[(2, 2)],
        s[(0, 1)],
        s[(1, 2)],
        s[(0, 2)],
    ]
}

/// Computes stresses for displacements `u` (global DOFs). Inverted points
/// (impossible at a converged state) give NaN.
///
/// # Panics
/// If `u` holds fewer than three values per node of the mesh.
#[must_use]
pub fn stress_fields(an: &Analysis, u: &[f64], nlgeom: bool) -> StressFields {
    assert!(
        u.len() >= an.num_nodal_dofs(),
        "stress_fields: u holds {} values, the mesh's nodes need {}",
        u.len(),
        an.num_nodal_dofs()
    );
    let per_elem: Vec<Matrix3<f64>> = an
        .body
        .par_iter()
        .map(|be| {
            let el = &an.mesh.elements[be.element];
            let (x0, ue) = an.element_state(be.element, u);
            mean_cauchy_stress(
                an.rule(el.kind),
                &x0,
                &ue,
                &an.materials[be.material],
                nlgeom,
            )
            .unwrap_or_else(|_| Matrix3::from_element(f64::NAN))
        })
        .collect();
    let n = an.mesh.nodes.len();
    let mut out = StressFields {
        cell_stress: Vec::with_capacity(6 * per_elem.len()),
        cell_von_mises: Vec::with_capacity(per_elem.len()),
        point_stress: vec![0.0; 6 * n],
        point_von_mises: vec![0.0; n],
    };
    let mut count = vec![0usize; n];
    for (be, s) in an.body.iter().zip(&per_elem) {
        let v = voigt(s);
        let vm = von_mises(s);
        out.cell_stress.extend_from_slice(&v);
        out.cell_von_mises.push(vm);
        for &a in &an.mesh.elements[be.element].nodes {
            count[a] += 1;
            for c in 0..6 {
                out.point_stress[6 * a + c] += v[c];
            }
            out.point_von_mises[a] += vm;
        }
    }
    for a in 0..n {
        if count[a] > 0 {
            let w = 1.0 / count[a] as f64;
            for c in 0..6 {
                out.point_stress[6 * a + c] *= w;
            }
            out.point_von_mises[a] *= w;
        }
    }
    out
}

/// Sum of the reaction forces over the nodes of each boundary group, in step `step`: only the
/// components the boundary prescribes in that step (0 for the others, and for a boundary that is
/// not active in it, whose nodes another boundary may hold).
///
/// # Panics
/// If `reactions` holds fewer than three values per node of the mesh.
#[must_use]
pub fn boundary_reactions(an: &Analysis, step: usize, reactions: &[f64]) -> Vec<[f64; 3]> {
    assert!(
        reactions.len() >= an.num_nodal_dofs(),
        "boundary_reactions: {} reactions, the mesh's nodes need {}",
        reactions.len(),
        an.num_nodal_dofs()
    );
    an.boundaries
        .iter()
        .map(|b| {
            let mut s = [0.0; 3];
            if !b.active.get(step).copied().unwrap_or(false) {
                return s;
            }
            for &a in &b.nodes {
                for i in (0..3).filter(|&i| b.values[i].is_some()) {
                    s[i] += reactions[3 * a + i];
                }
            }
            s
        })
        .collect()
}
