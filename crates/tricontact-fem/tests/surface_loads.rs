//! Pressure and total-force loads on quad4, tri3 and tri6 faces: resultant
//! `−p A n` with `n` the outward normal, whatever the face node order, and
//! the total force preserved by the area-weighted distribution.
#![allow(clippy::needless_range_loop)]

mod common;

use tricontact_fem::mesh::ElementKind;
use tricontact_fem::structured::box_mesh;

const SIZE: [f64; 3] = [2.0, 1.5, 1.0];
const SIDES: [&str; 6] = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"];

fn resultant(kind: ElementKind, load: &str, scale: f64) -> Vec<[f64; 3]> {
    let mut text = String::from(
        "[[material]]\nname = \"m\"\ntype = \"linear_elastic\"\nE = 1.0\nnu = 0.3\n[[body]]\ngroup = \"solid\"\nmaterial = \"m\"\n[[step]]\n",
    );
    for side in SIDES {
        text += &format!("[[load]]\ngroup = \"{side}\"\n{load}\n");
    }
    let an = common::analysis(box_mesh(SIZE.map(|x| x * scale), [3, 2, 2], kind), &text);
    an.loads
        .iter()
        .map(|l| {
            let mut s = [0.0; 3];
            for (_, f) in &l.forces {
                for i in 0..3 {
                    s[i] += f[i];
                }
            }
            s
        })
        .collect()
}

#[test]
fn pressure_resultant_is_minus_p_area_outward_normal() {
    let p = 3.0;
    for kind in [ElementKind::Hex8, ElementKind::Tet4, ElementKind::Tet10] {
        let r = resultant(kind, &format!("pressure = {p}"), 1.0);
        for (s, side) in SIDES.iter().enumerate() {
            let axis = s / 2;
            let outward = if s % 2 == 0 { -1.0 } else { 1.0 };
            let area = SIZE[(axis + 1) % 3] * SIZE[(axis + 2) % 3];
            for i in 0..3 {
                let expect = if i == axis { -p * area * outward } else { 0.0 };
                assert!(
                    (r[s][i] - expect).abs() < 1e-12 * p * area,
                    "{kind:?} {side}: {:?}",
                    r[s]
                );
            }
        }
    }
}

#[test]
fn total_force_is_preserved_on_every_face_type() {
    // Also on models of lengths near the limits of the coordinates (±10¹⁰⁰): at 10⁹⁰ the faces'
    // areas overflowed in their squares and the forces came out NaN.
    for scale in [1.0, 1e90, 1e-90] {
        for kind in [ElementKind::Hex8, ElementKind::Tet4, ElementKind::Tet10] {
            let r = resultant(kind, "force = [1.0, -2.0, 0.5]", scale);
            for (s, side) in SIDES.iter().enumerate() {
                let expect = [1.0, -2.0, 0.5];
                for i in 0..3 {
                    assert!(
                        (r[s][i] - expect[i]).abs() < 1e-12,
                        "{kind:?} {side} at {scale:e}: {:?}",
                        r[s]
                    );
                }
            }
        }
    }
}
