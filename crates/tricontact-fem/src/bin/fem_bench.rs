//! Benchmark of the linear-system pipeline on a structured hex8 cube:
//! assembly (parallel element loop + deterministic merge), symbolic
//! analysis, numeric Cholesky factorization and triangular solve, timed
//! separately.
//!
//! `cargo run --release -p tricontact-fem --bin fem-bench [-- N [--amd]]`
//! uses `N × N × N` bricks (default 45: 97 336 nodes, ≈ 290 000 free DOFs);
//! `--amd` replaces the nested-dissection ordering by faer's AMD;
//! `--dense M` only times a dense `M × M` Cholesky (machine reference);
//! `--vtu` only times encoding a `.vtu` of the cube (the fields a run writes, synthetic values)
//! as ASCII and as binary, and prints the sizes.

use std::time::Instant;

use tricontact_fem::analysis::Analysis;
use tricontact_fem::assembly::{DofMap, NoExtra, Pattern, assemble, node_adjacency};
use tricontact_fem::driver::{external_forces, step_constraints};
use tricontact_fem::linsolve::{LinearSolver, Structure};
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::model::Model;
use tricontact_fem::ordering::equation_order;
use tricontact_fem::structured::box_mesh;
use tricontact_fem::vtu::{Field, Grid, VtuFormat, vtk_cell, vtu_string};

/// Dense Cholesky of an `m × m` SPD matrix: the machine's dense GFlop/s,
/// an upper bound for the supernodal sparse factorization.
fn dense_reference(m: usize) {
    let a = faer::Mat::<f64>::from_fn(m, m, |i, j| {
        if i == j {
            m as f64
        } else {
            1.0 / (1.0 + (i + j) as f64)
        }
    });
    let t = Instant::now();
    let f = a.llt(faer::Side::Lower);
    let secs = t.elapsed().as_secs_f64();
    let ok = f.is_ok();
    println!(
        "dense Cholesky {m}x{m}: {secs:.3} s = {:.1} GFlop/s ({})",
        (m as f64).powi(3) / 3.0 / secs / 1e9,
        if ok { "ok" } else { "failed" }
    );
}

/// Best of three wall-clock times of `f`, in seconds, with its result.
fn best_of_three<T>(f: impl Fn() -> T) -> (f64, T) {
    let mut best = (f64::INFINITY, None);
    for _ in 0..3 {
        let t = Instant::now();
        let v = f();
        let s = t.elapsed().as_secs_f64();
        if s < best.0 {
            best = (s, Some(v));
        }
    }
    (best.0, best.1.expect("three runs"))
}

/// Times encoding the `n³` hex8 cube's `.vtu` (displacement, reaction, nodal and element stress
/// and von Mises, material: the fields of a run, with smooth synthetic values) in both formats.
fn vtu_encoding(n: usize) {
    let mesh = box_mesh([1.0, 1.0, 1.0], [n, n, n], ElementKind::Hex8);
    let cells: Vec<(u8, Vec<usize>)> = mesh
        .elements
        .iter()
        .filter(|e| e.kind == ElementKind::Hex8)
        .map(|e| vtk_cell(e.kind, &e.nodes))
        .collect();
    let wave = |k: usize, i: usize| ((k as f64) * 0.37 + (i as f64) * 1e-3).sin() * 1e-2;
    let per_node =
        |c: usize| -> Vec<f64> { (0..mesh.nodes.len() * c).map(|i| wave(c, i)).collect() };
    let per_cell = |c: usize| -> Vec<f64> { (0..cells.len() * c).map(|i| wave(c, i)).collect() };
    let (u, r, s, vm) = (per_node(3), per_node(3), per_node(6), per_node(1));
    let (cs, cvm, mat) = (per_cell(6), per_cell(1), vec![0.0; cells.len()]);
    let field = |name, components, values| Field {
        name,
        components,
        values,
    };
    let grid = Grid {
        points: &mesh.nodes,
        cells: &cells,
        point_data: vec![
            field("displacement", 3, &u),
            field("reaction", 3, &r),
            field("stress", 6, &s),
            field("von_mises", 1, &vm),
        ],
        cell_data: vec![
            field("stress", 6, &cs),
            field("von_mises", 1, &cvm),
            field("material", 1, &mat),
        ],
    };
    println!(
        "vtu of the hex8 cube {n}^3: {} nodes, {} cells (one thread)",
        mesh.nodes.len(),
        cells.len()
    );
    let mut sizes = Vec::new();
    for format in [VtuFormat::Ascii, VtuFormat::Binary] {
        let (secs, xml) = best_of_three(|| vtu_string(&grid, format).expect("in memory"));
        let mb = xml.len() as f64 * 1e-6;
        println!(
            "{format:?}: {mb:>8.1} MB encoded in {secs:.3} s ({:.0} MB/s)",
            mb / secs
        );
        sizes.push((mb, secs));
    }
    println!(
        "binary / ascii: size {:.2}, time {:.2}",
        sizes[1].0 / sizes[0].0,
        sizes[1].1 / sizes[0].1
    );
}

fn main() {
    if std::env::args().any(|a| a == "--vtu") {
        let n = std::env::args()
            .filter_map(|s| s.parse().ok())
            .next()
            .unwrap_or(45);
        vtu_encoding(n);
        return;
    }
    if let Some(m) = std::env::args()
        .skip_while(|a| a != "--dense")
        .nth(1)
        .and_then(|s| s.parse().ok())
    {
        dense_reference(m);
        return;
    }
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(45);
    let t = Instant::now();
    let mesh = box_mesh([1.0, 1.0, 1.0], [n, n, n], ElementKind::Hex8);
    let text = "[mesh]\nfile = \"none\"\n[[material]]\nname = \"m\"\ntype = \"linear_elastic\"\nE = 1000.0\nnu = 0.3\n[[body]]\ngroup = \"solid\"\nmaterial = \"m\"\n[[boundary]]\ngroup = \"zmin\"\nfix = [\"x\", \"y\", \"z\"]\n[[load]]\ngroup = \"zmax\"\npressure = 1.0\n[[step]]\n";
    let model = match Model::parse(text, std::path::Path::new("bench.toml")) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let an = match Analysis::new(&model, mesh) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let setup = t.elapsed();
    let (mask, _) = step_constraints(&an, 0);
    let dm = DofMap::new(&an.active_nodes, &mask, 0);
    let t = Instant::now();
    let adj = node_adjacency(&an);
    let pat = Pattern::from_adjacency(&adj, &dm);
    let amd = std::env::args().any(|a| a == "--amd");
    let order = if amd {
        None
    } else {
        Some(equation_order(&an.mesh.nodes, &adj, &dm))
    };
    drop(adj);
    let t_pattern = t.elapsed();
    let u = vec![0.0; an.num_nodal_dofs()];
    let t = Instant::now();
    let asm = match assemble(&an, &dm, &pat, &u, false, true, None, &mut NoExtra) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: assembly failed: {e:?}");
            std::process::exit(1);
        }
    };
    let t_assembly = t.elapsed();
    let k = asm.matrix(&pat);
    let f = external_forces(&an, an.num_nodal_dofs(), 0, 1.0);
    let mut rhs = vec![0.0; dm.n_eq];
    for (dof, &e) in dm.eq.iter().enumerate() {
        if e != tricontact_fem::assembly::NO_EQ {
            rhs[e] = f[dof];
        }
    }
    let mut solver = match order {
        Some(p) => LinearSolver::new().with_order(p),
        None => LinearSolver::new(),
    };
    let t = Instant::now();
    if let Err(e) = solver.analyze(k.as_ref()) {
        eprintln!("error: {}", e.0);
        std::process::exit(1);
    }
    let t_symbolic = t.elapsed();
    let t = Instant::now();
    let factor = match solver.factor(k.as_ref(), Structure::SymmetricDefinite) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {}", e.0);
            std::process::exit(1);
        }
    };
    let t_numeric = t.elapsed();
    let t = Instant::now();
    let x = factor.solve(&rhs);
    let t_solve = t.elapsed();
    // Residual check ‖K x − b‖ / ‖b‖.
    let kr = k.as_ref();
    let mut ax = vec![0.0; dm.n_eq];
    for (c, xc) in x.iter().enumerate() {
        for p in kr.col_ptr()[c]..kr.col_ptr()[c + 1] {
            ax[kr.row_idx()[p]] += kr.val()[p] * xc;
        }
    }
    let res = ax
        .iter()
        .zip(&rhs)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt()
        / rhs.iter().map(|b| b * b).sum::<f64>().sqrt();
    println!(
        "hex8 cube {n}^3: {} elements, {} nodes, {} free DOFs, {} nonzeros",
        an.body.len(),
        an.mesh.nodes.len(),
        dm.n_eq,
        kr.val().len()
    );
    println!("threads:            {}", rayon::current_num_threads());
    println!(
        "ordering:           {}",
        if amd {
            "AMD (faer)"
        } else {
            "nested dissection"
        }
    );
    println!("setup (mesh+model): {:>8.3} s", setup.as_secs_f64());
    println!("sparsity pattern:   {:>8.3} s", t_pattern.as_secs_f64());
    println!("assembly:           {:>8.3} s", t_assembly.as_secs_f64());
    println!("symbolic analysis:  {:>8.3} s", t_symbolic.as_secs_f64());
    println!(
        "numeric factor:     {:>8.3} s  ({})",
        t_numeric.as_secs_f64(),
        factor.method()
    );
    println!("solve:              {:>8.3} s", t_solve.as_secs_f64());
    let (nnz_l, supernodal) = factor.factor_size();
    println!(
        "factor entries:     {nnz_l} ({})",
        if supernodal {
            "supernodal"
        } else {
            "simplicial"
        }
    );
    println!("relative residual:  {res:.2e}");
}
