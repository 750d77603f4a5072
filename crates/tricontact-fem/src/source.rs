//! Where each table and key of a model file stands, so that a problem found after parsing (a
//! value out of range, a name that matches nothing) can name the line it comes from.
//!
//! A place is `(table, index, key)`: `("step", 1, "increments")` is the `increments` key of the
//! second `[[step]]`; a single table (`[output]`) has index 0; a key of an inline table is dotted
//! (`"displacement.x"`); the key `""` is the table's own header. A place that the file does not
//! spell out (a default value, a model built in code) falls back to its table's header, then to
//! nothing: the message is then given without a line.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};

use crate::model::line_col;

/// Lines of a model file's tables and keys (1-based).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SourceMap {
    /// The model file, as given to [`crate::model::Model::load`].
    path: PathBuf,
    /// `(table, index, key)` → line.
    lines: HashMap<(String, usize, String), usize>,
}

impl SourceMap {
    /// The lines of `text`'s tables and keys; empty when `text` is not valid TOML (the parser
    /// reports that itself).
    #[must_use]
    pub fn new(text: &str, path: &Path) -> Self {
        let mut map = Self {
            path: path.to_path_buf(),
            lines: HashMap::new(),
        };
        let Ok(root) = DeTable::parse(text) else {
            return map;
        };
        let line = |span: std::ops::Range<usize>| line_col(text, span.start).0;
        for (name, value) in root.get_ref() {
            let name = name.get_ref().to_string();
            match value.get_ref() {
                DeValue::Table(table) => {
                    map.insert(&name, 0, "", line(value.span()));
                    map.keys(&name, 0, "", table, &line);
                }
                DeValue::Array(items) => {
                    for (i, item) in items.iter().enumerate() {
                        if let DeValue::Table(table) = item.get_ref() {
                            map.insert(&name, i, "", line(item.span()));
                            map.keys(&name, i, "", table, &line);
                        }
                    }
                }
                _ => {}
            }
        }
        map
    }

    fn insert(&mut self, table: &str, index: usize, key: &str, line: usize) {
        self.lines
            .entry((table.to_string(), index, key.to_string()))
            .or_insert(line);
    }

    /// Records the keys of `table` (and, dotted, those of its inline tables).
    fn keys(
        &mut self,
        name: &str,
        index: usize,
        prefix: &str,
        table: &DeTable<'_>,
        line: &dyn Fn(std::ops::Range<usize>) -> usize,
    ) {
        for (key, value) in table {
            let key = format!("{prefix}{}", key.get_ref());
            self.insert(name, index, &key, line(value.span()));
            if let DeValue::Table(inner) = value.get_ref() {
                self.keys(name, index, &format!("{key}."), inner, line);
            }
        }
    }

    /// Forgets the lines of every `[table]` (its entries then have no place in the file).
    pub fn forget(&mut self, table: &str) {
        self.lines.retain(|(t, _, _), _| t != table);
    }

    /// The line of a place: its key's, else its table's header (`None` when neither is in the
    /// file).
    #[must_use]
    pub fn line(&self, table: &str, index: usize, key: &str) -> Option<usize> {
        let get = |k: &str| {
            self.lines
                .get(&(table.to_string(), index, k.to_string()))
                .copied()
        };
        get(key).or_else(|| get(""))
    }

    /// [`SourceMap::at`] for the first of `keys` the table spells out (a key and its aliases).
    #[must_use]
    pub fn at_first(&self, table: &str, index: usize, keys: &[&str]) -> String {
        let spelt = keys.iter().find(|k| {
            self.lines
                .contains_key(&(table.to_string(), index, (**k).to_string()))
        });
        self.at(table, index, spelt.copied().unwrap_or(""))
    }

    /// `"model.toml: "`, the prefix of a message about the whole file (`""` for a model built in
    /// code).
    #[must_use]
    pub fn file(&self) -> String {
        if self.path.as_os_str().is_empty() {
            String::new()
        } else {
            format!("{}: ", self.path.display())
        }
    }

    /// `"model.toml:12: "` for a place (see [`SourceMap::line`]), `""` when it has no line: the
    /// prefix of a message about it.
    #[must_use]
    pub fn at(&self, table: &str, index: usize, key: &str) -> String {
        self.line(table, index, key)
            .map(|n| format!("{}:{n}: ", self.path.display()))
            .unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"[mesh]
file = "m.msh"

[[step]]
name = "a"

[[step]]
name = "b"
increments = 0

[[boundary]]
group = "top"
displacement = { x = 0.0,
  z = 1.0 }
"#;

    #[test]
    fn keys_tables_and_inline_keys_have_their_lines() {
        let map = SourceMap::new(TEXT, Path::new("m.toml"));
        assert_eq!(map.line("mesh", 0, "file"), Some(2));
        assert_eq!(map.line("step", 0, ""), Some(4));
        assert_eq!(map.line("step", 1, "increments"), Some(9));
        assert_eq!(map.line("boundary", 0, "displacement"), Some(13));
        assert_eq!(map.line("boundary", 0, "displacement.z"), Some(14));
        assert_eq!(map.at("step", 1, "name"), "m.toml:8: ");
        assert_eq!(
            map.at_first("step", 1, &["steps", "increments"]),
            "m.toml:9: "
        );
        assert_eq!(map.at_first("step", 1, &["steps"]), "m.toml:7: ");
    }

    #[test]
    fn an_absent_key_falls_back_to_its_table_and_an_absent_table_to_nothing() {
        let map = SourceMap::new(TEXT, Path::new("m.toml"));
        assert_eq!(map.line("step", 0, "increments"), Some(4));
        assert_eq!(map.line("step", 2, "increments"), None);
        assert_eq!(map.line("output", 0, "folder"), None);
        assert_eq!(map.at("output", 0, "every"), "");
        assert_eq!(SourceMap::default().at("step", 0, ""), "");
    }

    #[test]
    fn text_that_is_not_toml_gives_an_empty_map() {
        let map = SourceMap::new("[[step]\nname = 1", Path::new("m.toml"));
        assert_eq!(map.line("step", 0, ""), None);
    }
}
