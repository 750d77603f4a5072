//! # Contact search benchmark
//!
//! Measures, in one run and on the same scenes, the BVH build, closest-facet queries in coherent
//! and random order, the speed-up over brute force and over `parry3d-f64`'s BVH point projection,
//! and the incremental search's speed-up over the full query after small deformations.
//!
//! Run with `cargo run --release -p tricontact --example search_bench` (add `-- --quick` to skip
//! the 10⁶-facet scene). Scenes: triangulated tori (major radius 3, minor radius 1) with about
//! 10⁴, 10⁵ and 10⁶ facets; one query point per facet, at a random point of the facet moved by up
//! to ±2 element sizes along its normal. "Coherent" queries come in facet order (neighbours in
//! space are neighbours in the list); "random" queries are shuffled. Per-core figures are the CPU
//! time of a one-thread pool (so they hold on a shared machine), the best of three batches of at
//! least 0.3 s; the two sides of a ratio (ours and parry's, the full query and the incremental
//! search) are measured in alternating batches, so that the machine's drift does not fall between
//! them. The coherent query is timed in two such windows, alone and beside parry's, and its figure
//! is the best of the six batches (both are printed): in trial runs the first window, right after
//! the two-thread run, read up to 30 % slower at 10⁴ facets than a second window straight after
//! it, for the same call; brute force is timed on a subset of queries and its ratio is per query (measured
//! per query on the subset, not extrapolated from a model). Two-thread figures are wall-clock. Answers (ours and parry's) are written into
//! buffers made once, as a solver searching at every iteration would: allocating a fresh buffer
//! of 10⁶ answers costs about 50 ns per answer in page faults, as much as a search.
//!
//! Incremental search: neighbourhood lists (skin half an element) are made at the initial
//! positions; the torus is then deformed by a wave and a twist of 0.01, 0.1 and 0.2 element sizes
//! each (the largest node motion is printed, in element sizes). After a deformation each search
//! first brings its structure to the new positions, once, whatever the number of queries: the
//! tree is refitted (`Bvh::update`), the lists get the node motions and the longest
//! (`Neighbourhoods::moved`). The two updates are timed (alternated), then the two queries on them
//! (alternated), then update and query in one go on each side (alternated: refit then
//! `Bvh::closest_all_into`, against `Neighbourhoods::closest_all_into`, which is what a solver
//! that searches once per iteration calls). Two ratios are printed: query against query, and
//! update and query against update and query, the latter from the one-go times.

use std::sync::Mutex;
use std::time::Instant;

use parry3d_f64::math::Vector as PVec;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::TriMesh;
use tricontact::Vec3;
use tricontact::search::scenes::{self, torus};
use tricontact::search::{Bvh, Hit, Neighbourhoods, Query, Surface, Update, brute_force_closest};

fn near_surface(nodes: &[Vec3], facets: &[[u32; 3]], h: f64) -> Vec<Query> {
    scenes::near_surface(nodes, facets, 2.0 * h, 11)
        .into_iter()
        .map(Query::point)
        .collect()
}

/// Best of `reps` wall-clock times of `f`, in seconds, with its last result.
fn time<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..reps {
        let t = Instant::now();
        let v = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(v);
    }
    (best, out.expect("at least one repetition"))
}

/// CPU time of the calling thread in seconds (`/proc/thread-self/schedstat`), `None` where the
/// kernel does not provide it. The thread yields first: the kernel brings a running thread's count
/// up to date when it is scheduled, and a thread that has run uninterrupted reads a count up to a
/// scheduler tick old (measured: about 1 ms without the yield, exact with it).
fn thread_cpu_time() -> Option<f64> {
    std::thread::yield_now();
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// One batch: repeats `f` until at least 0.3 s of CPU time (the calling thread's; wall-clock
/// where the per-thread clock is missing, and at most 10 s of wall-clock time) has passed;
/// returns the time per call and the last result.
fn batch<T>(f: &impl Fn() -> T) -> (f64, T) {
    let (c0, t0) = (thread_cpu_time(), Instant::now());
    let mut calls = 0u32;
    loop {
        let last = f();
        calls += 1;
        let wall = t0.elapsed().as_secs_f64();
        let cpu = c0.and_then(|c0| thread_cpu_time().map(|c1| c1 - c0));
        let spent = cpu.unwrap_or(wall);
        if spent >= 0.3 || wall >= 10.0 {
            return (spent / f64::from(calls), last);
        }
    }
}

/// CPU time per call of `f` on a one-thread pool, in seconds, the best of `reps` batches (see
/// [`batch`]): per-core figures stay meaningful when other processes share the machine, and the
/// best batch discounts a disturbed one. Returns the last result too.
fn time_one_core<T: Send>(reps: usize, f: impl Fn() -> T + Sync) -> (f64, T) {
    pool(1).install(|| {
        let mut best = f64::INFINITY;
        let mut last = None;
        for _ in 0..reps.max(1) {
            let (t, v) = batch(&f);
            best = best.min(t);
            last = Some(v);
        }
        (best, last.expect("at least one call"))
    })
}

/// [`time_one_core`] for two functions whose times are compared, their batches alternated
/// (`f`, `g`, `f`, `g`, …) so that a ratio is measured under the same conditions: this machine's
/// speed drifts by tens of per cent over minutes. The best of each, and the last results.
fn time_pair_one_core<T: Send, U: Send>(
    reps: usize,
    f: impl Fn() -> T + Sync,
    g: impl Fn() -> U + Sync,
) -> ((f64, T), (f64, U)) {
    pool(1).install(|| {
        let (mut best_f, mut best_g) = (f64::INFINITY, f64::INFINITY);
        let (mut last_f, mut last_g) = (None, None);
        for _ in 0..reps.max(1) {
            let (t, v) = batch(&f);
            best_f = best_f.min(t);
            last_f = Some(v);
            let (t, v) = batch(&g);
            best_g = best_g.min(t);
            last_g = Some(v);
        }
        let at_least_one = "at least one call";
        (
            (best_f, last_f.expect(at_least_one)),
            (best_g, last_g.expect(at_least_one)),
        )
    })
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

fn scene(nu: u32, nv: u32) {
    let (nodes, facets) = torus(nu, nv, 3.0, 1.0);
    let h = std::f64::consts::TAU / f64::from(nv);
    let n = facets.len();
    let queries = near_surface(&nodes, &facets, h);
    let mut random = queries.clone();
    scenes::shuffle(&mut random, 5);
    let nq = queries.len() as f64;
    println!(
        "\n## torus, {n} facets, {} query points, element size {h:.4}",
        queries.len()
    );

    let (t_surface, surface) = time(1, || {
        Surface::new(facets.clone(), nodes.len()).expect("surface")
    });
    let (t_build, bvh) = time(3, || Bvh::build(&surface, &nodes, 0.0).expect("bvh"));
    let (t_build1, _) =
        pool(1).install(|| time(3, || Bvh::build(&surface, &nodes, 0.0).expect("bvh")));
    println!("surface adjacency       {:>9.2} ms", t_surface * 1e3);
    println!(
        "BVH build (2 threads)   {:>9.2} ms   {:>7.2} M facets/s   (1 thread: {:.2} M facets/s)",
        t_build * 1e3,
        n as f64 / t_build / 1e6,
        n as f64 / t_build1 / 1e6
    );

    let inf = f64::INFINITY;
    // Answers go into buffers made once, as a solver searching at every iteration does.
    let buffer = Mutex::new(vec![None; queries.len()]);
    let into = |qs: &[Query]| {
        let mut out = buffer.lock().expect("buffer");
        bvh.closest_all_into(&surface, qs, inf, &mut out)
            .expect("one answer per query");
    };
    let (t_rand, ()) = time_one_core(3, || into(&random));
    let (t_coh2, ()) = time(3, || into(&queries));
    let (t_alone, ()) = time_one_core(3, || into(&queries));
    let hits = buffer.lock().expect("buffer").clone();
    // parry3d-f64: same vertices, same facets, same query points.
    let pv: Vec<PVec> = nodes.iter().map(|p| PVec::new(p.x, p.y, p.z)).collect();
    let (t_pbuild, mesh) = time(1, || {
        TriMesh::new(pv.clone(), facets.clone()).expect("parry trimesh")
    });
    let projections = Mutex::new(vec![None; queries.len()]);
    // Ours and parry's batches alternated, for the ratio.
    let ((t_ours, ()), (t_parry, ())) = time_pair_one_core(
        3,
        || into(&queries),
        || {
            let mut out = projections.lock().expect("buffer");
            for (p, q) in out.iter_mut().zip(&queries) {
                let point = PVec::new(q.point.x, q.point.y, q.point.z);
                *p = Some(mesh.project_local_point(point, false));
            }
        },
    );
    // The same call timed in two windows (alone, and alternating with parry3d-f64): the best of
    // its six batches, as every figure here is a best of batches.
    let t_coh = t_alone.min(t_ours);
    println!(
        "queries, coherent       {:>9.2} ms   {:>7.2} M/s per core   (2 threads: {:.2} M/s; best of 6 batches, {:.2} ms alone, {:.2} ms beside parry3d-f64)",
        t_coh * 1e3,
        nq / t_coh / 1e6,
        nq / t_coh2 / 1e6,
        t_alone * 1e3,
        t_ours * 1e3
    );
    println!(
        "queries, random order   {:>9.2} ms   {:>7.2} M/s per core",
        t_rand * 1e3,
        nq / t_rand / 1e6
    );

    // Brute force on a subset, one thread, same queries.
    let subset = (2000 * 10_000 / n).clamp(20, 2000);
    let sample: Vec<Query> = queries
        .iter()
        .step_by(queries.len() / subset)
        .copied()
        .collect();
    let (t_brute, brute) = time_one_core(1, || {
        sample
            .iter()
            .map(|q| brute_force_closest(&surface, &nodes, q, inf))
            .collect::<Vec<_>>()
    });
    let agree = sample
        .iter()
        .zip(&brute)
        .filter(|(q, b)| bvh.closest(&surface, q, inf).map(|h| h.facet) == b.map(|h| h.facet))
        .count();
    let per_brute = t_brute / sample.len() as f64;
    let per_tree = t_coh / nq;
    println!(
        "brute force             {:>9.2} µs/query on {} queries ({agree} identical answers); tree is {:.0}× faster per query",
        per_brute * 1e6,
        sample.len(),
        per_brute / per_tree
    );

    let proj: Vec<_> = projections
        .into_inner()
        .expect("buffer")
        .into_iter()
        .map(|p| p.expect("every query projected"))
        .collect();
    let worst = hits
        .iter()
        .zip(&proj)
        .zip(&queries)
        .map(|((h, p), q)| {
            let d_parry = (p.point - PVec::new(q.point.x, q.point.y, q.point.z)).length();
            (h.map_or(inf, |h: Hit| h.closest.distance) - d_parry).abs()
        })
        .fold(0.0, f64::max);
    println!(
        "parry3d-f64 TriMesh     build {:.2} ms, queries {:.2} ms = {:.2} M/s; tricontact is {:.2}× faster (coherent, 1 core); largest distance difference {worst:.1e}",
        t_pbuild * 1e3,
        t_parry * 1e3,
        nq / t_parry / 1e6,
        t_parry / t_ours
    );

    incremental(&surface, &nodes, &queries, bvh, h, &hits);
}

/// Neighbourhood lists made at the initial positions (skin half an element), then, after
/// deformations of 0.01, 0.1 and 0.2 element sizes: each search's update to the new positions (the
/// tree's refit, the lists' node motions), each query at them, and both in one go on each side;
/// the incremental query against the full query, and the incremental search's one call against
/// refit plus full query.
fn incremental(
    surface: &Surface,
    nodes: &[Vec3],
    queries: &[Query],
    bvh: Bvh,
    h: f64,
    hits: &[Option<Hit>],
) {
    let inf = f64::INFINITY;
    let nq = queries.len() as f64;
    let skin = 0.5 * h;
    let (t_lists, lists) = time_one_core(1, || {
        Neighbourhoods::new(&bvh, surface, nodes, queries, skin).expect("lists")
    });
    println!(
        "neighbourhood lists     {:>9.2} ms per core (skin 0.5 h): {:.1} facets per query, {:.0} MB",
        t_lists * 1e3,
        lists.len() as f64 / nq,
        lists.bytes() as f64 * 1e-6
    );
    for a in [0.01, 0.1, 0.2] {
        let moved = scenes::deformed(nodes, h, a);
        let tree = Mutex::new(bvh.clone());
        // The two updates to the new positions, their batches alternated.
        let ((t_refit, kind), (t_moved, delta)) = time_pair_one_core(
            3,
            || {
                tree.lock()
                    .expect("tree")
                    .update(surface, &moved)
                    .expect("update")
            },
            || lists.moved(surface, &moved).expect("motions").motion(),
        );
        assert_eq!(kind, Update::Refit);
        let refitted = tree.lock().expect("tree").clone();
        let buffer = Mutex::new(vec![None; queries.len()]);
        // A fallback updates the tree (each call: the update refits it again). Each incremental
        // path writes into a buffer of its own, starting empty, so that an answer it failed to
        // write would show below.
        let stale = Mutex::new(bvh.clone());
        let own = Mutex::new(vec![None; queries.len()]);
        let at = lists.moved(surface, &moved).expect("motions");
        // The two queries at the new positions, their batches alternated.
        let ((t_full, ()), (t_inc, stats)) = time_pair_one_core(
            3,
            || {
                let mut out = buffer.lock().expect("buffer");
                refitted
                    .closest_all_into(surface, queries, inf, &mut out)
                    .expect("one answer per query");
            },
            || {
                let mut out = own.lock().expect("buffer");
                at.closest_all_into(&mut stale.lock().expect("tree"), queries, inf, &mut out)
                    .expect("incremental")
            },
        );
        drop(at);
        // Update and query in one go on each side, as a solver that searches once per iteration
        // pays them, their batches alternated.
        let one = Mutex::new(vec![None; queries.len()]);
        let tree_out = Mutex::new(vec![None; queries.len()]);
        let ((t_tree_call, ()), (t_call, _)) = time_pair_one_core(
            3,
            || {
                let mut tree = tree.lock().expect("tree");
                tree.update(surface, &moved).expect("update");
                let mut out = tree_out.lock().expect("buffer");
                tree.closest_all_into(surface, queries, inf, &mut out)
                    .expect("one answer per query");
            },
            || {
                let mut out = one.lock().expect("buffer");
                lists
                    .closest_all_into(
                        &mut stale.lock().expect("tree"),
                        surface,
                        &moved,
                        queries,
                        inf,
                        &mut out,
                    )
                    .expect("incremental")
            },
        );
        let full = buffer.lock().expect("buffer").clone();
        let mismatches: usize = [own, one]
            .into_iter()
            .map(|answers| {
                let answers = answers.into_inner().expect("buffer");
                answers.iter().zip(&full).filter(|(a, b)| a != b).count()
            })
            .sum();
        let changed = hits
            .iter()
            .zip(&full)
            .filter(|(a, b)| a.map(|h| h.facet) != b.map(|h| h.facet))
            .count();
        println!(
            "after motion {:.2} h      update: refit {:.2} ms, motions {:.2} ms; query: full {:.2} ms, incremental {:.2} ms; both in one go: {:.2} ms and {:.2} ms (per core): {:.1}× query against query, {:.1}× update and query against update and query; {:.2} facets measured per query, {} fallbacks ({:.3} %), {changed} answers changed, {mismatches} differ from the full query",
            delta / h,
            t_refit * 1e3,
            t_moved * 1e3,
            t_full * 1e3,
            t_inc * 1e3,
            t_tree_call * 1e3,
            t_call * 1e3,
            t_full / t_inc,
            t_tree_call / t_call,
            stats.measured as f64 / nq,
            stats.fallbacks,
            100.0 * stats.fallbacks as f64 / nq
        );
    }
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    println!(
        "contact search benchmark ({} threads available)",
        rayon::current_num_threads()
    );
    scene(100, 50);
    scene(316, 158);
    if !quick {
        scene(1000, 500);
    }
}
