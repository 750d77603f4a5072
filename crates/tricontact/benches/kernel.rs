//! Throughput of the node–facet kernel on one core: detection, penalty force + tangent, and
//! multiplier Jacobian + geometric stiffness, per node–facet pair (facet construction included).
//!
//! Run with `cargo bench -p tricontact --bench kernel`.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use tricontact::{NodeFacet, Vec3, detect, multiplier, penalty};

/// A fixed batch of pairs: facets of varied shape, slave nodes above, below and beside them.
fn pairs(n: usize) -> Vec<[Vec3; 4]> {
    // A small linear congruential generator keeps the bench free of extra dependencies.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let mut p = || Vec3::new(next(), next(), next());
        let (a, b, c) = (p(), p(), p());
        let w = (b - a).cross(&(c - a));
        let l = (b - a).norm().max((c - b).norm()).max((a - c).norm());
        if w.norm() < 0.2 * l * l {
            continue;
        }
        let l = a + 0.6 * (b - a) + 0.3 * (c - a) + 0.1 * p();
        out.push([a, b, c, l]);
    }
    out
}

fn kernel(c: &mut Criterion) {
    let batch = pairs(1024);
    let mut group = c.benchmark_group("node-facet");
    group.throughput(Throughput::Elements(batch.len() as u64));
    group.bench_function("detection (P, N, inside)", |b| {
        b.iter(|| {
            let mut inside = 0usize;
            for [xi, xj, xk, xl] in black_box(&batch) {
                if let Ok(p) = detect(*xi, *xj, *xk, *xl) {
                    inside += usize::from(p.is_inside(1e-9) && p.is_penetrating());
                }
            }
            inside
        });
    });
    group.bench_function("penalty (R + K)", |b| {
        b.iter(|| {
            let mut trace = 0.0;
            for [xi, xj, xk, xl] in black_box(&batch) {
                let pair = NodeFacet::new(*xi, *xj, *xk, *xl).unwrap();
                let t = penalty(&pair, 1e4).unwrap();
                trace += t.stiffness[(11, 11)] + t.force[0];
            }
            trace
        });
    });
    group.bench_function("multiplier (grad c + lambda hess c)", |b| {
        b.iter(|| {
            let mut trace = 0.0;
            for [xi, xj, xk, xl] in black_box(&batch) {
                let pair = NodeFacet::new(*xi, *xj, *xk, *xl).unwrap();
                let t = multiplier(&pair, -2.0).unwrap();
                trace += t.geometric_stiffness[(0, 11)] + t.jacobian[0];
            }
            trace
        });
    });
    group.finish();
}

criterion_group!(benches, kernel);
criterion_main!(benches);
