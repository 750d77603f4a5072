//! Typed errors of the finite-element host.
//!
//! Every failure a user can cause (bad model file, bad mesh, a singular or
//! diverging analysis) maps to one variant whose `Display` is a single line
//! that names the cause, so the command line can print it as is.

use std::path::PathBuf;

/// Errors raised while reading, checking or solving a model.
#[derive(Debug, thiserror::Error)]
pub enum FemError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The model file is not valid TOML or does not match the schema: `invalid model:
    /// <file>:<line>:<column>: <message>`, as the model's other problems read (and as editors
    /// and terminals take a place in a file).
    #[error("invalid model: {path}{at}: {message}")]
    ModelSyntax {
        /// The model file.
        path: PathBuf,
        /// Where in it: `:line:column`, `:line`, or empty.
        at: String,
        /// Parser message.
        message: String,
    },
    /// The mesh file could not be parsed.
    #[error("mesh {path}: {message}")]
    Mesh {
        /// The mesh file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The mesh contains an element type the solver does not support.
    #[error("mesh {path}: unsupported element type {kind} in physical group '{group}'")]
    UnsupportedElement {
        /// The mesh file.
        path: PathBuf,
        /// The Gmsh element type name.
        kind: String,
        /// The group it belongs to.
        group: String,
    },
    /// The model refers to a physical group that is not in the mesh.
    #[error("{at}unknown {kind} group '{name}' (groups in the mesh: {available})")]
    UnknownGroup {
        /// Where the model file names it (`"model.toml:12: "`; empty when unknown).
        at: String,
        /// Which kind of group was expected (volume, surface, node).
        kind: &'static str,
        /// The missing name.
        name: String,
        /// Comma-separated list of the groups that exist.
        available: String,
    },
    /// The model is inconsistent; every problem found is listed.
    #[error("invalid model: {}", .0.join("; "))]
    Invalid(Vec<String>),
    /// An element has a non-positive Jacobian in the reference configuration.
    #[error(
        "mesh {}: element {tag} is inverted: Jacobian determinant {det_j:.3e} < 0 at an integration point",
        mesh.display()
    )]
    InvertedElement {
        /// The mesh file.
        mesh: PathBuf,
        /// Internal element index.
        element: usize,
        /// Gmsh element tag.
        tag: u64,
        /// The offending determinant.
        det_j: f64,
    },
    /// An element has (numerically) zero volume.
    #[error(
        "mesh {}: element {tag} has zero volume (Jacobian determinant {det_j:.3e} relative to its size)",
        mesh.display()
    )]
    ZeroVolume {
        /// The mesh file.
        mesh: PathBuf,
        /// Internal element index.
        element: usize,
        /// Gmsh element tag.
        tag: u64,
        /// The determinant scaled by the element size cubed.
        det_j: f64,
    },
    /// The stiffness matrix is singular (e.g. a body without enough supports).
    #[error("singular system: {0}")]
    Singular(String),
    /// The analysis did not converge even after the allowed cutbacks.
    #[error(
        "step '{step}' did not converge from load factor {} to {} ({exhausted}): {reason}",
        load_factor_text(*.load_factor, *.target - *.load_factor, 6),
        load_factor_text(*.target, *.target - *.load_factor, 6)
    )]
    NotConverged {
        /// Step name.
        step: String,
        /// Load factor reached in the step (the last converged increment).
        load_factor: f64,
        /// Load factor the last attempt aimed at.
        target: f64,
        /// Last failure reason.
        reason: String,
        /// How the cutbacks ran out (their number, or the smallest increment reached).
        exhausted: String,
        /// Every attempt of the failed increment (for a verbose log; the message gives the
        /// last).
        attempts: Vec<crate::driver::Attempt>,
    },
    /// Writing results failed.
    #[error("output: {0}")]
    Output(String),
}

/// Shorthand result type.
pub type Result<T, E = FemError> = std::result::Result<T, E>;

impl FemError {
    /// Wraps an I/O error with the path it concerns.
    #[must_use]
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }

    /// The problem's messages without the `invalid model:` prefix, one per problem.
    #[must_use]
    pub fn messages(&self) -> Vec<String> {
        match self {
            Self::Invalid(list) => list.clone(),
            other => vec![other.to_string()],
        }
    }

    /// One error for a list of problems: `None` for none, the problem itself for one, else
    /// [`FemError::Invalid`] listing every message once.
    #[must_use]
    pub fn combine(mut problems: Vec<Self>) -> Option<Self> {
        match problems.len() {
            0 => None,
            1 => problems.pop(),
            _ => Some(Self::Invalid(
                problems.iter().flat_map(Self::messages).collect(),
            )),
        }
    }
}

/// A load factor `t` printed with at least `min_decimals` decimals and enough more to show an
/// increment `dt` with two significant digits (deep cutbacks otherwise print the same `t` for
/// different increments).
#[must_use]
pub fn load_factor_text(t: f64, dt: f64, min_decimals: usize) -> String {
    let needed = if dt.abs() > 0.0 && dt.is_finite() {
        // Decimals up to dt's leading digit, plus one more.
        let lead = -dt.abs().log10().floor();
        if lead.is_finite() && lead > 0.0 {
            lead as usize + 1
        } else {
            0
        }
    } else {
        0
    };
    // Past 17 decimals an f64 has no more digits to show.
    format!("{t:.*}", needed.clamp(min_decimals.min(17), 17))
}

#[cfg(test)]
mod tests {
    use super::load_factor_text;

    #[test]
    fn load_factors_show_their_increment() {
        assert_eq!(load_factor_text(0.5, 0.25, 4), "0.5000");
        assert_eq!(load_factor_text(0.5, 0.0, 6), "0.500000");
        // Two increments 2⁻²⁰ apart print differently.
        let dt = 0.5f64.powi(20);
        let (a, b) = (0.440_970_443, 0.440_970_443 + dt);
        assert_ne!(load_factor_text(a, dt, 4), load_factor_text(b, dt, 4));
        // dt ≈ 9.5e-7: its leading digit is the 7th decimal, one more is shown.
        assert_eq!(load_factor_text(b, dt, 4).len(), "0.".len() + 8);
        assert_eq!(load_factor_text(1.0, f64::NAN, 4), "1.0000");
        // More decimals than an f64 has: 17 (`clamp` panicked when asked for more than 17).
        assert_eq!(
            load_factor_text(0.5, 0.25, usize::MAX),
            format!("{:.17}", 0.5)
        );
    }
}
