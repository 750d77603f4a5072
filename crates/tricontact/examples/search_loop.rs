//! # One search path in a loop, for A/B comparisons
//!
//! `search_bench` measures everything in about a minute; comparing two builds of one path needs
//! many short interleaved runs instead (this machine's speed drifts by tens of per cent over
//! minutes).
//! This program times one path on one core (or on `threads`, the optional fourth argument, except
//! `walk` and `stream`, which are sequential) and prints the best time per query over `reps` calls,
//! and the median. The bench's figures are means of batches of calls, nearer the median than the
//! best.
//! On this machine, in three runs each of `incremental 316 60` and `closest 316 60` taken in turn,
//! the incremental search read 37.9–52.1 ns per query at best and 43.5–57.6 at the median, the
//! full query 311–313 and 353–394: the medians' ratio was 6.1–8.8, the bests' 6.0–8.2. The
//! incremental search, which streams its lists from memory, varies more between calls.
//!
//! [`Moved::closest_all_into`]: tricontact::search::Moved::closest_all_into
//!
//! ```text
//! cargo run --release -p tricontact --example search_loop -- closest 316 15
//! cargo run --release -p tricontact --example search_loop -- incremental 1000 20
//! cargo run --release -p tricontact --example search_loop -- walk 1000 5
//! cargo run --release -p tricontact --example search_loop -- build 1000 5
//! cargo run --release -p tricontact --example search_loop -- stream 1000 30
//! cargo run --release -p tricontact --example search_loop -- carried 1000 20
//! ```
//!
//! The scene is `search_bench`'s: a torus of `nu × nu/2` quads split in two (316 gives 99 856
//! facets, 1000 gives 10⁶), one query per facet within ±2 element sizes of the surface, in facet
//! order. `closest` times [`Bvh::closest_all_into`], `random` the same on the queries shuffled
//! (`search_bench`'s random order); `incremental` makes neighbourhood lists (skin half an
//! element), deforms the torus by 0.01 element sizes as `search_bench` does, times
//! [`Neighbourhoods::closest_all_into`] and prints the facets it measured per query; of that call,
//! `moved` times the first part alone ([`Neighbourhoods::moved`]: the node motions and the
//! longest, the counterpart of `refit`, printed per query) and `query` the second
//! ([`Moved::closest_all_into`] on one `Moved`). `walk` times, on the same motion, the
//! alternative the incremental search does not take: from each query's facet before the motion,
//! a walk to nearer facets sharing a node ([`Surface::neighbours`], the scalar kernel on the facet
//! and all its neighbours, until none is nearer), and counts the facets it measures and the
//! answers that differ from the tree's (a walk certifies none of them).
//! `build` times [`Bvh::build`] and `refit` [`Bvh::update`] (the torus and its deformed copy in
//! turn), per facet. `stream` times the incremental search's three largest streams and nothing
//! else (sequential, like `walk`): per query, a 64-byte record and the query read, an answer
//! written (the floor its memory traffic sets). `carried` times the incremental search after
//! rigid motions of the deformed torus, a translation by 0.1 element sizes and a turn about its
//! axis moving its outer rim by as much, with the query points fixed or carried along (a query's
//! motion and the surface's then largely cancel in the first-order bound but not in the Lipschitz
//! bound, so the queries walk further). Expected output
//! (the time varies with the machine; these lines are from an AMD EPYC Zen 4, with AVX-512, but
//! for `moved` and `query`, from an Intel Xeon with AVX-512; an AVX2 machine, Zen 3, read 471.0
//! ns for the `closest` line):
//!
//! ```text
//! closest, 99856 facets: 313.9 ns per query (best of 15 calls, one core; median 359.8)
//! incremental, 1000000 facets: 34.2 ns per query (best of 20 calls, one core; median 47.0); 1.071 facets measured per query
//! moved, 1000000 facets: 1.2 ns per query (best of 20 calls, one core; median 1.3)
//! query, 1000000 facets: 27.4 ns per query (best of 20 calls, one core; median 27.9); 1.071 facets measured per query
//! build, 1000000 facets: 223.9 ns per facet (best of 4 calls, one core; median 239.4)
//! refit, 1000000 facets: 45.4 ns per facet (best of 6 calls, one core; median 52.0)
//! walk, 1000000 facets: 218.1 ns per query (best of 5 calls, one core; median 231.1); 13.16 facets measured per query, 0 answers differ from the tree
//! stream, 1000000 facets: 6.7 ns per query (best of 30 calls, one core; median 7.3)
//! carried, 1000000 facets, translated, queries fixed: 71.1 ns per query (best of 20 calls, one core; median 80.2); 1.364 facets measured per query
//! ```

use std::process::ExitCode;
use std::time::Instant;

use tricontact::search::scenes::{self, torus};
use tricontact::search::{Bvh, Hit, Neighbourhoods, Query, Surface};
use tricontact::{ClosestPoint, Feature, Vec3, distance_squared_to_triangle};

const USAGE: &str = "usage: search_loop closest|random|incremental|moved|query|walk|build|refit|stream|carried [nu ≥ 8, default 316] [reps ≥ 1, default 15] [threads ≥ 1, default 1]";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mode = args.first().map_or("closest", String::as_str);
    let nu = args.get(1).map_or(Ok(316), |s| s.parse::<u32>());
    let reps = args.get(2).map_or(Ok(15), |s| s.parse::<usize>());
    let threads = args.get(3).map_or(Ok(1), |s| s.parse::<usize>());
    let (Ok(nu), Ok(reps), Ok(threads)) = (nu, reps, threads) else {
        eprintln!("{USAGE}");
        return ExitCode::FAILURE;
    };
    if nu < 8
        || reps == 0
        || threads == 0
        || !matches!(
            mode,
            "closest"
                | "random"
                | "incremental"
                | "moved"
                | "query"
                | "walk"
                | "build"
                | "refit"
                | "stream"
                | "carried"
        )
    {
        eprintln!("{USAGE}");
        return ExitCode::FAILURE;
    }
    let (nodes, facets) = torus(nu, nu / 2, 3.0, 1.0);
    let h = std::f64::consts::TAU / f64::from(nu / 2);
    let surface = Surface::new(facets.clone(), nodes.len()).expect("a valid torus");
    let bvh = Bvh::build(&surface, &nodes, 0.0).expect("positions for every node");
    let mut queries: Vec<Query> = scenes::near_surface(&nodes, &facets, 2.0 * h, 11)
        .into_iter()
        .map(Query::point)
        .collect();
    if mode == "random" {
        scenes::shuffle(&mut queries, 5);
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    // `walk` and `stream` are sequential whatever the pool.
    let cores = if threads == 1 || matches!(mode, "walk" | "stream") {
        "one core".to_string()
    } else {
        format!("{threads} threads")
    };
    if mode == "walk" || mode == "carried" {
        let scene = Scene {
            pool: &pool,
            surface: &surface,
            bvh: &bvh,
            nodes: &nodes,
            queries: &queries,
            h,
            reps,
            cores: &cores,
        };
        if mode == "walk" {
            walk(&scene);
        } else {
            carried(&scene);
        }
        return ExitCode::SUCCESS;
    }
    if mode == "build" || mode == "refit" {
        let moved = scenes::deformed(&nodes, h, 0.01);
        let mut tree = bvh.clone();
        let times = pool.install(|| {
            if mode == "build" {
                timed(reps, || {
                    std::hint::black_box(Bvh::build(&surface, &nodes, 0.0).expect("a tree"));
                })
            } else {
                let mut k = 0;
                timed(reps, || {
                    k += 1;
                    let at = if k % 2 == 0 { &nodes } else { &moved };
                    tree.update(&surface, at).expect("positions for every node");
                })
            }
        });
        println!(
            "{mode}, {} facets: {}",
            facets.len(),
            times.per(facets.len(), "facet", &cores)
        );
        return ExitCode::SUCCESS;
    }
    let mut out = vec![None; queries.len()];
    let mut measured = None;
    let times = pool.install(|| {
        if mode == "stream" {
            stream(&queries, &mut out, reps)
        } else if mode == "closest" || mode == "random" {
            timed(reps, || {
                bvh.closest_all_into(&surface, &queries, f64::INFINITY, &mut out)
                    .expect("one answer per query");
            })
        } else {
            let lists = Neighbourhoods::new(&bvh, &surface, &nodes, &queries, 0.5 * h)
                .expect("lists for the torus");
            let moved = scenes::deformed(&nodes, h, 0.01);
            let mut tree = bvh.clone();
            if mode == "moved" {
                timed(reps, || {
                    let at = lists.moved(&surface, &moved).expect("motions");
                    std::hint::black_box(at.motion());
                })
            } else if mode == "query" {
                let at = lists.moved(&surface, &moved).expect("motions");
                timed(reps, || {
                    let stats = at
                        .closest_all_into(&mut tree, &queries, f64::INFINITY, &mut out)
                        .expect("incremental search");
                    measured = Some(stats.measured);
                })
            } else {
                timed(reps, || {
                    let stats = lists
                        .closest_all_into(
                            &mut tree,
                            &surface,
                            &moved,
                            &queries,
                            f64::INFINITY,
                            &mut out,
                        )
                        .expect("incremental search");
                    measured = Some(stats.measured);
                })
            }
        }
    });
    let nq = queries.len() as f64;
    let facets_measured = measured.map_or(String::new(), |m| {
        format!("; {:.3} facets measured per query", m as f64 / nq)
    });
    println!(
        "{mode}, {} facets: {}{facets_measured}",
        facets.len(),
        times.per(queries.len(), "query", &cores)
    );
    ExitCode::SUCCESS
}

/// What the modes that time the incremental search's alternatives share: the pool, the torus and
/// its tree, the queries, the element size `h`, the number of calls to time and what the pool's
/// threads are called in the output.
#[derive(Clone, Copy)]
struct Scene<'a> {
    pool: &'a rayon::ThreadPool,
    surface: &'a Surface,
    bvh: &'a Bvh,
    nodes: &'a [Vec3],
    queries: &'a [Query],
    h: f64,
    reps: usize,
    cores: &'a str,
}

/// The neighbour walk after a motion of 0.01 element sizes `h`, query after query (sequential, on
/// the scene's pool), timed (best of `reps` calls) against the tree's answers (see the module
/// documentation).
fn walk(scene: &Scene<'_>) {
    let Scene {
        pool,
        surface,
        bvh,
        nodes,
        queries,
        h,
        reps,
        ..
    } = *scene;
    let before = bvh.closest_all(surface, queries, f64::INFINITY);
    let moved = scenes::deformed(nodes, h, 0.01);
    let mut tree = bvh.clone();
    tree.update(surface, &moved)
        .expect("positions for every node");
    let truth = tree.closest_all(surface, queries, f64::INFINITY);
    let d2 = |f: u32, p: &Vec3| {
        let [a, b, c] = surface.corners(f, &moved);
        distance_squared_to_triangle(&a, &b, &c, p)
    };
    let mut ends = vec![None; queries.len()];
    let mut measured = 0usize;
    let times = pool.install(|| {
        timed(reps, || {
            measured = 0;
            for ((q, start), end) in queries.iter().zip(&before).zip(ends.iter_mut()) {
                let Some(start) = start else { continue };
                let (mut f, mut b) = (start.facet, d2(start.facet, &q.point));
                measured += 1;
                loop {
                    let mut next = None;
                    for &g in surface.neighbours(f) {
                        let d = d2(g, &q.point);
                        measured += 1;
                        // The total order of the tree: distance, then facet index.
                        if d < b || (d == b && g < next.unwrap_or(f)) {
                            (b, next) = (d, Some(g));
                        }
                    }
                    match next {
                        Some(g) => f = g,
                        None => break,
                    }
                }
                *end = Some(f);
            }
        })
    });
    let differ = ends
        .iter()
        .zip(&truth)
        .filter(|(e, t)| **e != t.map(|t| t.facet))
        .count();
    let n = queries.len() as f64;
    println!(
        "walk, {} facets: {}; {:.2} facets measured per query, {differ} answers differ from the tree",
        surface.len(),
        times.per(queries.len(), "query", scene.cores),
        measured as f64 / n
    );
}

/// The incremental search after the deformed torus is translated, or turned about its axis, by
/// 0.1 element sizes `h` (at its outer rim), with the query points fixed or carried along, timed
/// on the scene's pool (best of `reps` calls; see the module documentation).
fn carried(scene: &Scene<'_>) {
    let (surface, queries, h) = (scene.surface, scene.queries, scene.h);
    let lists =
        Neighbourhoods::new(scene.bvh, surface, scene.nodes, queries, 0.5 * h).expect("lists");
    let rim = scene
        .nodes
        .iter()
        .map(|p| p.x.hypot(p.y))
        .fold(0.0, f64::max);
    let shift = Vec3::new(1.0, 1.0, 1.0).normalize() * (0.1 * h);
    let angle = 0.1 * h / rim;
    let turn = |p: &Vec3| {
        let (c, s) = (angle.cos(), angle.sin());
        Vec3::new(c * p.x - s * p.y, s * p.x + c * p.y, p.z)
    };
    let deformed = scenes::deformed(scene.nodes, h, 0.01);
    // Motion 0 translates, motion 1 turns.
    let motion = |k: usize, p: &Vec3| if k == 0 { p + shift } else { turn(p) };
    for (k, name) in [(0, "translated"), (1, "turned")] {
        let moved: Vec<Vec3> = deformed.iter().map(|p| motion(k, p)).collect();
        let carried: Vec<Query> = queries
            .iter()
            .map(|q| Query::point(motion(k, &q.point)))
            .collect();
        for (how, qs) in [("fixed", queries), ("carried", &carried[..])] {
            let mut tree = scene.bvh.clone();
            let mut out = vec![None; qs.len()];
            let mut measured = 0;
            let times = scene.pool.install(|| {
                timed(scene.reps, || {
                    let stats = lists
                        .closest_all_into(&mut tree, surface, &moved, qs, f64::INFINITY, &mut out)
                        .expect("incremental search");
                    measured = stats.measured;
                })
            });
            println!(
                "carried, {} facets, {name}, queries {how}: {}; {:.3} facets measured per query",
                surface.len(),
                times.per(qs.len(), "query", scene.cores),
                measured as f64 / qs.len() as f64
            );
        }
    }
}

/// The incremental search's three largest streams and nothing else, timed (best of `reps`
/// passes, sequential): per query, a record of 64 bytes (as many as the lists' records) and the
/// query read, and an answer (`Option<Hit>`, 80 bytes) written in place.
fn stream(queries: &[Query], out: &mut [Option<Hit>], reps: usize) -> Times {
    let records: Vec<[f64; 8]> = queries
        .iter()
        .enumerate()
        .map(|(i, q)| {
            let p = q.point;
            [p.x, p.y, p.z, i as f64, 0.25, 0.5, 0.25, 0.1]
        })
        .collect();
    timed(reps, || {
        for ((r, q), o) in records.iter().zip(queries).zip(out.iter_mut()) {
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            let facet = r[3] as u32;
            *o = Some(Hit {
                facet,
                closest: ClosestPoint {
                    feature: Feature::Face,
                    barycentric: [r[4], r[5], r[6]],
                    point: q.point,
                    distance: r[7] + (r[0] - q.point.x),
                },
            });
        }
        std::hint::black_box(&*out);
    })
}

/// The shortest and the median of `reps` wall-clock times of `f`, in seconds.
fn timed(reps: usize, mut f: impl FnMut()) -> Times {
    let mut times: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    Times {
        best: times[0],
        median: times[times.len() / 2],
        reps,
    }
}

/// What [`timed`] measured, in seconds, over `reps` calls.
#[derive(Clone, Copy)]
struct Times {
    best: f64,
    median: f64,
    reps: usize,
}

impl Times {
    /// The best and median times per item of `n` (a query, a facet) as this program prints them,
    /// the calls run on `cores`.
    fn per(&self, n: usize, item: &str, cores: &str) -> String {
        let n = n as f64;
        format!(
            "{:.1} ns per {item} (best of {} calls, {cores}; median {:.1})",
            self.best * 1e9 / n,
            self.reps,
            self.median * 1e9 / n
        )
    }
}
