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
//! as ASCII and as binary, and prints the sizes;
//! `--contact N [M]` only times a contact run: an `M × M × 2` hex8 block (default `M = N − 1`)
//! pressed onto an `N × N × 2` one, `(M + 1)²` slave nodes, with Lagrange multipliers and with
//! a penalty (one increment each); with `--multipliers-last` the multipliers are all ordered
//! after the displacements (the former ordering), for comparison;
//! `--inp FILE` writes, instead of solving, the CalculiX input deck of the cube (or with
//! `--contact`, of the penalty contact run), for `scripts/compare-calculix.sh`.

use std::path::PathBuf;
use std::time::Instant;

use tricontact_fem::analysis::Analysis;
use tricontact_fem::assembly::{DofMap, ExtraTerms, NoExtra, Pattern, assemble, node_adjacency};
use tricontact_fem::contact::ContactTerms;
use tricontact_fem::driver::{external_forces, run, step_constraints};
use tricontact_fem::linsolve::{LinearSolver, Structure};
use tricontact_fem::mesh::ElementKind;
use tricontact_fem::model::Model;
use tricontact_fem::ordering::equation_order;
use tricontact_fem::structured::{box_mesh, stack};
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
        integer: false,
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
            Field {
                integer: true,
                ..field("material", 1, &mat)
            },
        ],
        time: Some(1.0),
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

/// The model of [`contact_run`] for `method`.
fn contact_model(method: &str) -> String {
    format!(
        "[mesh]\nfile = \"none\"\n\
         [[material]]\nname = \"m\"\ntype = \"linear_elastic\"\nE = 1000.0\nnu = 0.3\n\
         [[body]]\ngroup = \"lower_solid\"\nmaterial = \"m\"\n\
         [[body]]\ngroup = \"upper_solid\"\nmaterial = \"m\"\n\
         [[boundary]]\ngroup = \"lower_zmin\"\nfix = [\"x\", \"y\", \"z\"]\n\
         [[boundary]]\ngroup = \"upper_zmax\"\ndisplacement = {{ x = 0.0, y = 0.0, z = -0.002 }}\n\
         [[contact]]\nslave = \"upper_zmin\"\nmaster = \"lower_zmax\"\nmethod = \"{method}\"\n\
         [[step]]\n"
    )
}

/// Contact terms whose multipliers are all ordered after the displacements (the former ordering),
/// for comparison: everything else delegates.
struct MultipliersLast(ContactTerms);

impl ExtraTerms for MultipliersLast {
    fn num_extra(&self) -> usize {
        self.0.num_extra()
    }
    fn symmetric(&self) -> bool {
        self.0.symmetric()
    }
    fn definite(&self) -> bool {
        self.0.definite()
    }
    fn nonlinear(&self) -> bool {
        self.0.nonlinear()
    }
    fn supports_bodies(&self) -> bool {
        self.0.supports_bodies()
    }
    fn begin_increment(&mut self, u: &[f64]) -> Result<(), String> {
        self.0.begin_increment(u)
    }
    fn add_terms(
        &mut self,
        u: &[f64],
        residual: &mut [f64],
        triplets: &mut Vec<(usize, usize, f64)>,
    ) -> Result<(), String> {
        self.0.add_terms(u, residual, triplets)
    }
    fn iteration_note(&self) -> Option<String> {
        self.0.iteration_note()
    }
    fn after_converged(&mut self, u: &[f64]) -> Result<bool, String> {
        self.0.after_converged(u)
    }
    fn commit(&mut self) {
        self.0.commit();
    }
    fn restore(&mut self) {
        self.0.restore();
    }
}

/// The path given after `--inp`, if any.
fn inp_path() -> Option<PathBuf> {
    std::env::args()
        .skip_while(|a| a != "--inp")
        .nth(1)
        .map(PathBuf::from)
}

/// Writes the CalculiX deck of `an` to `path` and prints what it approximates.
fn write_deck(an: &Analysis, path: &std::path::Path, title: &str) {
    match tricontact_fem::inp::write(an, title) {
        Ok(deck) => {
            for note in &deck.notes {
                println!("note: {note}");
            }
            if let Err(e) = tricontact_fem::atomic::write_atomic(path, deck.text.as_bytes()) {
                eprintln!("error: {e}");
                std::process::exit(1);
            }
            println!("wrote {}", path.display());
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}

/// Times a contact run with multipliers and with a penalty on two stacked hex8 blocks.
fn contact_run(n: usize, m: usize) {
    let lower = box_mesh([1.0, 1.0, 0.2], [n, n, 2], ElementKind::Hex8);
    let upper = box_mesh([0.9, 0.9, 0.2], [m, m, 2], ElementKind::Hex8);
    let mesh = stack(&lower, &upper, [0.05, 0.05, 0.2]);
    println!(
        "contact: hex8 {m}x{m}x2 block on {n}x{n}x2, {} nodes, {} slave nodes, {} threads",
        mesh.nodes.len(),
        (m + 1) * (m + 1),
        rayon::current_num_threads()
    );
    if let Some(path) = inp_path() {
        let model = Model::parse(
            &contact_model("penalty"),
            std::path::Path::new("bench.toml"),
        )
        .expect("valid model");
        let an = Analysis::new(&model, mesh).expect("valid analysis");
        write_deck(&an, &path, &format!("fem-bench --contact {n} {m}, penalty"));
        return;
    }
    let last = std::env::args().any(|a| a == "--multipliers-last");
    for method in ["multiplier", "penalty"] {
        let model = Model::parse(&contact_model(method), std::path::Path::new("bench.toml"))
            .expect("valid model");
        let an = Analysis::new(&model, mesh.clone()).expect("valid analysis");
        let mut terms: Box<dyn ExtraTerms> = if last && method == "multiplier" {
            Box::new(MultipliersLast(ContactTerms::new(&an)))
        } else {
            Box::new(ContactTerms::new(&an))
        };
        let t = Instant::now();
        let mut factor = String::new();
        let mut force = f64::NAN;
        let mut history = String::new();
        let pressed = &an.boundaries[1].nodes;
        let summary = run(&an, terms.as_mut(), &mut |info| {
            factor = info.method.to_string();
            force = pressed.iter().map(|&a| info.reactions[3 * a + 2]).sum();
            history = info
                .relative_residuals()
                .iter()
                .map(|r| format!("{r:.1e}"))
                .collect::<Vec<_>>()
                .join(" ");
            Ok(())
        });
        let secs = t.elapsed().as_secs_f64();
        match summary {
            Ok(s) => println!(
                "{method:>10}{}: {secs:>8.2} s, {} Newton iterations ({:.2} s each), {} cutbacks, {factor}, reaction on the pressed face {force:.6e}; relative residuals [{history}]",
                if last && method == "multiplier" {
                    " (last)"
                } else {
                    ""
                },
                s.iterations,
                secs / s.iterations.max(1) as f64,
                s.cutbacks
            ),
            Err(e) => println!("{method:>10}: failed after {secs:.2} s: {e}"),
        }
    }
}

/// The value of `r`, or its error printed after `what` and the process ended with status 1.
fn or_exit<T, E: std::fmt::Display>(r: Result<T, E>, what: &str) -> T {
    r.unwrap_or_else(|e| {
        eprintln!("error: {what}{e}");
        std::process::exit(1);
    })
}

/// The number after the argument `flag`, if both are given.
fn after<T: std::str::FromStr>(flag: &str, skip: usize) -> Option<T> {
    std::env::args()
        .skip_while(|a| a != flag)
        .nth(1 + skip)
        .and_then(|s| s.parse().ok())
}

fn main() {
    if let Some(n) = after::<usize>("--contact", 0) {
        let m = after("--contact", 1).unwrap_or(n.saturating_sub(1).max(1));
        contact_run(n, m);
        return;
    }
    let first_number = || std::env::args().filter_map(|s| s.parse().ok()).next();
    if std::env::args().any(|a| a == "--vtu") {
        vtu_encoding(first_number().unwrap_or(45));
        return;
    }
    if let Some(m) = after("--dense", 0) {
        dense_reference(m);
        return;
    }
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(45);
    let t = Instant::now();
    let an = cube(n);
    let setup = t.elapsed();
    if let Some(path) = inp_path() {
        write_deck(&an, &path, &format!("fem-bench {n}: hex8 cube"));
        return;
    }
    solve_cube(&an, n, std::env::args().any(|a| a == "--amd"), setup);
}

/// The `n × n × n` hex8 unit cube, clamped at `z = 0` and pressed at `z = 1`.
fn cube(n: usize) -> Analysis {
    let mesh = box_mesh([1.0, 1.0, 1.0], [n, n, n], ElementKind::Hex8);
    let text = "[mesh]\nfile = \"none\"\n[[material]]\nname = \"m\"\ntype = \"linear_elastic\"\nE = 1000.0\nnu = 0.3\n[[body]]\ngroup = \"solid\"\nmaterial = \"m\"\n[[boundary]]\ngroup = \"zmin\"\nfix = [\"x\", \"y\", \"z\"]\n[[load]]\ngroup = \"zmax\"\npressure = 1.0\n[[step]]\n";
    let model = or_exit(Model::parse(text, std::path::Path::new("bench.toml")), "");
    or_exit(Analysis::new(&model, mesh), "")
}

/// Times each phase of one linear solve of `an` (the cube of size `n`; with `amd`, faer's AMD
/// ordering instead of the nested dissection) and prints the times (with the `setup` before it),
/// the sizes and the residual.
fn solve_cube(an: &Analysis, n: usize, amd: bool, setup: std::time::Duration) {
    let (mask, _) = step_constraints(an, 0);
    let dm = DofMap::new(&an.active_nodes, &mask, 0);
    let t = Instant::now();
    let adj = node_adjacency(an);
    let pat = Pattern::from_adjacency(&adj, an, &dm);
    let order = (!amd).then(|| equation_order(&an.mesh.nodes, &adj, &dm, (&[], &[])));
    drop(adj);
    let t_pattern = t.elapsed();
    let u = vec![0.0; an.num_nodal_dofs()];
    let t = Instant::now();
    let asm = or_exit(
        assemble(an, &dm, &pat, &u, false, true, None, &mut NoExtra).map_err(|e| format!("{e:?}")),
        "assembly failed: ",
    );
    let t_assembly = t.elapsed();
    let k = asm.matrix(&pat);
    let f = external_forces(an, an.num_nodal_dofs(), 0, 1.0);
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
    or_exit(solver.analyze(k.as_ref()).map_err(|e| e.0), "");
    let t_symbolic = t.elapsed();
    let t = Instant::now();
    let factor = or_exit(
        solver
            .factor(k.as_ref(), Structure::SymmetricDefinite)
            .map_err(|e| e.0),
        "",
    );
    let t_numeric = t.elapsed();
    let t = Instant::now();
    let x = factor.solve(&rhs);
    let t_solve = t.elapsed();
    let kr = k.as_ref();
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
    println!(
        "relative residual:  {:.2e}",
        relative_residual(kr, &x, &rhs)
    );
}

/// `‖K x − b‖ / ‖b‖`.
fn relative_residual(
    k: faer::sparse::SparseColMatRef<'_, usize, f64>,
    x: &[f64],
    b: &[f64],
) -> f64 {
    let mut kx = vec![0.0; b.len()];
    for (c, xc) in x.iter().enumerate() {
        for p in k.col_ptr()[c]..k.col_ptr()[c + 1] {
            kx[k.row_idx()[p]] += k.val()[p] * xc;
        }
    }
    let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|r| r * r).sum::<f64>().sqrt();
    norm(&mut kx.iter().zip(b).map(|(a, b)| a - b)) / norm(&mut b.iter().copied())
}
