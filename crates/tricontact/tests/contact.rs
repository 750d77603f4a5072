//! The contact layer's facet choice at edges and vertices, sliding, convex and concave edges, and
//! the assembled penalty terms against finite differences.

use tricontact::contact::{Constraint, assemble_penalty, choose_facet, choose_facet_facing};
use tricontact::search::scenes::grid;
use tricontact::search::{Bvh, Surface};
use tricontact::{GeometryError, Vec3, penalty};

/// A flat master grid (4 × 4 squares of size 1, normals +z) plus one slave node at `x`.
fn flat_with_slave(x: Vec3) -> (Surface, Vec<Vec3>, u32) {
    let (mut nodes, facets) = grid(4, 1.0);
    let slave = u32::try_from(nodes.len()).unwrap();
    nodes.push(x);
    (Surface::new(facets, nodes.len()).unwrap(), nodes, slave)
}

fn slave_force(x: Vec3, alpha: f64) -> (u32, f64, Vec3) {
    let (surface, nodes, slave) = flat_with_slave(x);
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let (facet, pair) = choose_facet(&surface, &bvh, &nodes, slave, 0.5).expect("a facet");
    let terms = penalty(&pair, alpha).unwrap();
    (facet, pair.gap(), terms.resistance(3))
}

#[test]
fn interior_edge_and_vertex_nodes_get_the_same_force() {
    let depth = 1e-3;
    let alpha = 1e4;
    let reference = alpha * depth;
    for (x, y) in [
        (1.3, 2.6),
        (1.5, 2.0),
        (2.0, 2.5),
        (2.0, 2.0),
        (1.5, 1.5),
        (0.0, 0.0),
        (4.0, 4.0),
    ] {
        let (_, gap, r) = slave_force(Vec3::new(x, y, -depth), alpha);
        assert!((gap + depth).abs() <= 1e-15, "({x}, {y}): gap {gap}");
        assert!(
            (r - Vec3::new(0.0, 0.0, reference)).norm() <= 1e-12 * reference,
            "({x}, {y}): {r}"
        );
    }
}

#[test]
fn a_node_on_a_shared_vertex_is_constrained_once_to_the_lowest_facet() {
    let (surface, nodes, slave) = flat_with_slave(Vec3::new(2.0, 2.0, -1e-3));
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let (facet, _) = choose_facet(&surface, &bvh, &nodes, slave, 0.5).unwrap();
    // Node (2, 2) of the 5 × 5 node grid is node 12; the lowest facet containing it wins.
    let lowest = (0..surface.len() as u32)
        .find(|&f| surface.facets()[f as usize].contains(&12))
        .unwrap();
    assert_eq!(facet, lowest);
}

#[test]
fn sliding_across_facet_edges_keeps_gap_and_force_constant() {
    let depth = 2e-3;
    let alpha = 5e3;
    let mut facets_seen = std::collections::BTreeSet::new();
    for step in 0..=400 {
        let s = f64::from(step) / 400.0;
        let x = Vec3::new(0.2 + 3.5 * s, 0.7 + 2.1 * s, -depth);
        let (facet, gap, r) = slave_force(x, alpha);
        facets_seen.insert(facet);
        assert!((gap + depth).abs() <= 1e-15);
        assert!(
            (r.z - alpha * depth).abs() <= 1e-12 * alpha * depth && r.x.abs() + r.y.abs() < 1e-12
        );
    }
    assert!(
        facets_seen.len() >= 6,
        "crossed {} facets",
        facets_seen.len()
    );
}

/// A roof: two strips of facets meeting at the ridge `x = 0` (apex `z = 0`), slopes `z = −|x|/2`,
/// outward normals pointing up and away from the ridge; or a valley with `z = +|x|/2`.
fn ridge(sign: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut nodes = Vec::new();
    for j in 0..5 {
        for i in 0..5 {
            let x = f64::from(i) - 2.0;
            nodes.push(Vec3::new(x, f64::from(j), sign * x.abs() / 2.0));
        }
    }
    let id = |i: u32, j: u32| j * 5 + i;
    let mut facets = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            facets.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            facets.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (nodes, facets)
}

fn choose_on(nodes: &[Vec3], facets: &[[u32; 3]], x: Vec3) -> Option<f64> {
    let mut all = nodes.to_vec();
    let slave = u32::try_from(all.len()).unwrap();
    all.push(x);
    let surface = Surface::new(facets.to_vec(), all.len()).unwrap();
    let bvh = Bvh::build(&surface, &all, 0.0).unwrap();
    choose_facet(&surface, &bvh, &all, slave, 1.0).map(|(_, pair)| pair.gap())
}

#[test]
fn a_node_pushed_through_a_convex_ridge_is_always_caught() {
    let (nodes, facets) = ridge(-1.0);
    // Straight down through the apex line, and obliquely across it while inside.
    for k in 0..=100 {
        let z = 0.2 - 0.4 * f64::from(k) / 100.0;
        let gap = choose_on(&nodes, &facets, Vec3::new(0.0, 2.3, z));
        if z < 0.0 {
            let gap = gap.expect("a node inside the body is constrained");
            // The shallowest way out: the distance to the nearer flank.
            assert!(gap < 0.0 && gap >= z, "z = {z}: gap {gap}");
        } else if let Some(gap) = gap {
            assert!(
                gap >= 0.0,
                "z = {z}: an outside node reports penetration {gap}"
            );
        }
    }
    for k in 0..=100 {
        let x = -0.3 + 0.6 * f64::from(k) / 100.0;
        let inside = -x.abs() / 2.0 - 0.01;
        let gap = choose_on(&nodes, &facets, Vec3::new(x, 1.7, inside)).expect("caught");
        assert!(gap < 0.0, "x = {x}: gap {gap}");
    }
}

#[test]
fn a_node_penetrating_one_flank_of_a_valley_is_caught() {
    let (nodes, facets) = ridge(1.0);
    for k in 1..=50 {
        let x = 0.02 * f64::from(k);
        // Just below the right flank z = x/2, above the left flank's plane z = −x/2.
        let gap = choose_on(&nodes, &facets, Vec3::new(x, 2.2, x / 2.0 - 0.005)).expect("caught");
        assert!(gap < 0.0, "x = {x}: gap {gap}");
    }
}

/// The rule's one blind spot, stated in `choice.rs`: below a valley, between the two flanks'
/// inward normals at the valley line, a penetrating node projects into neither flank. On the
/// valley `z = |x|/2` (flank normals `(∓1/2, 0, 1)/√1.25`) a node `d` below the right flank at
/// `x` has its foot on that flank for `x ≥ 0.4 d` only.
#[test]
fn below_a_valley_between_the_flank_normals_no_facet_is_chosen() {
    let (nodes, facets) = ridge(1.0);
    let d = 0.01;
    for k in 0..=20 {
        let x = 0.4 * d * f64::from(k) / 20.0;
        let node = Vec3::new(x, 2.2, x / 2.0 - d);
        let gap = choose_on(&nodes, &facets, node);
        if x < 0.4 * d * (1.0 - 1e-9) {
            assert_eq!(gap, None, "x = {x}: inside the wedge");
        } else {
            assert!(gap.is_some_and(|g| g < 0.0), "x = {x}: {gap:?}");
        }
    }
}

#[test]
fn assembled_penalty_terms_match_finite_differences() {
    let (mut nodes, facets) = grid(2, 1.0);
    // Perturb the master so the facets are not coplanar, then add three slave nodes.
    for (n, p) in nodes.iter_mut().enumerate() {
        p.z = 0.05 * ((n * 7 % 5) as f64 - 2.0);
    }
    let base = u32::try_from(nodes.len()).unwrap();
    nodes.extend([
        Vec3::new(0.4, 0.3, -0.2),
        Vec3::new(1.3, 1.6, -0.15),
        Vec3::new(0.9, 1.1, 0.3),
    ]);
    let constraints: Vec<Constraint> = (0..3)
        .map(|s| {
            let f = [0usize, 5, 3][s];
            let [a, b, c] = facets[f];
            Constraint {
                nodes: [a, b, c, base + u32::try_from(s).unwrap()],
            }
        })
        .collect();
    let alpha = 1e3;
    let at =
        |x: &[f64]| -> Vec<Vec3> { x.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect() };
    let x0: Vec<f64> = nodes.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    let n = x0.len();
    let exact = assemble_penalty(&constraints, &nodes, alpha).unwrap();
    assert_eq!(exact.active, 2, "the third slave node is above its facet");
    let mut k = vec![0.0; n * n];
    for &(r, c, v) in &exact.triplets {
        k[r * n + c] += v;
    }
    let h = 1e-6;
    let mut worst_f: f64 = 0.0;
    let mut worst_k: f64 = 0.0;
    for d in 0..n {
        let (mut xp, mut xm) = (x0.clone(), x0.clone());
        xp[d] += h;
        xm[d] -= h;
        let (p, m) = (
            assemble_penalty(&constraints, &at(&xp), alpha).unwrap(),
            assemble_penalty(&constraints, &at(&xm), alpha).unwrap(),
        );
        worst_f = worst_f.max(((p.energy - m.energy) / (2.0 * h) - exact.force[d]).abs());
        for r in 0..n {
            worst_k = worst_k.max(((p.force[r] - m.force[r]) / (2.0 * h) - k[r * n + d]).abs());
        }
    }
    let f_scale = exact.force.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let k_scale = k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(
        worst_f <= 1e-6 * f_scale,
        "force error {worst_f:e} of {f_scale:e}"
    );
    assert!(
        worst_k <= 1e-6 * k_scale,
        "tangent error {worst_k:e} of {k_scale:e}"
    );
    // The tangent is symmetric.
    for r in 0..n {
        for c in 0..n {
            assert!((k[r * n + c] - k[c * n + r]).abs() <= 1e-12 * k_scale);
        }
    }
}

/// A constraint naming a node without a position is an error that names the node, and a slave node
/// without a position a panic that names it, not an index out of bounds.
#[test]
fn nodes_without_positions_are_named() {
    let (nodes, facets) = grid(2, 1.0);
    let missing = u32::try_from(nodes.len()).unwrap() + 3;
    let [a, b, c] = facets[0];
    let constraints = [Constraint {
        nodes: [a, b, c, missing],
    }];
    let err = assemble_penalty(&constraints, &nodes, 1e3).unwrap_err();
    assert_eq!(
        err,
        GeometryError::MissingNode {
            node: missing,
            nodes: nodes.len()
        }
    );
    assert!(
        err.to_string().contains(&format!("node {missing}")),
        "{err}"
    );
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let panic = std::panic::catch_unwind(|| choose_facet(&surface, &bvh, &nodes, missing, 0.5))
        .unwrap_err();
    let message = panic.downcast_ref::<String>().expect("a message");
    assert!(
        message.contains(&format!("slave node {missing} has no position")),
        "{message}"
    );
}

/// The rule applied to every facet within `radius` (what `choose_facet` did before it searched a
/// growing reach): the reference for the search.
fn choose_among_all(
    surface: &Surface,
    bvh: &Bvh,
    positions: &[Vec3],
    slave: u32,
    radius: f64,
) -> Option<(u32, f64)> {
    choose_facing_among_all(surface, bvh, positions, (slave, None), radius)
}

/// [`choose_among_all`] among the facets whose normal `W` is within 60° of `−n`, when `n` is
/// given.
fn choose_facing_among_all(
    surface: &Surface,
    bvh: &Bvh,
    positions: &[Vec3],
    (slave, facing): (u32, Option<Vec3>),
    radius: f64,
) -> Option<(u32, f64)> {
    let x = positions[slave as usize];
    let query = tricontact::search::Query {
        point: x,
        exclude: Some(slave),
    };
    let mut best: Option<(u32, f64)> = None;
    for hit in bvh.within(surface, &query, radius) {
        let [a, b, c] = surface.corners(hit.facet, positions);
        let Ok(pair) = tricontact::NodeFacet::new(a, b, c, x) else {
            continue;
        };
        if !pair
            .projection
            .is_inside(tricontact::contact::PROJECTION_TOLERANCE)
        {
            continue;
        }
        if facing.is_some_and(|n| pair.facet.normal().dot(&n.normalize()) >= -0.5) {
            continue;
        }
        let g = pair.gap();
        if best.is_none_or(|(f, b)| g.abs() < b.abs() || (g.abs() == b.abs() && hit.facet < f)) {
            best = Some((hit.facet, g));
        }
    }
    best
}

/// The search over a growing reach chooses what the rule chooses among all facets within the
/// radius, facet and gap bit for bit: on a graded, bumpy master (cells from 0.01 to 0.39, the
/// radius its longest edge), a convex ridge, a valley, a torus (with a part of the slave nodes on
/// it: self-contact) and two stacked plates, for nodes above, below and beyond the master, on its
/// vertices and edges.
/// Enough of them are answered beyond their closest facet, and enough find none, for the
/// reach's growth to be exercised.
#[test]
fn the_growing_reach_chooses_what_all_facets_within_the_radius_choose() {
    let mut r = tricontact::search::scenes::uniform(17);
    // Graded and bumpy: coordinates x = 4 s², s uniform in [0, 1].
    let n = 20u32;
    let at = |i: u32| 4.0 * (f64::from(i) / f64::from(n)).powi(2);
    let mut graded = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (at(i), at(j));
            graded.push(Vec3::new(x, y, 0.02 * (3.0 * x).sin() * (2.0 * y).cos()));
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let mut graded_facets = Vec::new();
    for j in 0..n {
        for i in 0..n {
            graded_facets.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            graded_facets.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let (torus_nodes, torus_facets) = tricontact::search::scenes::torus(24, 12, 2.0, 0.6);
    // A small plate 0.4 above a large one: beside the small plate, the closest facet is one of
    // its edges, which the node does not project into, and the facet chosen lies below, farther.
    let (mut stacked, mut stacked_facets) = grid(4, 0.25);
    let (low, low_facets) = grid(6, 1.0);
    let shift = u32::try_from(stacked.len()).unwrap();
    stacked.extend(low.iter().map(|p| p + Vec3::new(-2.5, -2.5, -0.4)));
    stacked_facets.extend(low_facets.iter().map(|f| f.map(|v| v + shift)));
    let scenes = [
        (graded, graded_facets),
        ridge(-1.0),
        ridge(1.0),
        (torus_nodes, torus_facets),
        (stacked, stacked_facets),
    ];
    let (mut compared, mut beyond_nearest, mut none) = (0, 0, 0);
    for (scene, (nodes, facets)) in scenes.iter().enumerate() {
        let longest = facets
            .iter()
            .flat_map(|f| {
                (0..3).map(move |e| (nodes[f[e] as usize] - nodes[f[(e + 1) % 3] as usize]).norm())
            })
            .fold(0.0, f64::max);
        let lo = nodes
            .iter()
            .fold(Vec3::repeat(f64::INFINITY), |a, p| a.inf(p));
        let hi = nodes
            .iter()
            .fold(Vec3::repeat(f64::NEG_INFINITY), |a, p| a.sup(p));
        let mut points: Vec<Vec3> = (0..600)
            .map(|_| {
                let t = Vec3::new(1.4 * r() - 0.2, 1.4 * r() - 0.2, r());
                let z = lo.z + (hi.z - lo.z) * t.z + longest * (r() - 0.6);
                Vec3::new(lo.x + (hi.x - lo.x) * t.x, lo.y + (hi.y - lo.y) * t.y, z)
            })
            .collect();
        // On vertices and edge midpoints, just inside.
        for f in facets.iter().step_by(7) {
            let [a, b, _] = f.map(|v| nodes[v as usize]);
            points.push(a - Vec3::new(0.0, 0.0, 1e-3));
            points.push(0.5 * (a + b) - Vec3::new(0.0, 0.0, 1e-3));
        }
        // The torus's slave nodes include some of its own nodes (self-contact).
        let own = if scene == 3 { nodes.len() / 3 } else { 0 };
        // Over the small plate and around it, for the stacked plates.
        if scene == 4 {
            points.truncate(0);
            points.extend(
                (0..600).map(|_| Vec3::new(2.0 * r() - 0.5, 2.0 * r() - 0.5, 0.6 * r() - 0.3)),
            );
        }
        let mut all = nodes.clone();
        all.extend(points);
        let surface = Surface::new(facets.clone(), all.len()).unwrap();
        let bvh = Bvh::build(&surface, &all, 0.0).unwrap();
        let slaves = (0..own).step_by(3).chain(nodes.len()..all.len());
        for slave in slaves {
            let slave = u32::try_from(slave).unwrap();
            let got = choose_facet(&surface, &bvh, &all, slave, longest);
            let want = choose_among_all(&surface, &bvh, &all, slave, longest);
            assert_eq!(
                got.map(|(f, p)| (f, p.gap().to_bits())),
                want.map(|(f, g)| (f, g.to_bits())),
                "scene {scene}, slave {slave} at {:?}",
                all[slave as usize]
            );
            compared += 1;
            // Without a finite positive radius there is no reach to grow: every facet (∞), or
            // those at distance 0, as the rule has them.
            if slave % 5 == 0 {
                for radius in [f64::INFINITY, 0.0] {
                    let got = choose_facet(&surface, &bvh, &all, slave, radius);
                    let want = choose_among_all(&surface, &bvh, &all, slave, radius);
                    assert_eq!(
                        got.map(|(f, p)| (f, p.gap().to_bits())),
                        want.map(|(f, g)| (f, g.to_bits())),
                        "scene {scene}, slave {slave}, radius {radius}"
                    );
                }
            }
            let query = tricontact::search::Query {
                point: all[slave as usize],
                exclude: Some(slave),
            };
            match (want, bvh.closest(&surface, &query, longest)) {
                (Some((_, g)), Some(near)) if g.abs() > near.closest.distance + 1e-6 => {
                    beyond_nearest += 1;
                }
                (None, _) => none += 1,
                _ => {}
            }
        }
    }
    assert!(
        compared > 3000 && beyond_nearest > 100 && none > 100,
        "{compared} compared, {beyond_nearest} beyond their closest facet, {none} with none"
    );
}

/// Area-weighted normals at the nodes of `facets` (zero at a node of none).
fn node_normals(nodes: &[Vec3], facets: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::zeros(); nodes.len()];
    for f in facets {
        let [a, b, c] = f.map(|v| nodes[v as usize]);
        let w = (b - a).cross(&(c - a));
        for &v in f {
            normals[v as usize] += w;
        }
    }
    normals
}

/// Self-contact: among the facets facing the node's own surface, the search chooses what the rule
/// chooses among all facets within the radius, bit for bit: the nodes of a torus and of two plates
/// facing each other (one surface), and points off them, with their surfaces' normals (or, off
/// the surface, random directions). The normal must matter: for many nodes the rule without it
/// chooses a facet of the node's own side (behind which a node of the torus's convex outer side
/// lies), and the facing rule another facet or none.
#[test]
fn self_contact_chooses_among_the_facing_facets_as_the_rule_does() {
    let mut r = tricontact::search::scenes::uniform(29);
    let (torus_nodes, torus_facets) = tricontact::search::scenes::torus(24, 12, 2.0, 0.6);
    // Two plates 0.3 apart, facing each other: the lower one's normal up, the upper one's down.
    let (mut plates, mut plate_facets) = grid(6, 1.0);
    let (upper, upper_facets) = grid(8, 0.8);
    let shift = u32::try_from(plates.len()).unwrap();
    plates.extend(upper.iter().map(|p| p + Vec3::new(-0.5, -0.3, 0.3)));
    plate_facets.extend(
        upper_facets
            .iter()
            .map(|f| [f[0], f[2], f[1]].map(|v| v + shift)),
    );
    let (mut compared, mut differ, mut found) = (0, 0, 0);
    for (nodes, facets) in [(torus_nodes, torus_facets), (plates, plate_facets)] {
        let longest = facets
            .iter()
            .flat_map(|f| {
                (0..3).map(|e| (nodes[f[e] as usize] - nodes[f[(e + 1) % 3] as usize]).norm())
            })
            .fold(0.0, f64::max);
        let mut all = nodes.clone();
        // Points near the surface's nodes, off it.
        all.extend(
            nodes
                .iter()
                .step_by(3)
                .map(|p| p + Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * longest),
        );
        let mut normals = node_normals(&all, &facets);
        for n in &mut normals[nodes.len()..] {
            *n = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5);
        }
        let surface = Surface::new(facets.clone(), all.len()).unwrap();
        let bvh = Bvh::build(&surface, &all, 0.0).unwrap();
        for (slave, &n) in normals.iter().enumerate() {
            let slave = u32::try_from(slave).unwrap();
            let got = choose_facet_facing(&surface, &bvh, &all, slave, longest, n);
            let want = choose_facing_among_all(&surface, &bvh, &all, (slave, Some(n)), longest);
            assert_eq!(
                got.map(|(f, p)| (f, p.gap().to_bits())),
                want.map(|(f, g)| (f, g.to_bits())),
                "slave {slave} at {:?}, facing {n:?}",
                all[slave as usize]
            );
            compared += 1;
            found += usize::from(got.is_some());
            let plain = choose_facet(&surface, &bvh, &all, slave, longest).map(|(f, _)| f);
            differ += usize::from(plain != got.map(|(f, _)| f));
        }
        // A zero normal faces nothing.
        assert_eq!(
            choose_facet_facing(&surface, &bvh, &all, 0, longest, Vec3::zeros()).map(|(f, _)| f),
            None
        );
    }
    assert!(
        compared > 500 && differ > 40 && found > 100,
        "{compared} compared, {differ} differ from the rule without normals, {found} found a facet"
    );
}
