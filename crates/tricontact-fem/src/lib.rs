//! Implicit finite-element solver for 3D solids: Gmsh mesh in, ParaView
//! (VTU/PVD) results and a CSV history out, driven by a TOML model file.
//!
//! Pipeline: [`gmsh::read_msh`] → [`model::Model::load`] →
//! [`analysis::Analysis::new`] → [`driver::run`] (steps, load increments,
//! Newton–Raphson with cutback, [`assembly`] in parallel, [`linsolve`] with
//! faer) → [`output::ResultWriter`]. Contact and other terms from outside
//! the element loop plug in through [`assembly::ExtraTerms`].

// Index loops mirror the index notation of the formulas in the module docs.
#![allow(clippy::needless_range_loop)]

pub mod analysis;
pub mod assembly;
pub mod atomic;
pub mod contact;
pub mod driver;
pub mod element;
pub mod error;
pub mod face;
pub mod follower;
pub mod gmsh;
pub mod gmsh_nodes;
pub mod hertz;
pub mod hex8;
pub mod inp;
pub mod line_search;
pub mod linear_elastic;
pub mod linsolve;
pub mod loads;
pub mod material;
pub mod mesh;
pub mod model;
pub mod neo_hooke;
pub mod newton;
pub mod ordering;
pub mod output;
pub mod plots;
pub mod report;
pub mod results;
pub mod rigid;
pub mod sections;
pub mod shape;
pub mod source;
pub mod structured;
pub mod tet10;
pub mod tet4;
pub mod throttle;
pub mod vtu;

pub use error::{FemError, Result};

/// Reads a model file and its mesh and resolves them.
///
/// # Errors
/// Any model, mesh or validation error.
pub fn load_analysis(model_path: &std::path::Path) -> Result<analysis::Analysis> {
    let model = model::Model::load(model_path)?;
    let mesh = model.read_mesh()?;
    analysis::Analysis::new(&model, mesh)
}
