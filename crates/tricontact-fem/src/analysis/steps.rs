//! The steps of a model: their controls checked, and which steps a boundary or load acts in.

use super::{MAX_CUTBACKS, MAX_INCREMENTS, Step, invalid};
use crate::error::FemError;
use crate::model::Model;

/// The model's steps, each problem with them added to `problems`.
pub(super) fn resolve(model: &Model, problems: &mut Vec<FemError>) -> Vec<Step> {
    let src = &model.source;
    if model.steps.is_empty() {
        problems.push(invalid(format!("{}no [[step]] defined", src.file())));
    }
    let steps: Vec<Step> = model
        .steps
        .iter()
        .enumerate()
        .map(|(i, s)| Step {
            name: model.step_name(i),
            increments: s.increments,
            max_iterations: s.max_iterations,
            residual_tolerance: s.residual_tolerance,
            displacement_tolerance: s.displacement_tolerance,
            nlgeom: s.nlgeom,
            max_cutbacks: s.max_cutbacks,
            extrapolation: s.extrapolation,
            line_search: s.line_search,
        })
        .collect();
    for (i, s) in steps.iter().enumerate() {
        if s.name.trim().is_empty() {
            problems.push(invalid(format!(
                "{}step {}: the name is empty",
                src.at("step", i, "name"),
                i + 1
            )));
        }
        if steps[..i].iter().any(|t| t.name == s.name) {
            problems.push(invalid(format!(
                "{}step name '{}' is used twice (`steps = [...]` must name one step)",
                src.at("step", i, "name"),
                s.name
            )));
        }
        for (key, value, low, high) in [
            ("increments", s.increments, 1, MAX_INCREMENTS),
            ("max_iterations", s.max_iterations, 1, MAX_INCREMENTS),
            ("max_cutbacks", s.max_cutbacks, 0, MAX_CUTBACKS),
        ] {
            if !(low..=high).contains(&value) {
                problems.push(invalid(format!(
                    "{}step '{}': {key} must be from {low} to {high} (got {value})",
                    src.at("step", i, key),
                    s.name
                )));
            }
        }
        for (key, value) in [
            ("residual_tolerance", s.residual_tolerance),
            ("displacement_tolerance", s.displacement_tolerance),
        ] {
            if !(value > 0.0 && value < 1.0) {
                problems.push(invalid(format!(
                    "{}step '{}': {key} must be > 0 and < 1 (got {value})",
                    src.at("step", i, key),
                    s.name
                )));
            }
        }
    }
    steps
}

/// In which of `steps` an item acts, from its `steps = [...]` (`None`: every step); `what`
/// names the item in the problems added to `problems` (no step named, one named twice or unknown).
pub(super) fn mask(
    steps: &[Step],
    names: Option<&[String]>,
    what: &str,
    problems: &mut Vec<FemError>,
) -> Vec<bool> {
    match names {
        None => vec![true; steps.len()],
        Some(names) => {
            if names.is_empty() {
                problems.push(invalid(format!(
                    "{what}: `steps = []` names no step, so it would never act (omit `steps` for every step)"
                )));
            }
            for (i, n) in names.iter().enumerate() {
                if names[..i].contains(n) {
                    problems.push(invalid(format!("{what}: step '{n}' is listed twice")));
                }
                // With no step at all, that is the one problem to report.
                if !steps.is_empty() && !steps.iter().any(|s| &s.name == n) {
                    problems.push(invalid(format!(
                        "{what}: unknown step '{n}' (steps: {})",
                        steps
                            .iter()
                            .map(|s| s.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )));
                }
            }
            steps.iter().map(|s| names.contains(&s.name)).collect()
        }
    }
}
