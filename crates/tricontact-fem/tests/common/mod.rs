//! Shared helpers of the integration tests.
#![allow(dead_code)]

use std::path::Path;

use tricontact_fem::analysis::{Analysis, Boundary};
use tricontact_fem::assembly::NoExtra;
use tricontact_fem::driver::{IncrementInfo, RunSummary, run};
use tricontact_fem::mesh::Mesh;
use tricontact_fem::model::Model;
use tricontact_fem::results::boundary_reactions;

/// A linear elastic block of the structured box meshes, clamped at `xmin` (model text without
/// `[mesh]`, loads or steps).
pub const CLAMPED_BLOCK: &str = r#"
[[material]]
name = "m"
type = "linear_elastic"
E = 100.0
nu = 0.25
[[body]]
group = "solid"
material = "m"
[[boundary]]
group = "xmin"
fix = ["x", "y", "z"]
"#;

/// Model text without the `[mesh]` table, resolved against `mesh`.
pub fn analysis(mesh: Mesh, body: &str) -> Analysis {
    let text = format!("[mesh]\nfile = \"unused.msh\"\n{body}");
    let model = Model::parse(&text, Path::new("test.toml")).expect("valid model");
    Analysis::new(&model, mesh).expect("valid analysis")
}

/// One converged increment as recorded by the tests.
#[derive(Clone, Debug)]
pub struct Record {
    pub step: usize,
    pub increment: usize,
    pub load_factor: f64,
    pub iterations: usize,
    pub residuals: Vec<f64>,
    pub reference: f64,
    pub reactions: Vec<[f64; 3]>,
    pub u: Vec<f64>,
}

impl Record {
    /// The record of one converged increment.
    pub fn of(an: &Analysis, info: &IncrementInfo<'_>) -> Self {
        Self {
            step: info.step,
            increment: info.increment,
            load_factor: info.load_factor,
            iterations: info.iterations,
            residuals: info.residuals.to_vec(),
            reference: info.reference,
            reactions: boundary_reactions(an, info.step, info.reactions),
            u: info.u.to_vec(),
        }
    }
}

/// Runs the analysis and records every increment.
pub fn solve(an: &Analysis) -> (RunSummary, Vec<Record>) {
    let mut records = Vec::new();
    let summary = run(an, &mut NoExtra, &mut |info| {
        records.push(Record::of(an, info));
        Ok(())
    })
    .expect("run succeeds");
    (summary, records)
}

/// Prescribes `u(X)` on every node of `nodes`, one boundary per node.
pub fn prescribe_field(an: &mut Analysis, nodes: &[usize], field: impl Fn([f64; 3]) -> [f64; 3]) {
    let n_steps = an.steps.len();
    for &a in nodes {
        let v = field(an.mesh.nodes[a]);
        an.boundaries.push(Boundary {
            name: format!("node{a}"),
            nodes: vec![a],
            values: [Some(v[0]), Some(v[1]), Some(v[2])],
            active: vec![true; n_steps],
        });
    }
}

/// Nodes on the surface of the box `[0, size]`.
pub fn box_boundary_nodes(mesh: &Mesh, size: [f64; 3]) -> Vec<usize> {
    (0..mesh.nodes.len())
        .filter(|&a| {
            let p = mesh.nodes[a];
            (0..3).any(|i| p[i].abs() < 1e-12 * size[i] || (p[i] - size[i]).abs() < 1e-12 * size[i])
        })
        .collect()
}

/// Runs with the model's contact pairs; returns the contact terms at the end and the records.
pub fn solve_contact(
    an: &Analysis,
) -> (
    tricontact_fem::contact::ContactTerms,
    Vec<Record>,
    Vec<Vec<String>>,
) {
    let mut terms = tricontact_fem::contact::ContactTerms::new(an);
    let mut records = Vec::new();
    let mut notes = Vec::new();
    run(an, &mut terms, &mut |info| {
        records.push(Record::of(an, info));
        notes.push(info.notes.to_vec());
        Ok(())
    })
    .expect("run succeeds");
    (terms, records, notes)
}

/// Runs `examples/<dir>/<model>` (with `mesh` instead of its `[mesh] file` when given) as
/// `tricontact run` does, recording what the CLI records; nothing is written.
pub fn run_example(
    dir: &str,
    model: &str,
    mesh: Option<&str>,
) -> (RunSummary, tricontact_fem::report::RunRecord) {
    let (m, an) = example(dir, model, mesh);
    let hertz = m
        .hertz
        .as_ref()
        .map(|h| tricontact_fem::hertz::HertzSetup::resolve(h, &an).expect("[hertz] resolves"));
    let mut record = tricontact_fem::report::RunRecord::new(hertz);
    let mut terms = tricontact_fem::contact::ContactTerms::new(&an);
    let summary = run(&an, &mut terms, &mut |info| {
        record.record(&an, info);
        Ok(())
    })
    .expect("example runs");
    (summary, record)
}

/// `examples/<dir>/<model>` (with `mesh` instead of its `[mesh] file` when given), resolved.
pub fn example(dir: &str, model: &str, mesh: Option<&str>) -> (Model, Analysis) {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(dir);
    let mesh = mesh.map(|f| folder.join(f));
    let m = Model::load_with_mesh(&folder.join(model), mesh.as_deref()).expect("example model");
    let mesh = tricontact_fem::gmsh::read_msh(&m.mesh_path()).expect("example mesh");
    let an = Analysis::new(&m, mesh).expect("example analysis");
    (m, an)
}

/// One converged increment: its time and the contact history columns.
pub type HistoryRow = (f64, Vec<(String, f64)>);

/// Runs an example analysis with its contact pairs; returns the summary and, per converged
/// increment, its time and the contact history columns.
pub fn contact_history(an: &Analysis) -> (RunSummary, Vec<HistoryRow>) {
    let mut terms = tricontact_fem::contact::ContactTerms::new(an);
    let mut rows = Vec::new();
    let summary = run(an, &mut terms, &mut |info| {
        rows.push((info.time, info.history.to_vec()));
        Ok(())
    })
    .expect("example runs");
    (summary, rows)
}

/// The value of the contact history column ending in `key` (a pair's name, then `_normal_force`,
/// `_active`, …) at `terms`' committed state.
pub fn contact_column(terms: &tricontact_fem::contact::ContactTerms, key: &str) -> f64 {
    use tricontact_fem::assembly::ExtraTerms;
    terms
        .history()
        .into_iter()
        .find(|(k, _)| k.ends_with(key))
        .map(|(_, v)| v)
        .unwrap_or_else(|| panic!("no history column ending in {key}"))
}

/// The value of history column `name` in `row`.
pub fn column(row: &[(String, f64)], name: &str) -> f64 {
    row.iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| *v)
        .unwrap_or_else(|| panic!("no history column {name}"))
}

/// A history column of the last increment of a record.
pub fn last_column(record: &tricontact_fem::report::RunRecord, name: &str) -> f64 {
    record
        .last
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| *v)
        .unwrap_or_else(|| panic!("no history column {name}"))
}

/// Height of the V-groove's floor at `x` in [`v_groove`]: `1` outside `|x − 1| < 0.5`, down to
/// `0.75` at the valley line `x = 1` (flanks at 26.6°, a concave kink of 53° between them).
pub fn groove_top(x: f64) -> f64 {
    1.0 - 0.25 * (1.0 - (x - 1.0).abs() / 0.5).max(0.0)
}

/// A 2 × 1 × 1 base of `base` bricks with a V-groove along `y` in its top (`lower_*` groups)
/// and, as `upper_*`, a wedge of `wedge` bricks filling the groove between `x = 0.6` and `1.4`
/// (`y` from 0.1 to 0.9, top at `z = 1.3`), its bottom lying on the flanks; `kind` for both.
/// With an even number of bricks along `x` in the wedge, a row of its bottom nodes lies on the
/// valley line.
pub fn v_groove(
    base: [usize; 3],
    wedge: [usize; 3],
    kind: tricontact_fem::mesh::ElementKind,
) -> Mesh {
    let mut lower = tricontact_fem::structured::box_mesh([2.0, 1.0, 1.0], base, kind);
    for p in &mut lower.nodes {
        p[2] *= groove_top(p[0]);
    }
    let mut upper = tricontact_fem::structured::box_mesh([0.8, 0.8, 1.0], wedge, kind);
    for p in &mut upper.nodes {
        let (x, y, s) = (0.6 + p[0], 0.1 + p[1], p[2]);
        let bottom = groove_top(x);
        *p = [x, y, bottom + (1.3 - bottom) * s];
    }
    tricontact_fem::structured::stack(&lower, &upper, [0.0, 0.0, 0.0])
}

/// The model of [`v_groove`] (without `[mesh]`): a stiff base (`E` 1000) and a soft wedge (100),
/// neo-Hookean, the wedge's top pressed 0.04 down in four increments, with one `[[contact]]`
/// table whose keys are `contact`.
pub fn v_groove_model(contact: &str) -> String {
    format!(
        r#"
[[material]]
name = "base"
type = "neo_hooke"
E = 1000.0
nu = 0.3
[[material]]
name = "wedge"
type = "neo_hooke"
E = 100.0
nu = 0.3
[[body]]
group = "lower_solid"
material = "base"
[[body]]
group = "upper_solid"
material = "wedge"
[[boundary]]
group = "lower_zmin"
fix = ["x", "y", "z"]
[[boundary]]
group = "upper_zmax"
displacement = {{ x = 0.0, y = 0.0, z = -0.04 }}
[[contact]]
{contact}
[[step]]
name = "press"
increments = 4
nlgeom = true
"#
    )
}

/// The slave nodes closed on a second flank at the committed state (`contact::flank`): how
/// many, and the deepest penetration `−P_G` of those flanks (0 for none).
pub fn second_flanks(terms: &tricontact_fem::contact::ContactTerms) -> (usize, f64) {
    terms
        .states()
        .iter()
        .flatten()
        .flatten()
        .filter(|st| st.second.active)
        .fold((0, 0.0f64), |(n, deepest), st| {
            (n + 1, deepest.max(-st.second.gap))
        })
}
