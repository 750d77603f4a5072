//! Structured box meshes `[0, lx] × [0, ly] × [0, lz]` for tests, examples and
//! the benchmark: hex8 bricks, or each brick split into 6 tet4 (Kuhn split
//! along the main diagonal, conforming between bricks), optionally promoted
//! to tet10 by inserting edge mid-nodes.
//!
//! Groups: `solid` (3D) and the six faces `xmin, xmax, ymin, ymax, zmin,
//! zmax` (2D; quad4, tri3 or tri6 faces). [`stack`] puts two meshes in one
//! (two bodies, e.g. for contact), their groups prefixed `lower_` and `upper_`.

use std::collections::HashMap;

use crate::mesh::{Element, ElementKind, Group, Mesh};

fn node_id(n: [usize; 3], i: usize, j: usize, k: usize) -> usize {
    i + (n[0] + 1) * (j + (n[1] + 1) * k)
}

/// Builds a box mesh of `n` bricks per direction with elements of `kind`
/// (`Hex8`, `Tet4` or `Tet10`).
///
/// # Panics
/// If `kind` is a face kind.
#[must_use]
pub fn box_mesh(size: [f64; 3], n: [usize; 3], kind: ElementKind) -> Mesh {
    assert!(kind.dim() == 3, "box_mesh needs a volume element kind");
    let mut nodes = grid_nodes(size, n);
    let mut vols = bricks(n, kind);
    orient_tets(&nodes, &mut vols);
    let mut sides = boundary_faces(&nodes, size, &vols, kind);
    if kind == ElementKind::Tet10 {
        add_mid_nodes(&mut nodes, &mut vols, &mut sides);
    }
    let mut mesh = Mesh {
        nodes,
        ..Mesh::default()
    };
    let face_kind = match kind {
        ElementKind::Hex8 => ElementKind::Quad4,
        ElementKind::Tet4 => ElementKind::Tri3,
        _ => ElementKind::Tri6,
    };
    mesh.node_tags = (1..=mesh.nodes.len() as u64).collect();
    let mut tag = 0u64;
    let mut push = |mesh: &mut Mesh, kind: ElementKind, nodes: Vec<usize>| {
        tag += 1;
        mesh.elements.push(Element { kind, nodes, tag });
        mesh.elements.len() - 1
    };
    let solid: Vec<usize> = vols.into_iter().map(|v| push(&mut mesh, kind, v)).collect();
    let mut groups = vec![Group {
        name: "solid".into(),
        dim: 3,
        nodes: Vec::new(),
        elements: solid,
    }];
    for (s, name) in ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]
        .iter()
        .enumerate()
    {
        let faces = std::mem::take(&mut sides[s]);
        let elements = faces
            .into_iter()
            .map(|f| push(&mut mesh, face_kind, f))
            .collect();
        groups.push(Group {
            name: (*name).into(),
            dim: 2,
            nodes: Vec::new(),
            elements,
        });
    }
    for g in &mut groups {
        let mut nodes: Vec<usize> = g
            .elements
            .iter()
            .flat_map(|&e| mesh.elements[e].nodes.iter().copied())
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        g.nodes = nodes;
    }
    mesh.groups = groups;
    mesh
}

/// The `(n₀+1)(n₁+1)(n₂+1)` grid nodes, `x` fastest.
fn grid_nodes(size: [f64; 3], n: [usize; 3]) -> Vec<[f64; 3]> {
    let mut nodes = Vec::with_capacity((n[0] + 1) * (n[1] + 1) * (n[2] + 1));
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                nodes.push([
                    size[0] * i as f64 / n[0] as f64,
                    size[1] * j as f64 / n[1] as f64,
                    size[2] * k as f64 / n[2] as f64,
                ]);
            }
        }
    }
    nodes
}

/// The volume elements brick by brick: one hex8 each, or six tets of the Kuhn split (corner
/// nodes only; see the module documentation).
fn bricks(n: [usize; 3], kind: ElementKind) -> Vec<Vec<usize>> {
    let mut vols: Vec<Vec<usize>> = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let c = |di: usize, dj: usize, dk: usize| node_id(n, i + di, j + dj, k + dk);
                let hex = [
                    c(0, 0, 0),
                    c(1, 0, 0),
                    c(1, 1, 0),
                    c(0, 1, 0),
                    c(0, 0, 1),
                    c(1, 0, 1),
                    c(1, 1, 1),
                    c(0, 1, 1),
                ];
                if kind == ElementKind::Hex8 {
                    vols.push(hex.to_vec());
                } else {
                    // Cube vertex by bits (x = 1, y = 2, z = 4).
                    let v = |b: usize| c(b & 1, (b >> 1) & 1, (b >> 2) & 1);
                    for p in [
                        [0, 1, 2],
                        [0, 2, 1],
                        [1, 0, 2],
                        [1, 2, 0],
                        [2, 0, 1],
                        [2, 1, 0],
                    ] {
                        let b1 = 1 << p[0];
                        let b2 = b1 | (1 << p[1]);
                        vols.push(vec![v(0), v(b1), v(b2), v(7)]);
                    }
                }
            }
        }
    }
    vols
}

/// Swaps two nodes of every tet with a negative volume.
fn orient_tets(nodes: &[[f64; 3]], vols: &mut [Vec<usize>]) {
    for t in vols.iter_mut().filter(|t| t.len() == 4) {
        let x = |a: usize| nodes[t[a]];
        let d = |a: usize| {
            let (p, o) = (x(a), x(0));
            [p[0] - o[0], p[1] - o[1], p[2] - o[2]]
        };
        let (a, b, c) = (d(1), d(2), d(3));
        let vol = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]);
        if vol < 0.0 {
            t.swap(1, 2);
        }
    }
}

/// The boundary faces of each side `xmin, xmax, ymin, ymax, zmin, zmax`, taken from the volume
/// elements (corner nodes only).
fn boundary_faces(
    nodes: &[[f64; 3]],
    size: [f64; 3],
    vols: &[Vec<usize>],
    kind: ElementKind,
) -> Vec<Vec<Vec<usize>>> {
    let on_side = |p: [f64; 3], side: usize| {
        let axis = side / 2;
        let target = if side.is_multiple_of(2) {
            0.0
        } else {
            size[axis]
        };
        (p[axis] - target).abs() <= 1e-12 * size[axis]
    };
    let local_faces: Vec<Vec<usize>> = if kind == ElementKind::Hex8 {
        vec![
            vec![0, 3, 2, 1],
            vec![4, 5, 6, 7],
            vec![0, 1, 5, 4],
            vec![1, 2, 6, 5],
            vec![2, 3, 7, 6],
            vec![3, 0, 4, 7],
        ]
    } else {
        vec![vec![0, 2, 1], vec![0, 1, 3], vec![1, 2, 3], vec![0, 3, 2]]
    };
    let mut sides: Vec<Vec<Vec<usize>>> = vec![Vec::new(); 6];
    for v in vols {
        for lf in &local_faces {
            let f: Vec<usize> = lf.iter().map(|&a| v[a]).collect();
            for (s, side) in sides.iter_mut().enumerate() {
                if f.iter().all(|&a| on_side(nodes[a], s)) {
                    side.push(f.clone());
                }
            }
        }
    }
    sides
}

/// Tet10: mid-edge nodes (Gmsh edge order) appended to `nodes`, shared through an edge map, and
/// added to the tets and to the side faces (tri6).
fn add_mid_nodes(
    nodes: &mut Vec<[f64; 3]>,
    vols: &mut [Vec<usize>],
    sides: &mut [Vec<Vec<usize>>],
) {
    let mut edge_nodes: HashMap<(usize, usize), usize> = HashMap::new();
    let mut mid = |a: usize, b: usize, nodes: &mut Vec<[f64; 3]>| {
        let key = (a.min(b), a.max(b));
        *edge_nodes.entry(key).or_insert_with(|| {
            let (p, q) = (nodes[a], nodes[b]);
            nodes.push([
                (p[0] + q[0]) / 2.0,
                (p[1] + q[1]) / 2.0,
                (p[2] + q[2]) / 2.0,
            ]);
            nodes.len() - 1
        })
    };
    for t in vols.iter_mut() {
        let c = [t[0], t[1], t[2], t[3]];
        for [a, b] in crate::tet10::EDGES {
            let m = mid(c[a], c[b], nodes);
            t.push(m);
        }
    }
    for side in sides.iter_mut() {
        for f in side.iter_mut() {
            let c = [f[0], f[1], f[2]];
            for [a, b] in [[0, 1], [1, 2], [2, 0]] {
                let m = mid(c[a], c[b], nodes);
                f.push(m);
            }
        }
    }
}

/// Two meshes in one: node and element indices of `upper` shifted, its node coordinates moved
/// by `offset`, groups renamed `lower_<name>` and `upper_<name>`.
#[must_use]
pub fn stack(lower: &Mesh, upper: &Mesh, offset: [f64; 3]) -> Mesh {
    let mut m = lower.clone();
    let (nn, ne) = (lower.nodes.len(), lower.elements.len());
    for g in &mut m.groups {
        g.name = format!("lower_{}", g.name);
    }
    for p in &upper.nodes {
        m.nodes
            .push([p[0] + offset[0], p[1] + offset[1], p[2] + offset[2]]);
    }
    m.node_tags = (1..=m.nodes.len() as u64).collect();
    let tag0 = lower.elements.len() as u64;
    for e in &upper.elements {
        let mut e = e.clone();
        e.nodes.iter_mut().for_each(|a| *a += nn);
        e.tag += tag0;
        m.elements.push(e);
    }
    for g in &upper.groups {
        let mut g = g.clone();
        g.name = format!("upper_{}", g.name);
        g.elements.iter_mut().for_each(|e| *e += ne);
        g.nodes.iter_mut().for_each(|a| *a += nn);
        m.groups.push(g);
    }
    m
}

/// Moves every node not on the box boundary by a deterministic pseudo-random
/// offset of at most `amount` (a fraction of the smallest brick edge).
/// Tet10 edge nodes are then put back at the midpoints of their (moved)
/// corners, so elements stay straight-sided (affine).
pub fn distort_interior(mesh: &mut Mesh, size: [f64; 3], n: [usize; 3], amount: f64) {
    let h = (0..3)
        .map(|i| size[i] / n[i] as f64)
        .fold(f64::INFINITY, f64::min);
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for p in &mut mesh.nodes {
        let interior = (0..3).all(|i| p[i] > 1e-9 * size[i] && p[i] < size[i] * (1.0 - 1e-9));
        let d = [rnd(), rnd(), rnd()];
        if interior {
            for i in 0..3 {
                p[i] += amount * h * d[i];
            }
        }
    }
    for e in &mesh.elements {
        if e.kind == ElementKind::Tet10 {
            for (k, [a, b]) in crate::tet10::EDGES.iter().enumerate() {
                let (p, q) = (mesh.nodes[e.nodes[*a]], mesh.nodes[e.nodes[*b]]);
                mesh.nodes[e.nodes[4 + k]] = [
                    (p[0] + q[0]) / 2.0,
                    (p[1] + q[1]) / 2.0,
                    (p[2] + q[2]) / 2.0,
                ];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_groups() {
        let m = box_mesh([2.0, 1.0, 1.0], [2, 1, 1], ElementKind::Hex8);
        assert_eq!(m.nodes.len(), 12);
        assert_eq!(m.group("solid").map(|g| g.elements.len()), Some(2));
        assert_eq!(m.group("xmax").map(|g| g.nodes.len()), Some(4));
        let t = box_mesh([1.0, 1.0, 1.0], [1, 1, 1], ElementKind::Tet10);
        assert_eq!(t.group("solid").map(|g| g.elements.len()), Some(6));
        // 8 corners + 19 edges of the Kuhn split (12 cube + 6 face + 1 body diagonal).
        assert_eq!(t.nodes.len(), 8 + 19);
        assert_eq!(t.group("zmin").map(|g| g.elements.len()), Some(2));
    }
}
