//! The TOML model file: schema, defaults and loading.
//!
//! Every table rejects unknown keys (`deny_unknown_fields`). Relative paths
//! (mesh file, output folder) are resolved against the model file's folder.
//! Syntax and schema errors report the line and column of the offending key.
//! The repository README ("Model-file reference") documents every key with a complete example.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{FemError, Result};
use crate::gmsh;
use crate::mesh::Mesh;
use crate::source::SourceMap;
use crate::vtu::VtuFormat;

/// A whole model file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Model {
    /// Mesh input.
    pub mesh: MeshDef,
    /// Materials.
    #[serde(default, rename = "material")]
    pub materials: Vec<MaterialDef>,
    /// Bodies: a volume group with a material.
    #[serde(default, rename = "body")]
    pub bodies: Vec<BodyDef>,
    /// Supports and prescribed displacements.
    #[serde(default, rename = "boundary")]
    pub boundaries: Vec<BoundaryDef>,
    /// Forces and pressures.
    #[serde(default, rename = "load")]
    pub loads: Vec<LoadDef>,
    /// Contact pairs.
    #[serde(default, rename = "contact")]
    pub contacts: Vec<ContactDef>,
    /// Analysis steps, run in order.
    #[serde(default, rename = "step")]
    pub steps: Vec<StepDef>,
    /// Result files.
    #[serde(default)]
    pub output: OutputDef,
    /// Comparison of a contact pair with Hertz theory (optional).
    pub hertz: Option<HertzDef>,
    /// Folder of the model file (set by [`Model::load`]).
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// Lines of the model file's tables and keys, for messages (set by [`Model::parse`]; empty
    /// for a model built in code).
    #[serde(skip)]
    pub source: SourceMap,
}

/// `[mesh]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshDef {
    /// Gmsh 4.1 file, relative to the model file.
    pub file: PathBuf,
}

/// Constitutive model keyword.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum MaterialKind {
    /// Linear elastic (Saint-Venant–Kirchhoff when `nlgeom`).
    LinearElastic,
    /// Compressible neo-Hookean.
    NeoHooke,
}

/// `[[material]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialDef {
    /// Name referenced by bodies.
    pub name: String,
    /// Law.
    #[serde(rename = "type")]
    pub kind: MaterialKind,
    /// Young's modulus (`E`, alias `youngs_modulus`).
    #[serde(rename = "E", alias = "youngs_modulus")]
    pub e: f64,
    /// Poisson's ratio (`nu`, alias `poisson_ratio`).
    #[serde(alias = "poisson_ratio")]
    pub nu: f64,
}

/// `[[body]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BodyDef {
    /// 3D physical group.
    pub group: String,
    /// Material name.
    pub material: String,
}

/// A displacement component.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Component {
    /// x.
    X,
    /// y.
    Y,
    /// z.
    Z,
}

impl Component {
    /// 0, 1 or 2.
    #[must_use]
    pub fn index(self) -> usize {
        match self {
            Self::X => 0,
            Self::Y => 1,
            Self::Z => 2,
        }
    }
}

/// Prescribed displacement components (any subset), written as a table: `{ x = 0.1, z = -0.05 }`.
/// An array is refused (its values would be taken in order and any beyond the third ignored).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Displacement {
    /// x component.
    pub x: Option<f64>,
    /// y component.
    pub y: Option<f64>,
    /// z component.
    pub z: Option<f64>,
}

impl<'de> Deserialize<'de> for Displacement {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        /// The table's keys.
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Table {
            x: Option<f64>,
            y: Option<f64>,
            z: Option<f64>,
        }
        /// Accepts a table only.
        struct OnlyTable;
        impl<'de> serde::de::Visitor<'de> for OnlyTable {
            type Value = Displacement;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a table of components, such as { x = 0.1, z = -0.05 }")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> std::result::Result<Displacement, A::Error> {
                let t = Table::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(Displacement {
                    x: t.x,
                    y: t.y,
                    z: t.z,
                })
            }
        }
        d.deserialize_map(OnlyTable)
    }
}

/// `[[boundary]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoundaryDef {
    /// Group of any dimension (its nodes).
    pub group: String,
    /// Components held at zero.
    #[serde(default)]
    pub fix: Vec<Component>,
    /// Components prescribed to reach these values at the end of the step.
    pub displacement: Option<Displacement>,
    /// Names of the steps in which it is active (default: all).
    pub steps: Option<Vec<String>>,
}

/// `[[load]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LoadDef {
    /// Group: a node group for `force`, a 2D group for `pressure`.
    pub group: String,
    /// Total force vector applied to the group.
    #[serde(default, deserialize_with = "three_opt")]
    pub force: Option<[f64; 3]>,
    /// Pressure (positive pushes into the body), dead load on the reference surface.
    pub pressure: Option<f64>,
    /// Pressure follows the deformed surface in `nlgeom` steps.
    #[serde(default)]
    pub follower: bool,
    /// Names of the steps in which it is active (default: all).
    pub steps: Option<Vec<String>>,
}

/// Contact enforcement method.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ContactMethod {
    /// Penalty `αP` on penetrating nodes.
    Penalty,
    /// Lagrange multipliers (one unknown per slave node, two with finite sliding for a second
    /// flank at concave kinks; primal–dual active set).
    Multiplier,
    /// Augmented Lagrangian: penalty plus Uzawa multiplier updates.
    Augmented,
}

impl ContactMethod {
    /// The method as the model file spells it (`method = "…"`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Penalty => "penalty",
            Self::Multiplier => "multiplier",
            Self::Augmented => "augmented",
        }
    }
}

impl std::fmt::Display for ContactMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// `[[contact]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ContactDef {
    /// Surface or node group: its nodes are the slave nodes.
    pub slave: String,
    /// Surface group: its faces are the master facets (the slave group itself for self-contact).
    pub master: String,
    /// Enforcement method.
    pub method: ContactMethod,
    /// Penalty factor (force per length); default `10 E h` (see the README, `[[contact]]`).
    pub penalty: Option<f64>,
    /// Also constrain the master nodes against the slave surface.
    #[serde(default)]
    pub two_pass: bool,
    /// Initial penetrations up to this distance are removed by moving slave
    /// nodes onto the master surface (strain-free).
    pub adjust: Option<f64>,
    /// Augmented Lagrangian: largest gap `|P|` of a closed node allowed,
    /// relative to the mean master facet edge length.
    #[serde(default = "default_contact_tolerance")]
    pub tolerance: f64,
    /// Keep each node's facet, shape functions and normal from the start of
    /// the increment.
    #[serde(default)]
    pub small_sliding: bool,
}

impl ContactDef {
    /// `true` for the contact of a surface group with itself (slave = master; see
    /// [`crate::contact::pair`], "Self-contact").
    #[must_use]
    pub fn is_self_contact(&self) -> bool {
        self.slave == self.master
    }
}

fn default_contact_tolerance() -> f64 {
    1e-4
}

/// `[[step]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StepDef {
    /// Name (default `step-<n>`).
    pub name: Option<String>,
    /// Number of equal increments initially tried.
    #[serde(default = "default_increments")]
    pub increments: usize,
    /// Newton iterations allowed per increment.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Relative residual tolerance.
    #[serde(default = "default_tol")]
    pub residual_tolerance: f64,
    /// Relative displacement-correction tolerance.
    #[serde(default = "default_tol")]
    pub displacement_tolerance: f64,
    /// Geometric nonlinearity (total-Lagrangian finite strain).
    #[serde(default)]
    pub nlgeom: bool,
    /// How many times an increment may be halved.
    #[serde(default = "default_cutbacks")]
    pub max_cutbacks: usize,
    /// Newton's starting point for the second and later increments of the step.
    #[serde(default)]
    pub extrapolation: Extrapolation,
    /// Line search along each Newton correction (where the residual is an energy gradient).
    #[serde(default)]
    pub line_search: LineSearchMode,
}

/// When a step's Newton corrections are line-searched (`[[step]] line_search`: `true`, `false`
/// or `"auto"`). The line search applies only where the residual is an energy gradient (no
/// multipliers, no follower pressure).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LineSearchMode {
    /// Never (`false`).
    Off,
    /// Every correction after the predictor (`true`).
    On,
    /// Off until an attempt inverts an element where the line search applies; that increment is
    /// then retried at the same size with the line search, which stays on for the rest of the
    /// step (`"auto"`, the default).
    #[default]
    Auto,
}

/// As written in a model file: `true`, `false` or `"auto"`.
impl std::fmt::Display for LineSearchMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Off => "false",
            Self::On => "true",
            Self::Auto => "\"auto\"",
        })
    }
}

impl<'de> Deserialize<'de> for LineSearchMode {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = LineSearchMode;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("true, false or \"auto\"")
            }
            fn visit_bool<E: serde::de::Error>(
                self,
                v: bool,
            ) -> std::result::Result<Self::Value, E> {
                Ok(if v {
                    LineSearchMode::On
                } else {
                    LineSearchMode::Off
                })
            }
            fn visit_str<E: serde::de::Error>(
                self,
                v: &str,
            ) -> std::result::Result<Self::Value, E> {
                match v {
                    "auto" => Ok(LineSearchMode::Auto),
                    _ => Err(E::invalid_value(serde::de::Unexpected::Str(v), &self)),
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// Where Newton starts an increment (`[[step]] extrapolation`).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Extrapolation {
    /// From the last converged state plus the previous increment of the step, scaled to the new
    /// increment's size (the first increment of a step, and the retry after a cutback, start from
    /// the last converged state).
    #[default]
    Linear,
    /// From the last converged state.
    None,
}

fn default_increments() -> usize {
    1
}
fn default_max_iterations() -> usize {
    20
}
fn default_tol() -> f64 {
    1e-8
}
fn default_cutbacks() -> usize {
    5
}

/// `[output]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputDef {
    /// Result folder, relative to the model file.
    #[serde(default = "default_folder")]
    pub folder: PathBuf,
    /// Write a `.vtu` per converged increment and the `.pvd` collection.
    #[serde(default = "yes")]
    pub vtu: bool,
    /// Write `history.csv`.
    #[serde(default = "yes")]
    pub history: bool,
    /// Write a `.vtu` every `every`-th increment (the last of each step always).
    #[serde(default = "one")]
    pub every: usize,
    /// Encoding of the `.vtu` data arrays.
    #[serde(default)]
    pub vtu_format: VtuFormat,
    /// Write PNG plots (Newton residuals, contact force, Hertz comparison) at the end of the run.
    #[serde(default)]
    pub plots: bool,
}

/// `[hertz]`: compare a contact pair with Hertz theory for a sphere on a flat.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HertzDef {
    /// Contact pair `slave-master` (default: the only pair).
    pub contact: Option<String>,
    /// Sphere radius `R`.
    pub radius: f64,
    /// Contact modulus `E*` (default: `E/(1 − ν²)` of the slave body, master rigid).
    pub modulus: Option<f64>,
    /// Point of first contact; radii are measured from the axis through it.
    #[serde(default, deserialize_with = "three")]
    pub centre: [f64; 3],
    /// Load axis, pointing from the flat into the sphere.
    #[serde(default = "default_axis", deserialize_with = "three")]
    pub axis: [f64; 3],
    /// The model is `1/symmetry` of the full contact (quarter model: 4).
    #[serde(default = "one")]
    pub symmetry: usize,
    /// Group whose mean displacement against `axis` is reported as the approach.
    pub loaded: String,
}

/// Exactly three numbers: serde's fixed-size arrays read the first three entries of a longer
/// TOML array and ignore the rest.
fn three<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<[f64; 3], D::Error> {
    let v: Vec<f64> = Vec::deserialize(d)?;
    <[f64; 3]>::try_from(v.as_slice())
        .map_err(|_| serde::de::Error::invalid_length(v.len(), &"an array of 3 numbers"))
}

/// [`three`] for an optional key.
fn three_opt<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Option<[f64; 3]>, D::Error> {
    three(d).map(Some)
}

fn default_axis() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

fn default_folder() -> PathBuf {
    PathBuf::from("results")
}
fn yes() -> bool {
    true
}
fn one() -> usize {
    1
}

impl Default for OutputDef {
    fn default() -> Self {
        Self {
            folder: default_folder(),
            vtu: true,
            history: true,
            every: 1,
            vtu_format: VtuFormat::default(),
            plots: false,
        }
    }
}

impl Model {
    /// Reads and parses a model file.
    ///
    /// # Errors
    /// I/O error, or a syntax/schema error with line and column.
    pub fn load(path: &Path) -> Result<Self> {
        // A device or a pipe (`/dev/zero`, a fifo) would be read until memory runs out, or
        // forever.
        let meta = std::fs::metadata(path).map_err(|e| FemError::io(path, e))?;
        if !meta.is_file() {
            return Err(FemError::ModelSyntax {
                path: path.to_path_buf(),
                at: String::new(),
                message: "not a regular file (a model is a .toml file)".into(),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|e| FemError::io(path, e))?;
        let mut model = Self::parse(&text, path)?;
        model.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok(model)
    }

    /// Reads a model file and, when `mesh` is given, uses that mesh instead of `[mesh] file`
    /// (`mesh` relative to the current folder, as on a command line).
    ///
    /// # Errors
    /// As [`Model::load`]; the current folder cannot be read.
    pub fn load_with_mesh(path: &Path, mesh: Option<&Path>) -> Result<Self> {
        let mut model = Self::load(path)?;
        if let Some(m) = mesh {
            model.mesh.file = std::path::absolute(m).map_err(|e| FemError::io(m, e))?;
            // Problems with this mesh are the command line's, not the model file's.
            model.source.forget("mesh");
        }
        Ok(model)
    }

    /// Parses model text (`path` only for messages).
    ///
    /// # Errors
    /// A syntax/schema error with line and column.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        crate::sections::check(text, path)?;
        let mut model: Self = toml::from_str(text).map_err(|e| {
            let mut message = plain_types(&e.message().trim().replace('\n', " "));
            // The parser's "duplicate key" does not say which: its span covers the key.
            if message == "duplicate key"
                && let Some(key) = e.span().and_then(|s| text.get(s)).map(str::trim)
                && !key.is_empty()
            {
                message = format!("duplicate key `{key}`");
            }
            let at = e
                .span()
                .map(|s| {
                    let (line, col) = line_col(text, s.start);
                    format!(":{line}:{col}")
                })
                .unwrap_or_default();
            FemError::ModelSyntax {
                path: path.to_path_buf(),
                at,
                message,
            }
        })?;
        model.source = SourceMap::new(text, path);
        if model.mesh.file.as_os_str().is_empty() {
            let at = model
                .source
                .line("mesh", 0, "file")
                .map(|n| format!(":{n}"))
                .unwrap_or_default();
            return Err(FemError::ModelSyntax {
                path: path.to_path_buf(),
                at,
                message:
                    "[mesh] file is empty (give the .msh file, relative to the model's folder)"
                        .into(),
            });
        }
        Ok(model)
    }

    /// Reads the mesh ([`Model::mesh_path`]). A file that cannot be opened, or is not a regular
    /// file, is a problem of the model, reported at its `[mesh] file` line.
    ///
    /// # Errors
    /// As [`gmsh::read_msh`].
    pub fn read_mesh(&self) -> Result<Mesh> {
        let path = self.mesh_path();
        gmsh::read_msh(&path).map_err(|e| {
            let reason = match &e {
                FemError::Io { source, .. } => source.to_string(),
                FemError::Mesh { message, .. } if !path.is_file() => message.clone(),
                _ => return e,
            };
            let at = self.source.at("mesh", 0, "file");
            FemError::Invalid(vec![format!("{at}mesh {}: {reason}", path.display())])
        })
    }

    /// The mesh path resolved against the model folder.
    #[must_use]
    pub fn mesh_path(&self) -> PathBuf {
        self.base_dir.join(&self.mesh.file)
    }

    /// The output folder resolved against the model folder.
    #[must_use]
    pub fn output_dir(&self) -> PathBuf {
        self.base_dir.join(&self.output.folder)
    }

    /// Step name (given or `step-<n>`, 1-based).
    #[must_use]
    pub fn step_name(&self, index: usize) -> String {
        self.steps[index]
            .name
            .clone()
            .unwrap_or_else(|| format!("step-{}", index + 1))
    }
}

/// The reader's message with Rust's type names (`expected usize`) in the model file's terms.
fn plain_types(message: &str) -> String {
    const WHOLE: &str = "a whole number ≥ 0";
    let mut m = message.to_string();
    for t in ["usize", "u64", "u32"] {
        let expected = format!("expected {t}");
        if m.ends_with(&expected) && m.starts_with("invalid type: floating point") {
            m = m.replace(
                &expected,
                &format!("expected {WHOLE}, without a decimal point"),
            );
        }
        m = m.replace(&expected, &format!("expected {WHOLE}"));
    }
    m.replace("expected f64", "expected a number")
}

/// 1-based line and column of a byte offset.
#[must_use]
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset.min(text.len())).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let last = before.rsplit('\n').next().unwrap_or_default();
    // A byte-order mark, which some editors write, is not a column.
    let last = if line == 1 {
        last.strip_prefix('\u{feff}').unwrap_or(last)
    } else {
        last
    };
    (line, last.chars().count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
[mesh]
file = "m.msh"
[[material]]
name = "steel"
type = "linear_elastic"
E = 210e3
nu = 0.3
[[body]]
group = "solid"
material = "steel"
[[boundary]]
group = "left"
fix = ["x", "y", "z"]
[[boundary]]
group = "right"
displacement = { x = 0.5 }
[[load]]
group = "top"
pressure = 2.0
[[step]]
increments = 4
nlgeom = true
"#;

    /// Type mistakes are told in the file's terms, not Rust's (`usize`, `f64`).
    #[test]
    fn type_mistakes_name_the_kind_of_value_expected() {
        let cases = [
            (
                "increments = 4",
                "increments = -1",
                "integer `-1`, expected a whole number ≥ 0",
            ),
            (
                "increments = 4",
                "increments = 4.0",
                "floating point `4.0`, expected a whole number ≥ 0, without a decimal point",
            ),
            (
                "increments = 4",
                "increments = \"x\"",
                "expected a whole number ≥ 0",
            ),
            ("E = 210e3", "E = \"x\"", "string \"x\", expected a number"),
        ];
        for (from, to, expect) in cases {
            let text = GOOD.replace(from, to);
            let e = Model::parse(&text, Path::new("m.toml"))
                .expect_err(to)
                .to_string();
            assert!(
                e.contains(expect) && !e.contains("usize") && !e.contains("f64"),
                "{to}: {e}"
            );
        }
    }

    #[test]
    fn parses_with_defaults() {
        let m = Model::parse(GOOD, Path::new("m.toml")).expect("valid");
        assert_eq!(m.materials[0].kind, MaterialKind::LinearElastic);
        assert_eq!(
            m.boundaries[0].fix,
            vec![Component::X, Component::Y, Component::Z]
        );
        assert_eq!(
            m.boundaries[1].displacement.as_ref().and_then(|d| d.x),
            Some(0.5)
        );
        assert_eq!(m.steps[0].max_iterations, 20);
        assert!(m.steps[0].nlgeom);
        assert!(m.output.vtu);
        assert_eq!(m.output.vtu_format, VtuFormat::Binary);
        assert_eq!(m.step_name(0), "step-1");
    }

    #[test]
    fn vtu_format_is_ascii_or_binary() {
        let with = |v: &str| format!("{GOOD}[output]\nvtu_format = \"{v}\"\n");
        let m = Model::parse(&with("ascii"), Path::new("m.toml")).expect("valid");
        assert_eq!(m.output.vtu_format, VtuFormat::Ascii);
        let m = Model::parse(&with("binary"), Path::new("m.toml")).expect("valid");
        assert_eq!(m.output.vtu_format, VtuFormat::Binary);
        let e = Model::parse(&with("base64"), Path::new("m.toml")).expect_err("bad value");
        let msg = e.to_string();
        assert!(
            msg.contains("base64") && msg.contains("ascii") && msg.contains("m.toml:25:"),
            "{msg}"
        );
    }

    #[test]
    fn line_search_is_true_false_or_auto() {
        let with = |v: &str| {
            GOOD.replace(
                "nlgeom = true",
                &format!("nlgeom = true\nline_search = {v}"),
            )
        };
        let mode = |v: &str| {
            Model::parse(&with(v), Path::new("m.toml"))
                .expect("valid")
                .steps[0]
                .line_search
        };
        assert_eq!(mode("true"), LineSearchMode::On);
        assert_eq!(mode("false"), LineSearchMode::Off);
        assert_eq!(mode("\"auto\""), LineSearchMode::Auto);
        let default = Model::parse(GOOD, Path::new("m.toml")).expect("valid");
        assert_eq!(default.steps[0].line_search, LineSearchMode::Auto);
        for bad in ["\"always\"", "1"] {
            let e = Model::parse(&with(bad), Path::new("m.toml")).expect_err("bad value");
            let msg = e.to_string();
            assert!(
                msg.contains("true, false or \"auto\"") && msg.contains("m.toml:24:"),
                "{msg}"
            );
        }
    }

    #[test]
    fn long_material_key_names_are_accepted() {
        let text = GOOD
            .replace("E = 210e3", "youngs_modulus = 7e4")
            .replace("nu = 0.3", "poisson_ratio = 0.33");
        let m = Model::parse(&text, Path::new("m.toml")).expect("valid");
        assert_eq!((m.materials[0].e, m.materials[0].nu), (7e4, 0.33));
    }

    #[test]
    fn unknown_key_is_an_error_with_position() {
        let bad = GOOD.replace("increments = 4", "incremnets = 4");
        let e = Model::parse(&bad, Path::new("m.toml")).expect_err("unknown key");
        let msg = e.to_string();
        assert!(msg.contains("incremnets"), "{msg}");
        assert!(msg.contains(".toml:22:1: "), "{msg}");
    }

    #[test]
    fn a_vector_has_exactly_three_entries() {
        for bad in ["[0.0, 1.0]", "[0.0, 1.0, 2.0, 3.0]"] {
            let text = format!("{GOOD}[[load]]\ngroup = \"tip\"\nforce = {bad}\n");
            let msg = Model::parse(&text, Path::new("m.toml"))
                .expect_err("not three")
                .to_string();
            assert!(
                msg.contains("an array of 3 numbers") && msg.contains(".toml:26:9: "),
                "{msg}"
            );
        }
        let text = format!("{GOOD}[[load]]\ngroup = \"tip\"\nforce = [0.0, 1.0, 2.0]\n");
        let m = Model::parse(&text, Path::new("m.toml")).expect("three");
        assert_eq!(m.loads[1].force, Some([0.0, 1.0, 2.0]));
    }

    #[test]
    fn a_byte_order_mark_is_not_a_column() {
        let text = "\u{feff}bogus = 1\n";
        let e = Model::parse(text, Path::new("m.toml")).expect_err("unknown key");
        assert!(e.to_string().contains(".toml:1:1: "), "{e}");
        assert_eq!(line_col(text, text.len()), (2, 1));
    }

    #[test]
    fn malformed_toml_points_at_line_and_column() {
        let bad = "[mesh]\nfile = \"a.msh\"\n[[material]\nname = 1\n";
        let e = Model::parse(bad, Path::new("m.toml")).expect_err("syntax");
        let msg = e.to_string();
        assert!(msg.contains(".toml:3:"), "{msg}");
        assert!(!msg.contains('\n'));
    }
}
