//! The contact search against brute force: random and structured scenes, ties on shared edges and
//! vertices, degenerate facets, self-contact exclusion, refit/rebuild, hints, packets, incremental
//! search from neighbourhood lists, threads.

use proptest::prelude::*;
use tricontact::search::scenes::{self, grid, torus};
use tricontact::search::{
    Bvh, Hit, MAX_FACETS, Neighbourhoods, Query, Surface, SurfaceError, Update,
    brute_force_closest, measure,
};
use tricontact::{Vec3, distance_squared_to_triangle};

fn same(a: Option<Hit>, b: Option<Hit>) -> Result<(), TestCaseError> {
    match (a, b) {
        (None, None) => Ok(()),
        (Some(a), Some(b)) => {
            prop_assert_eq!(a.facet, b.facet);
            let (da, db) = (a.closest.distance, b.closest.distance);
            prop_assert!((da - db).abs() <= 1e-12 * da.max(db).max(f64::MIN_POSITIVE));
            prop_assert_eq!(a.closest.feature, b.closest.feature);
            Ok(())
        }
        (a, b) => Err(TestCaseError::fail(format!("{a:?} vs {b:?}"))),
    }
}

/// A triangle soup of `n` random facets in the unit cube (some nearly degenerate).
fn soup(n: usize, seed: u64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut r = scenes::uniform(seed);
    let mut nodes = Vec::new();
    let mut facets = Vec::new();
    for f in 0..n {
        let c = Vec3::new(r(), r(), r());
        for _ in 0..3 {
            nodes.push(c + 0.1 * Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5));
        }
        let b = u32::try_from(3 * f).unwrap();
        facets.push([b, b + 1, b + 2]);
    }
    (nodes, facets)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_soup_matches_brute_force(seed in any::<u64>(), n in 1usize..400, inflation in 0.0..0.05f64) {
        let (nodes, facets) = soup(n, seed);
        let surface = Surface::new(facets, nodes.len()).unwrap();
        let bvh = Bvh::build(&surface, &nodes, inflation).unwrap();
        let mut r = scenes::uniform(seed ^ 0x5555);
        for _ in 0..50 {
            let q = Query::point(Vec3::new(1.4 * r() - 0.2, 1.4 * r() - 0.2, 1.4 * r() - 0.2));
            for max in [f64::INFINITY, 0.05] {
                same(bvh.closest(&surface, &q, max), brute_force_closest(&surface, &nodes, &q, max))?;
            }
            let within = bvh.within(&surface, &q, 0.1);
            prop_assert_eq!(within, brute_force_within(&surface, &nodes, &q, 0.1));
        }
    }
}

/// The tree's extent is the diagonal of its facets' box, up to the boxes' rounding to `f32`
/// (outwards), whether the root is a node or a single leaf; `0` for a surface without a valid
/// facet.
#[test]
fn the_extent_is_the_diagonal_of_the_facets_box() {
    for (n, h) in [(8, 0.5), (1, 3.0)] {
        let (nodes, facets) = grid(n, h);
        let surface = Surface::new(facets, nodes.len()).unwrap();
        let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
        let diagonal = f64::from(n) * h * 2f64.sqrt();
        let extent = bvh.extent();
        assert!(
            extent >= diagonal * (1.0 - 1e-12) && extent <= diagonal * (1.0 + 1e-6),
            "{n} cells: {extent} for {diagonal}"
        );
    }
    let collinear = [
        Vec3::zeros(),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
    ];
    let surface = Surface::new(vec![[0, 1, 2]], 3).unwrap();
    assert_eq!(Bvh::build(&surface, &collinear, 0.0).unwrap().extent(), 0.0);
}

#[test]
fn grid_ties_on_edges_and_vertices_match_brute_force() {
    let (nodes, facets) = grid(8, 0.5);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let (mut checked, mut at_radius) = (0, 0);
    // Every vertex, every edge midpoint and the facet centres, on the plane and above/below it.
    for j in 0..=16 {
        for i in 0..=16 {
            for z in [0.0, 0.3, -0.2] {
                let q = Query::point(Vec3::new(f64::from(i) * 0.25, f64::from(j) * 0.25, z));
                let tree = bvh.closest(&surface, &q, f64::INFINITY);
                same(
                    tree,
                    brute_force_closest(&surface, &nodes, &q, f64::INFINITY),
                )
                .unwrap();
                // The winner has the lowest index among all facets at the same distance.
                let d2 = |f: u32| {
                    let [a, b, c] = surface.corners(f, &nodes);
                    distance_squared_to_triangle(&a, &b, &c, &q.point)
                };
                let best = d2(tree.unwrap().facet);
                let lowest = (0..surface.len() as u32).find(|&f| d2(f) == best).unwrap();
                assert_eq!(tree.unwrap().facet, lowest);
                // Every facet within a radius, those exactly at it included (the points 0.3 off
                // the plane, radius 0.3; the vertices and edge midpoints, radius 0.25).
                for radius in [0.3, 0.25] {
                    let near = bvh.within(&surface, &q, radius);
                    assert_eq!(near, brute_force_within(&surface, &nodes, &q, radius));
                    at_radius += near
                        .iter()
                        .filter(|h| d2(h.facet) == radius * radius)
                        .count();
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 17 * 17 * 3);
    assert!(at_radius > 1000, "{at_radius} facets exactly at the radius");
}

#[test]
fn degenerate_facets_are_skipped_and_reported() {
    let (mut nodes, facets) = grid(4, 1.0);
    // Collapse facet 5's third node onto its first: nodes shared with other facets move too, so
    // move a copy instead: append three collinear nodes as an extra facet.
    let base = u32::try_from(nodes.len()).unwrap();
    nodes.extend([
        Vec3::new(1.0, 1.0, 0.1),
        Vec3::new(2.0, 2.0, 0.1),
        Vec3::new(3.0, 3.0, 0.1),
    ]);
    // The degenerate facet last, then first (the build sorts it out of the tree wherever it is).
    for at_front in [false, true] {
        let mut facets = facets.clone();
        let degenerate = if at_front {
            facets.insert(0, [base, base + 1, base + 2]);
            0
        } else {
            facets.push([base, base + 1, base + 2]);
            u32::try_from(facets.len() - 1).unwrap()
        };
        let surface = Surface::new(facets, nodes.len()).unwrap();
        let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
        assert_eq!(bvh.degenerate_facets(), vec![degenerate]);
        // A point right on the degenerate facet's line gets a regular facet.
        let q = Query::point(Vec3::new(1.5, 1.5, 0.1));
        let hit = bvh.closest(&surface, &q, f64::INFINITY).unwrap();
        assert_ne!(hit.facet, degenerate);
        same(
            Some(hit),
            brute_force_closest(&surface, &nodes, &q, f64::INFINITY),
        )
        .unwrap();
        // Every regular facet is in the tree: a point just above its centroid gets the answer
        // brute force gives (a facet left out would lose it to a neighbour).
        for f in (0..surface.len()).map(|f| u32::try_from(f).unwrap()) {
            if f == degenerate {
                continue;
            }
            let [a, b, c] = surface.corners(f, &nodes);
            let q = Query::point((a + b + c) / 3.0 + Vec3::new(0.0, 0.0, 1e-3));
            let hit = bvh.closest(&surface, &q, f64::INFINITY).unwrap();
            same(
                Some(hit),
                brute_force_closest(&surface, &nodes, &q, f64::INFINITY),
            )
            .unwrap();
        }
    }
}

#[test]
fn self_contact_never_pairs_a_node_with_its_own_facets() {
    let (nodes, facets) = torus(24, 12, 2.0, 0.5);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    for (n, p) in nodes.iter().enumerate() {
        let q = Query {
            point: *p,
            exclude: Some(u32::try_from(n).unwrap()),
        };
        let hit = bvh.closest(&surface, &q, f64::INFINITY).unwrap();
        assert!(!surface.facets()[hit.facet as usize].contains(&q.exclude.unwrap()));
        same(
            Some(hit),
            brute_force_closest(&surface, &nodes, &q, f64::INFINITY),
        )
        .unwrap();
        assert!(hit.closest.distance > 0.0);
    }
}

/// Query points within ±2 element sizes `h` of the surface, in facet order.
fn near_surface(nodes: &[Vec3], surface: &Surface, seed: u64, h: f64) -> Vec<Query> {
    scenes::near_surface(nodes, surface.facets(), 2.0 * h, seed)
        .into_iter()
        .map(Query::point)
        .collect()
}

/// A small deformation of the torus (motion about a quarter of an element): every query is
/// certified by its neighbourhood list, no tree update is needed, and all answers equal brute force
/// at the new positions.
#[test]
fn torus_queries_refit_and_incremental_search_match_brute_force() {
    let (nodes, facets) = torus(60, 30, 2.0, 0.6);
    let h = std::f64::consts::TAU * 0.6 / 30.0;
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let mut bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let queries = near_surface(&nodes, &surface, 7, h);
    let first = bvh.closest_all(&surface, &queries, f64::INFINITY);
    for (q, hit) in queries.iter().zip(&first).step_by(7) {
        same(
            *hit,
            brute_force_closest(&surface, &nodes, q, f64::INFINITY),
        )
        .unwrap();
    }
    let lists = Neighbourhoods::new(&bvh, &surface, &nodes, &queries, 0.6 * h).unwrap();
    // A small deformation: a wave of amplitude 0.2 h along the normal and a small twist.
    let moved: Vec<Vec3> = nodes
        .iter()
        .map(|p| {
            let wave = 0.2 * h * (3.0 * p.x).sin();
            let twist = 0.01 * p.z;
            Vec3::new(
                p.x * twist.cos() - p.y * twist.sin(),
                p.x * twist.sin() + p.y * twist.cos(),
                p.z + wave,
            )
        })
        .collect();
    assert!(lists.motion(&moved) < 0.25 * h);
    let (incremental, stats) = lists
        .closest_all(&mut bvh, &surface, &moved, &queries, f64::INFINITY)
        .unwrap();
    for (q, hit) in queries.iter().zip(&incremental) {
        same(
            *hit,
            brute_force_closest(&surface, &moved, q, f64::INFINITY),
        )
        .unwrap();
    }
    assert_eq!(stats.queries, queries.len());
    assert!(stats.fallbacks * 100 < stats.queries, "{stats:?}");
    assert!(stats.measured < 10 * stats.queries, "{stats:?}");
    // Into a reused buffer holding the answers at the old positions: every entry is rewritten.
    let mut buffer = first.clone();
    let stats_into = lists
        .closest_all_into(
            &mut bvh,
            &surface,
            &moved,
            &queries,
            f64::INFINITY,
            &mut buffer,
        )
        .unwrap();
    assert_eq!(
        (buffer.as_slice(), stats_into),
        (incremental.as_slice(), stats)
    );
    assert!(matches!(
        lists.closest_all_into(&mut bvh, &surface, &moved, &queries, 1.0, &mut buffer[1..]),
        Err(SurfaceError::AnswerCount { answers, queries: q }) if answers + 1 == q
    ));
    // The lists brought to the new positions once (the motions and the longest), then answering
    // twice, with a second `Moved` alive beside the first (its own motions' buffer): the same
    // answers and counts as the calls that do both at once.
    let at = lists.moved(&surface, &moved).unwrap();
    assert_eq!(at.motion().to_bits(), lists.motion(&moved).to_bits());
    let at_start = lists.moved(&surface, &nodes).unwrap();
    assert_eq!(at_start.motion(), 0.0);
    for _ in 0..2 {
        let mut again = vec![None; queries.len()];
        let stats_again = at
            .closest_all_into(&mut bvh, &queries, f64::INFINITY, &mut again)
            .unwrap();
        assert_eq!(
            (again.as_slice(), stats_again),
            (incremental.as_slice(), stats)
        );
    }
    assert_eq!(
        at_start
            .closest_all(&mut bvh, &queries, f64::INFINITY)
            .unwrap()
            .0,
        first
    );
    assert!(matches!(
        at.closest_all(&mut bvh, &queries[1..], 1.0),
        Err(SurfaceError::QueryCount { expected, given }) if expected == given + 1
    ));
    assert!(matches!(
        lists.moved(&surface, &moved[1..]),
        Err(SurfaceError::PositionCount { .. })
    ));
    drop((at, at_start));
    assert_eq!(bvh.update(&surface, &moved).unwrap(), Update::Refit);
    assert_eq!(
        bvh.closest_all(&surface, &queries, f64::INFINITY),
        incremental
    );
    // The tree into the same buffer, now holding the incremental answers, with a search distance.
    let limited = bvh.closest_all(&surface, &queries, 0.5 * h);
    bvh.closest_all_into(&surface, &queries, 0.5 * h, &mut buffer)
        .unwrap();
    assert_eq!(buffer, limited);
    assert!(limited.iter().any(Option::is_none) && limited.iter().any(Option::is_some));
    let err = bvh
        .closest_all_into(&surface, &queries, 1.0, &mut buffer[..3])
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "the answer buffer holds 3 entries for {} queries",
            queries.len()
        )
    );
    // A large motion (the torus swollen by half) degrades the refit: the tree is rebuilt.
    let swollen: Vec<Vec3> = nodes
        .iter()
        .map(|p| Vec3::new(p.x * 3.0, p.y * 3.0, p.z * 0.3))
        .collect();
    assert_eq!(bvh.update(&surface, &swollen).unwrap(), Update::Rebuilt);
    for q in queries.iter().step_by(13) {
        same(
            bvh.closest(&surface, q, f64::INFINITY),
            brute_force_closest(&surface, &swollen, q, f64::INFINITY),
        )
        .unwrap();
    }
}

/// 72 000 facets: large enough for the parallel build of the tree's top levels.
#[test]
fn results_do_not_depend_on_thread_count() {
    let (nodes, facets) = torus(240, 150, 2.0, 0.6);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let queries = near_surface(&nodes, &surface, 3, 0.05);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let bvh = Bvh::build(&surface, &nodes, 0.01).unwrap();
            bvh.closest_all(&surface, &queries, f64::INFINITY)
        })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    for (q, hit) in queries.iter().zip(&one).step_by(997) {
        same(
            *hit,
            brute_force_closest(&surface, &nodes, q, f64::INFINITY),
        )
        .unwrap();
    }
}

#[test]
fn bad_surfaces_are_errors() {
    assert!(matches!(
        Surface::new(vec![[0, 1, 5]], 3),
        Err(SurfaceError::NodeOutOfRange {
            facet: 0,
            node: 5,
            nodes: 3
        })
    ));
    assert!(matches!(
        Surface::new(vec![[0, 1, 1]], 3),
        Err(SurfaceError::RepeatedNode { .. })
    ));
    let surface = Surface::new(vec![[0, 1, 2]], 3).unwrap();
    assert!(matches!(
        Bvh::build(&surface, &[Vec3::zeros(); 2], 0.0),
        Err(SurfaceError::PositionCount {
            expected: 3,
            given: 2
        })
    ));
    // A surface with more facets than the search indexes is refused before its facets are read
    // (1.6 GB of zeros, asked of the system and never written), and the message names the limit.
    let too_many = Surface::new(vec![[0u32; 3]; MAX_FACETS + 1], 3);
    assert!(matches!(
        too_many,
        Err(SurfaceError::TooLarge { facets }) if facets == MAX_FACETS + 1
    ));
    let message = too_many.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(message.contains(&MAX_FACETS.to_string()), "{message}");
    // A node count no 32-bit index reaches is refused, not allocated (it aborted or overflowed).
    for nodes in [usize::MAX, 1 << 40] {
        assert!(matches!(
            Surface::new(vec![], nodes),
            Err(SurfaceError::TooManyNodes { nodes: n }) if n == nodes
        ));
    }
    // Negative or NaN lengths are refused: the inflation, the skin.
    for bad in [-0.05, f64::NAN] {
        let e = Bvh::build(&surface, &[Vec3::zeros(); 3], bad).err();
        assert!(
            matches!(
                e,
                Some(SurfaceError::BadLength {
                    name: "inflation",
                    ..
                })
            ),
            "{e:?}"
        );
    }
    let bvh = Bvh::build(&surface, &[Vec3::zeros(); 3], 0.0).unwrap();
    for bad in [-0.05, f64::NAN, f64::INFINITY] {
        let e = Neighbourhoods::new(&bvh, &surface, &[Vec3::zeros(); 3], &[], bad).err();
        assert!(
            matches!(e, Some(SurfaceError::BadLength { name: "skin", .. })),
            "{e:?}"
        );
    }
    // An empty surface answers nothing.
    let empty = Surface::new(vec![], 0).unwrap();
    let bvh = Bvh::build(&empty, &[], 0.0).unwrap();
    assert!(
        bvh.closest(&empty, &Query::point(Vec3::zeros()), f64::INFINITY)
            .is_none()
    );
}

/// Every hint — the answer, a neighbour, a facet far away, a degenerate facet, an excluded facet,
/// an index out of range — gives the unhinted (brute-force) answer, ties included.
#[test]
fn hints_never_change_the_answer() {
    let (mut nodes, mut facets) = grid(6, 0.5);
    // A degenerate facet (three collinear nodes) above the grid.
    let base = u32::try_from(nodes.len()).unwrap();
    nodes.extend([
        Vec3::new(0.5, 0.5, 0.2),
        Vec3::new(1.0, 1.0, 0.2),
        Vec3::new(1.5, 1.5, 0.2),
    ]);
    facets.push([base, base + 1, base + 2]);
    let degenerate = u32::try_from(facets.len() - 1).unwrap();
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let far = 0;
    let mut checked = 0;
    for j in 0..=12 {
        for i in 0..=12 {
            for z in [0.0, 0.4, -0.1] {
                let point = Vec3::new(f64::from(i) * 0.25, f64::from(j) * 0.25, z);
                let node = u32::try_from(j / 2 * 7 + i / 2).unwrap();
                for q in [
                    Query::point(point),
                    Query {
                        point,
                        exclude: Some(node),
                    },
                ] {
                    for max in [f64::INFINITY, 0.2] {
                        let reference = brute_force_closest(&surface, &nodes, &q, max);
                        let answer = reference.map(|h| h.facet);
                        let hints = [
                            answer,
                            answer.map(|f| f ^ 1),
                            Some(far),
                            Some(degenerate),
                            Some(
                                surface
                                    .facets()
                                    .iter()
                                    .position(|f| f.contains(&node))
                                    .unwrap() as u32,
                            ),
                            Some(u32::MAX),
                            None,
                        ];
                        for hint in hints {
                            same(bvh.closest_with_hint(&surface, &q, hint, max), reference)
                                .unwrap();
                            checked += 1;
                        }
                    }
                }
            }
        }
    }
    assert_eq!(checked, 13 * 13 * 3 * 2 * 2 * 7);
}

/// Chunked hinting in `closest_all` leaves every answer as the unhinted query gives it, in
/// coherent and in shuffled order, with and without a distance limit.
#[test]
fn closest_all_with_hints_matches_single_queries() {
    let (nodes, facets) = soup(3000, 9);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let mut r = scenes::uniform(4);
    let queries: Vec<Query> = (0..2000)
        .map(|_| Query::point(Vec3::new(r(), r(), r())))
        .collect();
    for max in [f64::INFINITY, 0.02] {
        let all = bvh.closest_all(&surface, &queries, max);
        for (q, hit) in queries.iter().zip(&all) {
            same(*hit, bvh.closest(&surface, q, max)).unwrap();
        }
        for (q, hit) in queries.iter().zip(&all).step_by(10) {
            same(*hit, brute_force_closest(&surface, &nodes, q, max)).unwrap();
        }
    }
}

/// Coherent batches go through packets (one gathering for 16 consecutive queries): on a tie grid,
/// queries in row order on vertices, edges and faces at mixed heights, with a far query now and
/// then (its answer lies beyond the gathering radius: a fallback, then a large radius), with and
/// without self-exclusion and a search distance, all equal brute force.
#[test]
fn packets_match_brute_force_on_ties_and_fallbacks() {
    let (nodes, facets) = grid(16, 0.5);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let heights = [0.0, 0.3, -0.2, 0.05];
    let mut points = Vec::new();
    for j in 0..=32 {
        for i in 0..=64 {
            let k = points.len();
            let z = if k % 37 == 36 { 3.0 } else { heights[k % 4] };
            points.push(Vec3::new(f64::from(i) * 0.125, f64::from(j) * 0.25, z));
        }
    }
    let node_at = |p: &Vec3| {
        let (i, j) = ((p.x / 0.5).round(), (p.y / 0.5).round());
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let n = (j as u32) * 17 + i as u32;
        n
    };
    for exclude in [false, true] {
        let queries: Vec<Query> = points
            .iter()
            .map(|p| Query {
                point: *p,
                exclude: exclude.then(|| node_at(p)),
            })
            .collect();
        for max in [f64::INFINITY, 0.25] {
            let all = bvh.closest_all(&surface, &queries, max);
            for (q, hit) in queries.iter().zip(&all) {
                same(*hit, brute_force_closest(&surface, &nodes, q, max)).unwrap();
            }
        }
    }
}

/// Packets on a random soup, with queries sorted by cells so that consecutive ones are close.
#[test]
fn packets_match_brute_force_on_a_sorted_soup() {
    let (nodes, facets) = soup(4000, 21);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let mut r = scenes::uniform(8);
    let mut points: Vec<Vec3> = (0..3000).map(|_| Vec3::new(r(), r(), 0.2 * r())).collect();
    // By cells of 0.1 × 0.1: 16 consecutive points lie in one or two cells.
    let cell = |p: &Vec3| ((10.0 * p.y).floor(), (10.0 * p.x).floor());
    points.sort_by(|a, b| cell(a).partial_cmp(&cell(b)).unwrap());
    let queries: Vec<Query> = points.into_iter().map(Query::point).collect();
    for max in [f64::INFINITY, 0.03] {
        let all = bvh.closest_all(&surface, &queries, max);
        for (q, hit) in queries.iter().zip(&all).step_by(3) {
            same(*hit, brute_force_closest(&surface, &nodes, q, max)).unwrap();
        }
    }
}

/// Two parallel plates without a shared node: queries that move from just above the lower plate to
/// just below the upper one. A walk over facet neighbours from the lower plate would stay there;
/// the lists' certificate fails (the queries moved farther than the reach), the queries fall back
/// to the tree, which is updated once, and the answers are those of brute force.
#[test]
fn incremental_search_falls_back_when_queries_move_far() {
    let (mut nodes, mut facets) = grid(6, 0.5);
    let n = u32::try_from(nodes.len()).unwrap();
    let (upper, upper_facets) = grid(6, 0.5);
    nodes.extend(upper.iter().map(|p| p + Vec3::new(0.0, 0.0, 1.0)));
    facets.extend(upper_facets.iter().map(|f| f.map(|v| v + n)));
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let mut bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let mut r = scenes::uniform(3);
    let mut queries: Vec<Query> = (0..200)
        .map(|_| Query::point(Vec3::new(3.0 * r(), 3.0 * r(), 0.1 + 0.05 * r())))
        .collect();
    let lists = Neighbourhoods::new(&bvh, &surface, &nodes, &queries, 0.2).unwrap();
    for (k, q) in queries.iter_mut().enumerate() {
        if k % 2 == 0 {
            q.point.z += 0.75;
        }
    }
    let (hits, stats) = lists
        .closest_all(&mut bvh, &surface, &nodes, &queries, f64::INFINITY)
        .unwrap();
    for (q, hit) in queries.iter().zip(&hits) {
        same(
            *hit,
            brute_force_closest(&surface, &nodes, q, f64::INFINITY),
        )
        .unwrap();
        assert_eq!(hit.unwrap().facet >= 72, q.point.z > 0.5);
    }
    assert_eq!(stats.fallbacks, 100);
    assert_eq!(stats.update, Some(Update::Refit));
    // The same through a `Moved` made once: the same answers and fallbacks, into a buffer of the
    // right size only.
    let at = lists.moved(&surface, &nodes).unwrap();
    let mut into = vec![None; queries.len()];
    let moved_stats = at
        .closest_all_into(&mut bvh, &queries, f64::INFINITY, &mut into)
        .unwrap();
    assert_eq!((into.as_slice(), moved_stats), (hits.as_slice(), stats));
    assert!(matches!(
        at.closest_all_into(&mut bvh, &queries, 1.0, &mut into[1..]),
        Err(SurfaceError::AnswerCount { answers, queries: q }) if answers + 1 == q
    ));
    // Back where the lists were made: every query is certified, the tree is not touched.
    for (k, q) in queries.iter_mut().enumerate() {
        if k % 2 == 0 {
            q.point.z -= 0.75;
        }
    }
    let (hits, stats) = lists
        .closest_all(&mut bvh, &surface, &nodes, &queries, f64::INFINITY)
        .unwrap();
    assert_eq!((stats.fallbacks, stats.update), (0, None));
    assert!(hits.iter().all(|h| h.unwrap().facet < 72));
}

/// Ties on vertices and edges of a grid lifted by an exactly representable offset (so ties stay
/// exact), self-exclusion, a search distance that certifies `None`, and facets turning degenerate
/// or valid between the lists and the query: all equal brute force.
#[test]
fn incremental_search_keeps_ties_exclusions_and_degenerate_facets_exact() {
    let (mut nodes, mut facets) = grid(8, 0.5);
    // Facet 128: collinear now, valid after the motion; facet 129: valid now, degenerate after.
    let base = u32::try_from(nodes.len()).unwrap();
    nodes.extend([
        Vec3::new(1.0, 1.0, 0.15),
        Vec3::new(1.5, 1.5, 0.15),
        Vec3::new(2.0, 2.0, 0.15),
        Vec3::new(3.0, 1.0, 0.15),
        Vec3::new(3.5, 1.0, 0.15),
        Vec3::new(3.25, 1.0 + 1.0 / 128.0, 0.15),
    ]);
    facets.extend([[base, base + 1, base + 2], [base + 3, base + 4, base + 5]]);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let mut bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    assert_eq!(bvh.degenerate_facets(), vec![128]);
    let check = |x: &[Vec3]| Bvh::build(&surface, x, 0.0).unwrap().degenerate_facets();
    let mut queries = Vec::new();
    for j in 0..=16 {
        for i in 0..=16 {
            let point = Vec3::new(f64::from(i) * 0.25, f64::from(j) * 0.25, 0.0);
            let node = u32::try_from(j / 2 * 9 + i / 2).unwrap();
            queries.push(Query::point(point + Vec3::new(0.0, 0.0, 0.1)));
            queries.push(Query {
                point,
                exclude: Some(node),
            });
        }
    }
    let lists = Neighbourhoods::new(&bvh, &surface, &nodes, &queries, 0.3).unwrap();
    let before = bvh.closest_all(&surface, &queries, f64::INFINITY);
    assert!(before.iter().flatten().any(|h| h.facet == 129));
    let lift = 1.0 / 1024.0;
    let mut moved: Vec<Vec3> = nodes
        .iter()
        .map(|p| p + Vec3::new(0.0, 0.0, lift))
        .collect();
    let b = base as usize;
    moved[b + 1].x += 1.0 / 64.0;
    moved[b + 5].y = moved[b + 3].y;
    assert_eq!(check(&moved), vec![129]);
    for max in [f64::INFINITY, 0.05] {
        let (hits, stats) = lists
            .closest_all(&mut bvh, &surface, &moved, &queries, max)
            .unwrap();
        for (q, hit) in queries.iter().zip(&hits) {
            same(*hit, brute_force_closest(&surface, &moved, q, max)).unwrap();
        }
        assert_eq!(hits.iter().flatten().any(|h| h.facet == 128), max > 1.0);
        assert!(hits.iter().flatten().all(|h| h.facet != 129));
        assert!(stats.fallbacks * 10 < stats.queries, "{stats:?}");
    }
    assert!(matches!(
        lists.closest_all(&mut bvh, &surface, &moved, &queries[1..], 1.0),
        Err(SurfaceError::QueryCount { .. })
    ));
    // Another surface (here: one facet fewer, then one node more) is refused, not searched.
    let fewer = Surface::new(surface.facets()[1..].to_vec(), nodes.len()).unwrap();
    let more = Surface::new(surface.facets().to_vec(), nodes.len() + 1).unwrap();
    moved.push(Vec3::zeros());
    for other in [&fewer, &more] {
        let err = lists
            .closest_all(&mut bvh, other, &moved, &queries, 1.0)
            .unwrap_err();
        assert!(matches!(err, SurfaceError::OtherSurface { .. }), "{err}");
    }
}

/// A query at NaN or infinity inside a coherent batch must not break the packet's certificate for
/// its neighbours: every other answer still equals brute force.
#[test]
fn packets_survive_non_finite_queries() {
    let (nodes, facets) = grid(16, 0.5);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let mut queries: Vec<Query> = (0..400)
        .map(|k| Query::point(Vec3::new(0.02 * f64::from(k), 1.3, 0.1)))
        .collect();
    queries[40].point.x = f64::NAN;
    queries[77].point.y = f64::INFINITY;
    let all = bvh.closest_all(&surface, &queries, f64::INFINITY);
    for (q, hit) in queries.iter().zip(&all) {
        same(
            *hit,
            brute_force_closest(&surface, &nodes, q, f64::INFINITY),
        )
        .unwrap();
    }
    // A point that is not finite has no answer.
    assert_eq!((all[40], all[77]), (None, None));
    // On a curved surface, with NaN or infinity amid a packet's queries (and the packet's box
    // wrong if it took them in: a NaN coordinate restarts a running minimum).
    let (nodes, facets) = torus(60, 30, 2.0, 0.6);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let mut queries = near_surface(&nodes, &surface, 5, 0.1);
    for k in (100..queries.len()).step_by(97) {
        queries[k].point[k % 3] = if k % 2 == 0 { f64::NAN } else { f64::INFINITY };
    }
    let all = bvh.closest_all(&surface, &queries, f64::INFINITY);
    for (k, (q, hit)) in queries.iter().zip(&all).enumerate() {
        same(
            *hit,
            brute_force_closest(&surface, &nodes, q, f64::INFINITY),
        )
        .unwrap_or_else(|e| panic!("query {k}: {e}"));
    }
}

/// A search distance that is NaN admits no facet, on every path (packets, single queries, hints,
/// the Z-ordered batch), as in brute force.
#[test]
fn a_nan_search_distance_finds_nothing() {
    // 6400 queries: enough for a shuffled batch to be answered in Z-order.
    let (nodes, facets) = torus(80, 40, 2.0, 0.6);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let queries = near_surface(&nodes, &surface, 8, 0.1);
    let mut shuffled = queries.clone();
    scenes::shuffle(&mut shuffled, 4);
    for batch in [&queries, &shuffled] {
        assert!(
            bvh.closest_all(&surface, batch, f64::NAN)
                .iter()
                .all(Option::is_none)
        );
    }
    for q in queries.iter().step_by(37) {
        assert_eq!(bvh.closest(&surface, q, f64::NAN), None);
        assert_eq!(bvh.closest_with_hint(&surface, q, Some(3), f64::NAN), None);
        assert_eq!(brute_force_closest(&surface, &nodes, q, f64::NAN), None);
    }
    // The same queries with a finite distance do find facets: the NaN is what empties them.
    assert!(
        bvh.closest_all(&surface, &queries, 1.0)
            .iter()
            .all(Option::is_some)
    );
}

/// A finite query so far from the surface that its squared distances overflow (beyond about
/// 10¹⁵⁴) still has an answer, the brute force's (every facet ties at `+∞`, so the lowest index):
/// a box at an infinite squared distance is not an empty slot.
#[test]
fn very_distant_queries_are_answered_as_by_brute_force() {
    let (nodes, facets) = torus(20, 10, 2.0, 0.6);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let far: Vec<Query> = [1e150, 1e155, 1e200, -1e300]
        .iter()
        .flat_map(|&x| {
            [
                Query::point(Vec3::new(x, 2.0, 0.0)),
                Query::point(Vec3::new(0.5, x, -x)),
            ]
        })
        .collect();
    let all = bvh.closest_all(&surface, &far, f64::INFINITY);
    for (q, batch) in far.iter().zip(all) {
        let expect = brute_force_closest(&surface, &nodes, q, f64::INFINITY);
        assert!(expect.is_some(), "{:?}", q.point);
        assert_eq!(
            bvh.closest(&surface, q, f64::INFINITY).map(|h| h.facet),
            expect.map(|h| h.facet),
            "{:?}",
            q.point
        );
        assert_eq!(
            batch.map(|h| h.facet),
            expect.map(|h| h.facet),
            "{:?}",
            q.point
        );
    }
    // The incremental search, from lists made for those queries, after no motion.
    let lists = Neighbourhoods::new(&bvh, &surface, &nodes, &far, 0.1).unwrap();
    let mut tree = bvh.clone();
    let (again, _) = lists
        .closest_all(&mut tree, &surface, &nodes, &far, f64::INFINITY)
        .unwrap();
    for (q, hit) in far.iter().zip(again) {
        let expect = brute_force_closest(&surface, &nodes, q, f64::INFINITY);
        assert_eq!(
            hit.map(|h| h.facet),
            expect.map(|h| h.facet),
            "{:?}",
            q.point
        );
    }
}

/// A large batch in random order is answered in Z-order and put back: the same answers as the
/// batch in surface order, as single queries and as brute force, with self-exclusion and a search
/// distance, for any thread count.
#[test]
fn shuffled_batches_give_the_same_answers() {
    let (nodes, facets) = torus(80, 40, 2.0, 0.6);
    let h = std::f64::consts::TAU * 0.6 / 40.0;
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    // Queries at the nodes (excluding their own facets), then near the surface.
    let mut queries: Vec<Query> = (0..nodes.len() as u32)
        .map(|n| Query {
            point: nodes[n as usize] + Vec3::new(0.0, 0.0, 0.3 * h),
            exclude: Some(n),
        })
        .collect();
    queries.extend(near_surface(&nodes, &surface, 5, h));
    let mut order: Vec<usize> = (0..queries.len()).collect();
    scenes::shuffle(&mut order, 21);
    let shuffled: Vec<Query> = order.iter().map(|&i| queries[i]).collect();
    for max in [f64::INFINITY, 0.5 * h] {
        let ordered = bvh.closest_all(&surface, &queries, max);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| bvh.closest_all(&surface, &shuffled, max))
        };
        let answers = run(1);
        assert_eq!(answers, run(2));
        for (k, &i) in order.iter().enumerate() {
            assert_eq!(answers[k], ordered[i], "query {i}");
        }
        for (q, hit) in shuffled.iter().zip(&answers).step_by(37) {
            same(*hit, bvh.closest(&surface, q, max)).unwrap();
            same(*hit, brute_force_closest(&surface, &nodes, q, max)).unwrap();
        }
    }
    // Points at NaN or infinity in a shuffled batch: no panic, and the other answers unchanged.
    let mut odd = shuffled.clone();
    odd[10].point.x = f64::NAN;
    odd[20].point.y = f64::INFINITY;
    odd[30].point = Vec3::new(f64::NEG_INFINITY, 1.0, f64::NAN);
    let answers = bvh.closest_all(&surface, &odd, f64::INFINITY);
    let reference = bvh.closest_all(&surface, &shuffled, f64::INFINITY);
    for (k, (a, b)) in answers.iter().zip(&reference).enumerate() {
        if ![10, 20, 30].contains(&k) {
            assert_eq!(a, b, "query {k}");
        }
    }
}

/// The answers of the incremental search at `moved` (queries `qs`, within `max`) against those of
/// a tree built there, answer for answer; returns the search's statistics and the answers.
fn incremental_matches_tree(
    lists: &Neighbourhoods,
    surface: &Surface,
    moved: &[Vec3],
    qs: &[Query],
    max: f64,
) -> (tricontact::search::IncrementalStats, Vec<Option<Hit>>) {
    let mut tree = Bvh::build(surface, moved, 0.0).unwrap();
    let expected = tree.closest_all(surface, qs, max);
    let (hits, stats) = lists
        .closest_all(&mut tree, surface, moved, qs, max)
        .unwrap();
    for (i, (a, b)) in hits.iter().zip(&expected).enumerate() {
        assert_eq!(a, b, "query {i}");
    }
    (stats, expected)
}

/// Every valid facet within `radius` of `q` at `positions` that `q` does not exclude ([`measure`]
/// leaves those out), by brute force, in the tree's order ([`tricontact::search::sort_hits`]): the
/// reference for `Bvh::within`.
fn brute_force_within(surface: &Surface, positions: &[Vec3], q: &Query, radius: f64) -> Vec<Hit> {
    let mut near: Vec<Hit> = (0..surface.len() as u32)
        .filter(|&f| {
            let [a, b, c] = surface.corners(f, positions);
            tricontact::Facet::new(a, b, c).is_ok()
                && distance_squared_to_triangle(&a, &b, &c, &q.point) <= radius * radius
        })
        .filter_map(|f| measure(surface, positions, f, q))
        .collect();
    tricontact::search::sort_hits(&mut near);
    near
}

/// A torus (`around` × `tube` cells, radii `major`, `minor`), query points scattered near its
/// surface, and the lists built for them with a margin of half an element.
struct ListedTorus {
    nodes: Vec<Vec3>,
    surface: Surface,
    bvh: Bvh,
    queries: Vec<Query>,
    lists: Neighbourhoods,
    h: f64,
}

fn listed_torus(around: u32, tube: u32, major: f64, minor: f64, seed: u64) -> ListedTorus {
    let (nodes, facets) = torus(around, tube, major, minor);
    let h = std::f64::consts::TAU * minor / f64::from(tube);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let queries = near_surface(&nodes, &surface, seed, h);
    let lists = Neighbourhoods::new(&bvh, &surface, &nodes, &queries, 0.5 * h).unwrap();
    ListedTorus {
        nodes,
        surface,
        bvh,
        queries,
        lists,
        h,
    }
}

/// Rigid motions of the whole torus (a translation, a rotation about its axis), with the query
/// points fixed or carried along: the first-order bound excludes the neighbouring facets that the
/// Lipschitz bound `d₀(f) − m` cannot, so the search measures little more than one facet per query
/// (1.09 after the translation and 1.11 after the rotation with the points fixed, 1.05 with them
/// carried along the translation; 1.15 and 1.26 with the facets' whole relative node motion in
/// place of their rise along the direction, and directions to 7·10⁻³), and every answer is the
/// tree's. With the Lipschitz bound alone the same lists measure 2.5 facets per query after the
/// translation.
#[test]
fn rigid_motions_are_certified_by_the_first_listed_facet() {
    let ListedTorus {
        nodes,
        surface,
        queries,
        lists,
        h,
        ..
    } = listed_torus(120, 60, 3.0, 1.0, 3);
    let shift = Vec3::new(0.02 * h, -0.01 * h, 0.015 * h);
    let angle = 0.02 * h / 4.0;
    let rotate = |p: &Vec3| {
        Vec3::new(
            p.x * angle.cos() - p.y * angle.sin(),
            p.x * angle.sin() + p.y * angle.cos(),
            p.z,
        )
    };
    let translated: Vec<Vec3> = nodes.iter().map(|p| p + shift).collect();
    let rotated: Vec<Vec3> = nodes.iter().map(rotate).collect();
    let carried: Vec<Query> = queries
        .iter()
        .map(|q| Query::point(q.point + shift))
        .collect();
    for (moved, qs) in [
        (&translated, &queries),
        (&rotated, &queries),
        (&translated, &carried),
    ] {
        let (stats, _) = incremental_matches_tree(&lists, &surface, moved, qs, f64::INFINITY);
        assert_eq!(stats.fallbacks, 0, "{stats:?}");
        assert!(
            stats.measured * 100 < 115 * stats.queries,
            "{} facets measured for {} queries",
            stats.measured,
            stats.queries
        );
    }
}

/// Node motions that are not smooth at all (each node jittered on its own, up to a fifth of an
/// element): the first-order bound's deformation term is then as large as the motion, the search
/// measures more, and every answer is still the tree's.
#[test]
fn jittered_nodes_keep_the_incremental_search_exact() {
    let ListedTorus {
        nodes,
        surface,
        queries,
        lists,
        h,
        ..
    } = listed_torus(60, 30, 2.0, 0.6, 9);
    for (seed, amplitude) in [(1, 0.01), (2, 0.03), (3, 0.1)] {
        let mut r = scenes::uniform(seed);
        let mut jitter = || amplitude * h * (2.0 * r() - 1.0);
        let moved: Vec<Vec3> = nodes
            .iter()
            .map(|p| p + Vec3::new(jitter(), jitter(), jitter()))
            .collect();
        let moving: Vec<Query> = queries
            .iter()
            .map(|q| Query::point(q.point + Vec3::new(jitter(), jitter(), jitter())))
            .collect();
        let (stats, _) = incremental_matches_tree(&lists, &surface, &moved, &moving, f64::INFINITY);
        if amplitude < 0.05 {
            assert!(stats.fallbacks * 20 < stats.queries, "{stats:?}");
        }
    }
}

/// A node at NaN: the tree leaves its facets out, and so must the incremental search (the
/// degeneracy checks are not skipped, since the motion is not below the lists' robustness); a query
/// at NaN or infinity gets the tree's answer too, and the others are unchanged.
#[test]
fn non_finite_positions_and_queries_in_the_incremental_search() {
    let ListedTorus {
        nodes,
        surface,
        bvh,
        queries,
        lists,
        ..
    } = listed_torus(40, 20, 2.0, 0.6, 4);
    let mut moved = nodes.clone();
    moved[7].y = f64::NAN;
    assert!(lists.motion(&moved).is_nan());
    let (stats, _) = incremental_matches_tree(&lists, &surface, &moved, &queries, f64::INFINITY);
    assert!(stats.fallbacks > 0, "{stats:?}");
    let mut odd = queries.clone();
    odd[3].point.x = f64::NAN;
    odd[11].point.z = f64::INFINITY;
    let mut tree = bvh.clone();
    let (hits, _) = lists
        .closest_all(&mut tree, &surface, &nodes, &odd, f64::INFINITY)
        .unwrap();
    let expected = bvh.closest_all(&surface, &odd, f64::INFINITY);
    assert_eq!(hits, expected);
    for k in [3, 11] {
        assert_eq!(hits[k], None);
        assert_eq!(bvh.closest(&surface, &odd[k], f64::INFINITY), None);
        let hinted = bvh.closest_with_hint(&surface, &odd[k], Some(0), f64::INFINITY);
        assert_eq!(hinted, None);
        assert_eq!(
            brute_force_closest(&surface, &nodes, &odd[k], f64::INFINITY),
            None
        );
        assert!(bvh.within(&surface, &odd[k], f64::INFINITY).is_empty());
    }
}

/// A query that was almost on a facet `f` (closer than the lists' direction floor, so that `f`
/// is listed without a direction) and then moves onto it: `f` is the answer now, and no bound may
/// exclude it. Two facets folded at a right angle along the `x` axis: `F` in the plane `z = 0`
/// (`y ≤ 0`), `f` in the plane `y = 0` (`z ≥ 0`); the query starts on `F`, 10⁻⁷ from the fold,
/// and ends on `f`, 5·10⁻⁸ above it, where `F` is 5·10⁻⁸ away.
#[test]
fn a_query_moving_onto_a_facet_listed_without_direction_finds_it() {
    let nodes = vec![
        Vec3::new(-1.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
    ];
    let surface = Surface::new(vec![[0, 1, 2], [1, 0, 3]], nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let before = [Query::point(Vec3::new(0.1, -1e-7, 0.0))];
    let lists = Neighbourhoods::new(&bvh, &surface, &nodes, &before, 0.01).unwrap();
    let after = [Query::point(Vec3::new(0.1, 0.0, 5e-8))];
    // The scene is as described: the query is now on `f`.
    let now = bvh.closest(&surface, &after[0], f64::INFINITY).unwrap();
    assert!(now.facet == 1 && now.closest.distance < 1e-15, "{now:?}");
    let (stats, _) = incremental_matches_tree(&lists, &surface, &nodes, &after, f64::INFINITY);
    assert_eq!(stats.queries, 1);
}

/// A bumpy grid (`2·6²` facets of size `1/6`, heights random within a third of an element, so
/// neighbouring facets meet at various angles), query points on or near its facets at distances
/// from 10⁻⁹ to 10⁻¹ (on faces, edges and vertices) and queries at its nodes (self-contact: each
/// skips its own facets and moves with its node), and node motions from 10⁻¹⁰ to 10⁻² (smooth, or
/// each node on its own) with the point queries fixed, moved as much, or moved by up to ten
/// elements, within an unbounded or a finite search distance: the incremental search gives the
/// tree's answers, bit for bit, at every scale, including the scales of the bounds' margins and
/// direction floor; and the tree, built or refitted, gives brute force's closest facet and facets
/// within a distance.
///
/// The grid is scaled by `size` and moved by `offset`, so that the same scene is searched at other
/// magnitudes of the coordinates (the tree's boxes are rounded to `f32`, the margins are relative).
fn bumpy_grid_at_every_scale(seed: u64, size: f64, offset: f64) {
    let mut r = scenes::uniform(seed);
    let h = size / 6.0;
    let (mut nodes, facets) = grid(6, h);
    for p in &mut nodes {
        p.z = (r() - 0.5) * h / 3.0;
        *p += Vec3::new(offset, -0.5 * offset, 0.25 * offset);
    }
    let surface = Surface::new(facets.clone(), nodes.len()).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let scale = |t: f64, lo: i32, hi: i32| 10f64.powf(f64::from(lo) + t * f64::from(hi - lo));
    let points = 60;
    let mut queries: Vec<Query> = (0..points)
        .map(|k| {
            let [a, b, c] = surface.corners((k * 7) % facets.len() as u32, &nodes);
            // On a face, an edge (one weight zero) or a vertex (two zero).
            let (mut u, mut v) = (r(), r());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            match k % 4 {
                1 => u = 0.0,
                2 => (u, v) = (0.0, 0.0),
                _ => {}
            }
            let on = a + (b - a) * u + (c - a) * v;
            let normal = (b - a).cross(&(c - a)).normalize();
            let sign = if k % 3 == 0 { -1.0 } else { 1.0 };
            Query::point(on + normal * (sign * size * scale(r(), -9, -1)))
        })
        .collect();
    let own = |n: u32, at: &[Vec3]| Query {
        point: at[n as usize],
        exclude: Some(n),
    };
    let node_count = u32::try_from(nodes.len()).unwrap();
    queries.extend((0..node_count).step_by(3).map(|n| own(n, &nodes)));
    let skin = h * scale(r(), -2, 0);
    let lists = Neighbourhoods::new(&bvh, &surface, &nodes, &queries, skin).unwrap();
    for round in 0..8 {
        let step = size * scale(r(), -10, -2);
        let jitter = round % 2 == 1;
        let moved: Vec<Vec3> = nodes
            .iter()
            .map(|p| {
                let local = (p - nodes[0]) / size;
                let smooth = Vec3::new(local.y, -local.x, 0.5 * local.x * local.y) * step;
                let alone = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * step;
                p + if jitter { alone } else { smooth }
            })
            .collect();
        let far = match round / 2 {
            0 => 0.0,
            1 | 3 => step * scale(r(), -1, 1),
            _ => h * scale(r(), -2, 1),
        };
        let qs: Vec<Query> = queries
            .iter()
            .map(|q| match q.exclude {
                Some(n) => own(n, &moved),
                None => Query::point(q.point + Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * far),
            })
            .collect();
        let max = if round >= 6 {
            h * scale(r(), -3, 0)
        } else {
            f64::INFINITY
        };
        let (_, expected) = incremental_matches_tree(&lists, &surface, &moved, &qs, max);
        // The tree refitted from the initial positions, against brute force: the closest facet,
        // and every facet within the search distance (or a tenth of the grid).
        let mut refitted = bvh.clone();
        refitted.update(&surface, &moved).unwrap();
        let radius = max.min(0.1 * size);
        for (q, hit) in qs.iter().zip(&expected) {
            let reference = brute_force_closest(&surface, &moved, q, max);
            same(*hit, reference).unwrap();
            same(refitted.closest(&surface, q, max), reference).unwrap();
            let near = brute_force_within(&surface, &moved, q, radius);
            assert_eq!(refitted.within(&surface, q, radius), near, "round {round}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn incremental_search_matches_the_tree_at_every_scale(
        seed in any::<u64>(),
        size in -6..4i32,
        offset in prop_oneof![Just(0.0), 1.0..1e7f64],
    ) {
        bumpy_grid_at_every_scale(seed, 10f64.powi(size), offset);
    }
}

/// A node lying on a thin but valid facet is found on it, by the tree, its lanes and a search
/// radius smaller than the facet (the kernel had put it 0.025 away, farther than a corner, and the
/// tree found nothing within 0.01).
#[test]
fn a_node_on_a_thin_facet_is_found_on_it() {
    let nodes = vec![
        Vec3::new(
            -0.225_062_636_640_116_72,
            0.344_898_195_781_236_9,
            0.117_998_977_377_701_82,
        ),
        Vec3::new(
            0.090_689_327_445_135_36,
            0.297_458_679_817_029,
            0.444_811_831_736_454_67,
        ),
        Vec3::new(
            -0.559_995_083_590_138_9,
            0.395_219_449_314_989_2,
            -0.228_666_256_326_117_73,
        ),
    ];
    let p = Vec3::new(
        -0.208_839_643_008_735_73,
        0.342_460_805_195_343_33,
        0.134_790_267_687_056_1,
    );
    let surface = Surface::new(vec![[0, 1, 2]], 3).unwrap();
    let bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    assert!(bvh.degenerate_facets().is_empty(), "a valid facet");
    let hit = bvh
        .closest(&surface, &Query::point(p), 0.01)
        .expect("found");
    assert!(hit.closest.distance < 1e-9, "{}", hit.closest.distance);
    let all = bvh.closest_all(&surface, &[Query::point(p); 9], 0.01);
    assert!(
        all.iter()
            .all(|h| h.is_some_and(|h| h.closest.distance < 1e-9))
    );
}

/// Nothing is within a negative or NaN search distance, for the tree, brute force, `within` and the
/// incremental search alike (a negative one searched as far as its magnitude; a NaN one gave the
/// incremental search answers the tree did not give).
#[test]
fn negative_and_nan_search_distances_find_nothing() {
    let (nodes, facets) = grid(4, 0.25);
    let surface = Surface::new(facets, nodes.len()).unwrap();
    let mut bvh = Bvh::build(&surface, &nodes, 0.0).unwrap();
    let queries: Vec<Query> = (0..20)
        .map(|i| Query::point(Vec3::new(0.05 * f64::from(i), 0.3, 0.02)))
        .collect();
    let lists = Neighbourhoods::new(&bvh, &surface, &nodes, &queries, 0.1).unwrap();
    for limit in [-0.05, -f64::INFINITY, f64::NAN] {
        for q in &queries {
            assert!(bvh.closest(&surface, q, limit).is_none(), "{limit}");
            assert!(brute_force_closest(&surface, &nodes, q, limit).is_none());
            assert!(bvh.within(&surface, q, limit).is_empty());
        }
        assert!(
            bvh.closest_all(&surface, &queries, limit)
                .iter()
                .all(Option::is_none)
        );
        let answers = lists
            .closest_all(&mut bvh, &surface, &nodes, &queries, limit)
            .unwrap()
            .0;
        assert!(answers.iter().all(Option::is_none), "{limit}");
    }
    // And everything is within an infinite one, by every path.
    let all = lists
        .closest_all(&mut bvh, &surface, &nodes, &queries, f64::INFINITY)
        .unwrap()
        .0;
    assert!(all.iter().all(Option::is_some));
}

/// Two bodies with surfaces of as many facets over as many nodes (the second body's nodes numbered
/// after the first's): a tree or lists made on one and handed the other are refused, with an error
/// where the call returns one and a panic naming the mix-up where it does not, instead of answers
/// naming the other body's facets. A copy of the same surface is accepted.
#[test]
fn a_tree_or_lists_refuse_another_surface_of_the_same_size() {
    let (mut nodes, facets) = grid(6, 0.5);
    let n = u32::try_from(nodes.len()).unwrap();
    let moved: Vec<Vec3> = nodes.iter().map(|x| x + Vec3::new(0.0, 0.0, 2.0)).collect();
    nodes.extend(moved);
    let second: Vec<[u32; 3]> = facets.iter().map(|f| f.map(|k| k + n)).collect();
    let one = Surface::new(facets.clone(), nodes.len()).unwrap();
    let other = Surface::new(second, nodes.len()).unwrap();
    assert_eq!(
        (one.len(), one.node_count()),
        (other.len(), other.node_count())
    );
    let copy = Surface::new(facets, nodes.len()).unwrap();
    let mut bvh = Bvh::build(&one, &nodes, 0.0).unwrap();
    let queries = vec![Query::point(Vec3::new(1.0, 1.0, 0.3)); 3];
    let other_surface = |e: SurfaceError| matches!(e, SurfaceError::OtherSurface { .. });
    let mut out = vec![None; queries.len()];
    let err = bvh
        .closest_all_into(&other, &queries, 1.0, &mut out)
        .unwrap_err();
    assert!(
        err.to_string()
            .contains("search tree was made on another surface"),
        "{err}"
    );
    assert!(other_surface(bvh.update(&other, &nodes).unwrap_err()));
    assert!(other_surface(
        Neighbourhoods::new(&bvh, &other, &nodes, &queries, 0.1).unwrap_err()
    ));
    let lists = Neighbourhoods::new(&bvh, &copy, &nodes, &queries, 0.1).unwrap();
    let err = lists
        .closest_all(&mut bvh, &other, &nodes, &queries, 1.0)
        .unwrap_err();
    assert!(
        err.to_string().contains("neighbourhood lists was made"),
        "{err}"
    );
    assert!(other_surface(lists.moved(&other, &nodes).unwrap_err()));
    // A tree of the other surface with the lists of the first: refused too.
    let mut other_bvh = Bvh::build(&other, &nodes, 0.0).unwrap();
    assert!(other_surface(
        lists
            .closest_all(&mut other_bvh, &one, &nodes, &queries, 1.0)
            .unwrap_err()
    ));
    assert!(other_surface(
        lists
            .moved(&one, &nodes)
            .unwrap()
            .closest_all(&mut other_bvh, &queries, 1.0)
            .unwrap_err()
    ));
    // The same surface, or an equal copy, is searched as before.
    let (hits, _) = lists
        .closest_all(&mut bvh, &copy, &nodes, &queries, 1.0)
        .unwrap();
    assert_eq!(hits, bvh.closest_all(&one, &queries, 1.0));
    assert_eq!(bvh.update(&copy, &nodes).unwrap(), Update::Refit);
    for call in [
        Box::new(|| {
            let _ = bvh.closest(&other, &queries[0], 1.0);
        }) as Box<dyn Fn()>,
        Box::new(|| {
            let _ = bvh.closest_with_hint(&other, &queries[0], Some(0), 1.0);
        }),
        Box::new(|| {
            let _ = bvh.within(&other, &queries[0], 1.0);
        }),
        Box::new(|| {
            let _ = bvh.closest_all(&other, &queries, 1.0);
        }),
    ] {
        let panic = std::panic::catch_unwind(std::panic::AssertUnwindSafe(call)).unwrap_err();
        let message = panic.downcast_ref::<String>().expect("a message");
        assert!(
            message.contains("search tree was made on another surface"),
            "{message}"
        );
    }
}
