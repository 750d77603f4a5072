//! Result files of a run, all written atomically (see [`crate::atomic`]):
//!
//! * `<stem>_<step>_<increment>.vtu` per converged increment (every
//!   `output.every`-th and the last of each step): point data
//!   `displacement`, `reaction`, `stress` (nodal average of element Cauchy
//!   stress), `von_mises`; cell data `stress`, `von_mises`, `material`; the faces of rigid
//!   contact surfaces are cells after the elements (material −1, zero stress);
//! * `<stem>.pvd`: the collection, `timestep` = step index + load factor,
//!   rewritten after each `.vtu` so ParaView can open a running job;
//! * `history.csv`: one row per converged increment (rewritten when due, see
//!   [`crate::throttle`], and by [`ResultWriter::finish`]): step, name, increment,
//!   load factor, time, iterations, final residual norm and relative
//!   residual, then `Rx, Ry, Rz` summed over each boundary group, then the
//!   columns of the extra terms (contact: see [`crate::contact`]); names
//!   holding a comma, quote or line break are quoted
//!   ([`crate::report::csv_field`], RFC 4180);
//! * extra point fields of the extra terms (contact) in every `.vtu`.
//!
//! When a run fails, [`ResultWriter::finish`] writes the last converged increment's `.vtu` if
//! `output.every` had skipped it, so that the state the run reached can be opened, and
//! `history.csv` even when no increment converged (its header alone; the extra terms' columns
//! are in it when [`ResultWriter::extra_columns`] named them).
//!
//! Files of an earlier run that this run would write under the same names
//! (`<stem>.pvd`, `<stem>_<step>_<increment>.vtu`, `history.csv` and the
//! tables and charts of [`crate::report`]) are removed first, so that even
//! after a failed run the folder holds only what this run wrote; other files
//! are left alone.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::analysis::Analysis;
use crate::assembly::PointField;
use crate::atomic::write_atomic;
use crate::driver::IncrementInfo;
use crate::error::{FemError, Result};
use crate::report::{FILE_NAMES, csv_field};
use crate::results::{boundary_reactions, stress_fields};
use crate::throttle::Throttle;
use crate::vtu::{Field, Grid, pvd_string, vtk_cell, vtu_string};

/// `history.csv`: one row per converged increment.
const HISTORY_CSV: &str = "history.csv";

/// Whether `name` is `<stem>_<step>_<increment>.vtu`, a `.vtu` of the model `stem`: at least 3
/// and 4 digits (the padding of the names, which grow past it from step 1000 and increment
/// 10000).
fn is_model_vtu(name: &str, stem: &str) -> bool {
    let Some(core) = name
        .strip_prefix(stem)
        .and_then(|r| r.strip_prefix('_'))
        .and_then(|r| r.strip_suffix(".vtu"))
    else {
        return false;
    };
    let numeric = |s: &str, n: usize| s.len() >= n && s.bytes().all(|b| b.is_ascii_digit());
    matches!(core.split_once('_'), Some((s, i)) if numeric(s, 3) && numeric(i, 4))
}

/// The faces of the contact surfaces that touch no body element (a rigid master: a surface
/// group without volume elements), each once, in element order. They are written as cells after
/// the body elements, so that ParaView draws the rigid surface and its nodes' fields.
fn rigid_faces(an: &Analysis) -> Vec<usize> {
    let mut in_body = vec![false; an.mesh.nodes.len()];
    for b in &an.body {
        for &a in &an.mesh.elements[b.element].nodes {
            in_body[a] = true;
        }
    }
    let mut faces: Vec<usize> = an
        .contacts
        .iter()
        .flat_map(|c| [&c.master_group, &c.slave_group])
        .filter_map(|name| {
            an.mesh
                .groups
                .iter()
                .find(|g| &g.name == name && g.dim == 2)
        })
        .flat_map(|g| g.elements.iter().copied())
        .filter(|&e| an.mesh.elements[e].nodes.iter().all(|&a| !in_body[a]))
        .collect();
    faces.sort_unstable();
    faces.dedup();
    faces
}

/// Removes `path`; one that is not there is fine.
fn remove_if_present(path: &Path) -> Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(FemError::io(path, e)),
        _ => Ok(()),
    }
}

/// Removes the files of an earlier run that this run would write under the same names: the
/// `.pvd` first (so it never lists missing files), `history.csv`, the tables and charts of
/// [`crate::report`], then the model's `.vtu` files.
fn remove_stale(dir: &Path, stem: &str) -> Result<()> {
    remove_if_present(&dir.join(format!("{stem}.pvd")))?;
    for name in std::iter::once(HISTORY_CSV).chain(FILE_NAMES) {
        remove_if_present(&dir.join(name))?;
    }
    let entries = std::fs::read_dir(dir).map_err(|e| FemError::io(dir, e))?;
    for entry in entries.flatten() {
        if is_model_vtu(&entry.file_name().to_string_lossy(), stem) {
            remove_if_present(&entry.path())?;
        }
    }
    Ok(())
}

/// Writes the result files of one run.
#[derive(Debug)]
pub struct ResultWriter {
    dir: PathBuf,
    stem: String,
    cells: Vec<(u8, Vec<usize>)>,
    /// Cells after the body elements' (the last ones of `cells`): faces of rigid contact
    /// surfaces ([`rigid_faces`]).
    rigid_faces: usize,
    pvd: Vec<(f64, String)>,
    history: String,
    header_done: bool,
    /// Rows added since `history.csv` was last written.
    history_pending: bool,
    rewrites: Throttle,
    /// The last converged increment when its `.vtu` was skipped (`output.every`).
    pending: Option<Snapshot>,
    /// Paths written so far.
    pub written: Vec<PathBuf>,
}

/// What a `.vtu` shows of a converged increment.
#[derive(Debug, Clone, Copy)]
struct State<'a> {
    step: usize,
    increment: usize,
    time: f64,
    nlgeom: bool,
    u: &'a [f64],
    reactions: &'a [f64],
    point_fields: &'a [PointField],
}

/// A [`State`] kept after its increment.
#[derive(Debug, Clone)]
struct Snapshot {
    step: usize,
    increment: usize,
    time: f64,
    nlgeom: bool,
    u: Vec<f64>,
    reactions: Vec<f64>,
    point_fields: Vec<PointField>,
}

impl Snapshot {
    fn of(s: &State<'_>) -> Self {
        Self {
            step: s.step,
            increment: s.increment,
            time: s.time,
            nlgeom: s.nlgeom,
            u: s.u.to_vec(),
            reactions: s.reactions.to_vec(),
            point_fields: s.point_fields.to_vec(),
        }
    }

    fn state(&self) -> State<'_> {
        State {
            step: self.step,
            increment: self.increment,
            time: self.time,
            nlgeom: self.nlgeom,
            u: &self.u,
            reactions: &self.reactions,
            point_fields: &self.point_fields,
        }
    }
}

/// An extra column's value: a whole number (a count of closed nodes, a force of exactly zero)
/// as an integer, `36` rather than `3.6e1`; any other value in exponent form, exact.
fn extra_cell(v: f64) -> String {
    // Below 2⁵³ every whole f64 is an exact i64.
    if v.fract() == 0.0 && v.abs() < 9_007_199_254_740_992.0 {
        #[allow(clippy::cast_possible_truncation)]
        let n = v as i64;
        n.to_string()
    } else {
        format!("{v:e}")
    }
}

impl ResultWriter {
    /// Creates the folder and the history header.
    ///
    /// # Errors
    /// When the folder cannot be created.
    pub fn new(an: &Analysis, dir: &Path, stem: &str) -> Result<Self> {
        if dir.exists() && !dir.is_dir() {
            return Err(FemError::Output(format!(
                "{}: exists and is not a folder (the result folder)",
                dir.display()
            )));
        }
        std::fs::create_dir_all(dir).map_err(|e| {
            FemError::Output(format!(
                "cannot create the result folder {}: {e}",
                dir.display()
            ))
        })?;
        remove_stale(dir, stem)?;
        let rigid = rigid_faces(an);
        let cells = an
            .body
            .iter()
            .map(|b| b.element)
            .chain(rigid.iter().copied())
            .map(|e| {
                let el = &an.mesh.elements[e];
                vtk_cell(el.kind, &el.nodes)
            })
            .collect();
        let mut history = String::from(
            "step,step_name,increment,load_factor,time,iterations,residual,relative_residual",
        );
        for (i, b) in an.boundaries.iter().enumerate() {
            // Two boundaries on one group get distinct columns: `name`, `name#2`, …
            let same = an.boundaries[..i]
                .iter()
                .filter(|o| o.name == b.name)
                .count();
            let name = if same == 0 {
                b.name.clone()
            } else {
                format!("{}#{}", b.name, same + 1)
            };
            for axis in ["Rx", "Ry", "Rz"] {
                let _ = write!(history, ",{}", csv_field(&format!("{name}_{axis}")));
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            stem: stem.to_string(),
            cells,
            rigid_faces: rigid.len(),
            pvd: Vec::new(),
            history,
            header_done: false,
            history_pending: false,
            rewrites: Throttle::default(),
            pending: None,
            written: Vec::new(),
        })
    }

    /// Writes what [`ResultWriter::write`] left pending: `history.csv`, and the last converged
    /// increment's `.vtu` when `output.every` skipped it (a run that failed). Call it once the
    /// run ended, whether it succeeded or not.
    ///
    /// # Errors
    /// I/O errors.
    pub fn finish(&mut self, an: &Analysis) -> Result<()> {
        if an.output.history && !self.written.contains(&self.dir.join(HISTORY_CSV)) {
            // No increment converged: the header alone, so that the table is there to read.
            self.close_header();
            self.history_pending = true;
        }
        if self.history_pending {
            self.write_history()?;
        }
        if let Some(last) = self.pending.take() {
            self.write_vtu(an, &last.state())?;
        }
        Ok(())
    }

    /// Completes the `history.csv` header with the extra terms' columns (the names of
    /// [`IncrementInfo::history`], e.g. from [`crate::assembly::ExtraTerms::history`] before the
    /// run), so that a run whose first increment fails still writes the whole header. Without
    /// it, the first converged increment completes the header. Does nothing once it is complete.
    pub fn extra_columns<'a>(&mut self, names: impl IntoIterator<Item = &'a str>) {
        if self.header_done {
            return;
        }
        for name in names {
            let _ = write!(self.history, ",{}", csv_field(name));
        }
        self.close_header();
    }

    fn close_header(&mut self) {
        if !self.header_done {
            self.history.push('\n');
            self.header_done = true;
        }
    }

    fn write_history(&mut self) -> Result<()> {
        let started = std::time::Instant::now();
        let p = self.dir.join(HISTORY_CSV);
        write_atomic(&p, self.history.as_bytes())?;
        if !self.written.contains(&p) {
            self.written.push(p);
        }
        self.history_pending = false;
        self.rewrites.wrote(started);
        Ok(())
    }

    /// Records one converged increment.
    ///
    /// # Errors
    /// I/O errors.
    pub fn write(&mut self, an: &Analysis, info: &IncrementInfo<'_>) -> Result<()> {
        if !self.header_done {
            // Extra columns (contact) not named by `extra_columns`: from the first increment.
            self.extra_columns(info.history.iter().map(|(name, _)| name.as_str()));
        }
        let last = info.residuals.last().copied().unwrap_or(0.0);
        let _ = write!(
            self.history,
            "{},{},{},{},{},{},{:e},{:e}",
            info.step + 1,
            csv_field(info.step_name),
            info.increment,
            info.load_factor,
            info.time,
            info.iterations,
            last,
            if info.reference > 0.0 {
                last / info.reference
            } else {
                0.0
            }
        );
        for r in boundary_reactions(an, info.step, info.reactions) {
            let _ = write!(self.history, ",{:e},{:e},{:e}", r[0], r[1], r[2]);
        }
        for (_, v) in info.history {
            let _ = write!(self.history, ",{}", extra_cell(*v));
        }
        self.history.push('\n');
        if an.output.history {
            self.history_pending = true;
            if self.rewrites.due() {
                self.write_history()?;
            }
        }
        if !an.output.vtu {
            return Ok(());
        }
        let state = State {
            step: info.step,
            increment: info.increment,
            time: info.time,
            nlgeom: info.nlgeom,
            u: info.u,
            reactions: info.reactions,
            point_fields: info.point_fields,
        };
        let every = an.output.every.max(1);
        if info.increment.is_multiple_of(every) || info.load_factor >= 1.0 {
            self.pending = None;
            self.write_vtu(an, &state)
        } else {
            self.pending = Some(Snapshot::of(&state));
            Ok(())
        }
    }

    /// Writes the `.vtu` of `info` and rewrites the `.pvd`.
    fn write_vtu(&mut self, an: &Analysis, info: &State<'_>) -> Result<()> {
        let name = format!(
            "{}_{:03}_{:04}.vtu",
            self.stem,
            info.step + 1,
            info.increment
        );
        let n = an.mesh.nodes.len();
        let mut fields = stress_fields(an, info.u, info.nlgeom);
        // Rigid faces carry no stress; their material is −1.
        let rigid = self.rigid_faces;
        fields
            .cell_stress
            .resize(fields.cell_stress.len() + 6 * rigid, 0.0);
        fields
            .cell_von_mises
            .resize(fields.cell_von_mises.len() + rigid, 0.0);
        let material: Vec<f64> = an
            .body
            .iter()
            .map(|b| b.material as f64)
            .chain(std::iter::repeat_n(-1.0, rigid))
            .collect();
        let field = |name, components, values, integer| Field {
            name,
            components,
            values,
            integer,
        };
        let mut point_data = vec![
            field("displacement", 3, &info.u[..3 * n], false),
            field("reaction", 3, &info.reactions[..3 * n], false),
            field("stress", 6, &fields.point_stress, false),
            field("von_mises", 1, &fields.point_von_mises, false),
        ];
        for f in info.point_fields {
            point_data.push(field(&f.name, f.components, &f.values, f.integer));
        }
        let grid = Grid {
            points: &an.mesh.nodes,
            cells: &self.cells,
            point_data,
            cell_data: vec![
                field("stress", 6, &fields.cell_stress, false),
                field("von_mises", 1, &fields.cell_von_mises, false),
                field("material", 1, &material, true),
            ],
            time: Some(info.time),
        };
        let xml =
            vtu_string(&grid, an.output.vtu_format).map_err(|e| FemError::Output(e.to_string()))?;
        let path = self.dir.join(&name);
        write_atomic(&path, xml.as_bytes())?;
        self.written.push(path);
        self.pvd.push((info.time, name));
        let pvd = pvd_string(&self.pvd).map_err(|e| FemError::Output(e.to_string()))?;
        let p = self.dir.join(format!("{}.pvd", self.stem));
        write_atomic(&p, pvd.as_bytes())?;
        if !self.written.contains(&p) {
            self.written.push(p);
        }
        Ok(())
    }
}
