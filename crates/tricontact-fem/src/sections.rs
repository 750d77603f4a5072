//! The shape of a model file's top-level sections, checked before its keys are read.
//!
//! `[mesh]`, `[output]` and `[hertz]` are one table each; `[[material]]`, `[[body]]`,
//! `[[boundary]]`, `[[load]]`, `[[contact]]` and `[[step]]` are lists of tables (inline tables in
//! an array, `step = [{ name = "press" }]`, are the same list). The typed reading would take a
//! list of bare values (`step = [["press", 4]]`) as the fields in their declared order, which
//! skips the key names this format promises to check, and it names the other mistakes in its own
//! terms (`[[output]]`: "invalid type: map, expected path string"). This check names the section
//! and the form to write instead, at the section's line.

use std::path::Path;

use toml::de::{DeTable, DeValue};

use crate::error::{FemError, Result};
use crate::model::line_col;

/// The sections that are one table.
const ONE: [&str; 3] = ["mesh", "output", "hertz"];

/// The sections that are lists of tables, with what one item is called.
const LISTS: [(&str, &str); 6] = [
    ("material", "material"),
    ("body", "body"),
    ("boundary", "boundary condition"),
    ("load", "load"),
    ("contact", "contact pair"),
    ("step", "step"),
];

/// Checks that each known top-level section of `text` has its shape (unknown sections and
/// invalid TOML are left to the typed reading, which reports them).
///
/// # Errors
/// [`FemError::ModelSyntax`] naming the first section of the wrong shape, its line, and the form
/// to write.
pub fn check(text: &str, path: &Path) -> Result<()> {
    let Ok(root) = DeTable::parse(text) else {
        return Ok(());
    };
    for (name, value) in root.get_ref() {
        let name = name.get_ref().as_ref();
        let problem = if ONE.contains(&name) {
            one_table(name, value.get_ref())
        } else if let Some((_, item)) = LISTS.iter().find(|(n, _)| *n == name) {
            list_of_tables(name, item, value.get_ref())
        } else {
            None
        };
        if let Some(problem) = problem {
            let (line, col) = line_col(text, value.span().start);
            return Err(FemError::ModelSyntax {
                path: path.to_path_buf(),
                at: format!(":{line}:{col}"),
                message: problem,
            });
        }
    }
    Ok(())
}

/// The problem with section `name`, which must be one table, given as `value`.
fn one_table(name: &str, value: &DeValue<'_>) -> Option<String> {
    match value {
        DeValue::Table(_) => None,
        DeValue::Array(items)
            if items
                .iter()
                .all(|i| matches!(i.get_ref(), DeValue::Table(_))) =>
        {
            Some(format!(
                "[[{name}]] is a list of tables, but [{name}] is one table: write [{name}] (single brackets), once"
            ))
        }
        _ => Some(format!(
            "`{name}` must be the table [{name}], its keys on the lines below it (`{name} = …` gives it a bare value)"
        )),
    }
}

/// The problem with section `name`, a list of tables whose items are each a `item`, given as
/// `value`.
fn list_of_tables(name: &str, item: &str, value: &DeValue<'_>) -> Option<String> {
    match value {
        DeValue::Array(items)
            if items
                .iter()
                .all(|i| matches!(i.get_ref(), DeValue::Table(_))) =>
        {
            None
        }
        DeValue::Table(_) => Some(format!(
            "[{name}] is one table, but each {item} is an entry of a list: write [[{name}]] (double brackets), once per {item}"
        )),
        _ => Some(format!(
            "each {item} must be a table of named keys, written [[{name}]] with its keys on the lines below it (`{name} = …` gives bare values)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem(text: &str) -> Option<String> {
        check(text, Path::new("m.toml"))
            .err()
            .map(|e| e.to_string())
    }

    #[test]
    fn well_formed_sections_pass() {
        // A top-level array of inline tables is a list of tables too (before any header, so
        // that it is not read as a key of the table above it).
        let text = "body = [{ group = \"g\", material = \"m\" }]\n[mesh]\nfile = \"a.msh\"\n\
                    [[step]]\nname = \"a\"\n[[step]]\nname = \"b\"\n[output]\nfolder = \"r\"\n";
        assert_eq!(problem(text), None);
        // Not TOML, or a section this check does not know: left to the typed reading.
        assert_eq!(problem("[mesh\n"), None);
        assert_eq!(problem("[meshes]\nfile = 1\n"), None);
    }

    #[test]
    fn a_single_table_written_as_a_list_names_its_form_and_line() {
        let e =
            problem("[mesh]\nfile = \"a.msh\"\n\n[[output]]\nfolder = \"r\"\n").expect("a problem");
        assert!(e.contains(":4:1: [[output]] is a list of tables"), "{e}");
        assert!(e.contains("write [output] (single brackets)"), "{e}");
        let e = problem("mesh = [\"a.msh\"]\n").expect("a problem");
        assert!(e.contains(":1:8: `mesh` must be the table [mesh]"), "{e}");
    }

    #[test]
    fn a_list_written_as_one_table_or_as_bare_values_names_its_form_and_line() {
        let e = problem("[mesh]\nfile = \"a.msh\"\n[step]\nname = \"a\"\n").expect("a problem");
        assert!(e.contains(":3:1: [step] is one table"), "{e}");
        assert!(
            e.contains("write [[step]] (double brackets), once per step"),
            "{e}"
        );
        let e =
            problem("material = [[\"steel\", \"neo_hooke\", 210e3, 0.3]]\n").expect("a problem");
        assert!(
            e.contains(":1:12: each material must be a table of named keys"),
            "{e}"
        );
    }
}
