//! A scenario file as text plus positions, so that every configuration error can name
//! the file, the line and the key, whether it comes from the base table, a variant's
//! override table or a `--set key=value` override.
//!
//! Resolution of one variant: the file's top-level tables (without `variants`), deep-
//! merged with `[variants.NAME]`, then with the command-line overrides, deserialised into
//! the typed scenario. An error found in the merged document is traced back by key path
//! to where that key was written.

use std::fmt;

use serde::de::DeserializeOwned;
use toml::{Table, Value};

/// A scenario problem: one line, naming the file, the line, the key and the fix.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioError {
    /// The scenario file.
    pub file: String,
    /// 1-based line where the offending key is written, when known.
    pub line: Option<usize>,
    /// Dotted key path, e.g. `controller.k1`.
    pub key: Option<String>,
    /// The variant being resolved, when the problem is specific to one.
    pub variant: Option<String>,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub hint: Option<String>,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        write!(f, ":")?;
        if let Some(key) = &self.key {
            write!(f, " key `{key}`")?;
        }
        if let Some(v) = &self.variant {
            write!(f, " (variant `{v}`)")?;
        }
        if self.key.is_some() || self.variant.is_some() {
            write!(f, ":")?;
        }
        write!(f, " {}", self.message)?;
        if let Some(h) = &self.hint {
            write!(f, "; hint: {h}")?;
        }
        Ok(())
    }
}

impl std::error::Error for ScenarioError {}

/// A semantic problem found by validation of a typed configuration: the key path (dotted,
/// relative to the scenario root), the message and an optional hint.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    /// Dotted key path.
    pub key: String,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub hint: Option<String>,
}

impl Invalid {
    /// A problem at `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            message: message.into(),
            hint: None,
        }
    }

    /// With a hint.
    pub fn hint(mut self, hint: impl Into<String>) -> Self {
        self.hint = Some(hint.into());
        self
    }
}

/// A parsed scenario file with positions.
#[derive(Debug, Clone)]
pub struct ScenarioSource {
    file: String,
    text: String,
    root: Table,
    /// (dotted key path, line) for every key in the file.
    lines: Vec<(String, usize)>,
    /// Command-line overrides `(dotted key, value)`.
    overrides: Vec<(String, Value)>,
}

fn line_at(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())]
        .bytes()
        .filter(|b| *b == b'\n')
        .count()
        + 1
}

fn collect_lines(
    text: &str,
    prefix: &str,
    table: &toml_edit::Table,
    out: &mut Vec<(String, usize)>,
) {
    for (key, item) in table.iter() {
        let path = if prefix.is_empty() {
            key.to_string()
        } else {
            format!("{prefix}.{key}")
        };
        let span = table
            .key(key)
            .and_then(|k| k.span())
            .or_else(|| item.span());
        if let Some(span) = span {
            out.push((path.clone(), line_at(text, span.start)));
        }
        match item {
            toml_edit::Item::Table(t) => collect_lines(text, &path, t, out),
            toml_edit::Item::Value(toml_edit::Value::InlineTable(t)) => {
                for (k, v) in t.iter() {
                    let p = format!("{path}.{k}");
                    if let Some(span) = t.key(k).and_then(|k| k.span()).or_else(|| v.span()) {
                        out.push((p, line_at(text, span.start)));
                    }
                }
            }
            toml_edit::Item::ArrayOfTables(a) => {
                for (i, t) in a.iter().enumerate() {
                    collect_lines(text, &format!("{path}.{i}"), t, out);
                }
            }
            _ => {}
        }
    }
}

fn merge(base: &mut Table, over: &Table) {
    for (k, v) in over {
        match (base.get_mut(k), v) {
            (Some(Value::Table(b)), Value::Table(o)) => merge(b, o),
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

/// Finds the dotted path of the deepest key whose key or value covers `offset` in `text`.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let doc = toml_edit::Document::parse(text.to_string()).ok()?;
    fn walk(prefix: &str, table: &toml_edit::Table, offset: usize, best: &mut Option<String>) {
        for (key, item) in table.iter() {
            let path = if prefix.is_empty() {
                key.to_string()
            } else {
                format!("{prefix}.{key}")
            };
            let key_span = table.key(key).and_then(|k| k.span());
            let covers = |s: Option<std::ops::Range<usize>>| {
                s.is_some_and(|s| s.start <= offset && offset < s.end.max(s.start + 1))
            };
            if covers(key_span.clone()) || covers(item.span()) {
                *best = Some(path.clone());
            }
            match item {
                toml_edit::Item::Table(t) => walk(&path, t, offset, best),
                toml_edit::Item::Value(toml_edit::Value::InlineTable(t)) => {
                    for (k, v) in t.iter() {
                        let ks = t.key(k).and_then(|k| k.span());
                        if covers(ks) || covers(v.span()) {
                            *best = Some(format!("{path}.{k}"));
                        }
                    }
                }
                _ => {}
            }
        }
    }
    let mut best = None;
    walk("", doc.as_table(), offset, &mut best);
    best
}

impl ScenarioSource {
    /// Reads and parses a scenario file (syntax only).
    pub fn load(path: &std::path::Path) -> Result<Self, ScenarioError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError {
            file: file.clone(),
            line: None,
            key: None,
            variant: None,
            message: format!("cannot read the file: {e}"),
            hint: None,
        })?;
        Self::parse(&text, &file)
    }

    /// Parses scenario text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, ScenarioError> {
        let syntax = |message: String, line: Option<usize>| ScenarioError {
            file: file.to_string(),
            line,
            key: None,
            variant: None,
            message,
            hint: Some("check the TOML syntax at that line".into()),
        };
        let doc = toml_edit::Document::parse(text.to_string()).map_err(|e| {
            let line = e.span().map(|s| line_at(text, s.start));
            syntax(format!("not valid TOML: {}", e.message().trim()), line)
        })?;
        let root: Table = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| line_at(text, s.start));
            syntax(format!("not valid TOML: {}", e.message().trim()), line)
        })?;
        let mut lines = Vec::new();
        collect_lines(text, "", doc.as_table(), &mut lines);
        Ok(Self {
            file: file.to_string(),
            text: text.to_string(),
            root,
            lines,
            overrides: Vec::new(),
        })
    }

    /// The file name used in errors.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The raw text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Names of the `[variants.NAME]` tables, in file order.
    pub fn variant_names(&self) -> Vec<String> {
        let mut names: Vec<(usize, String)> = match self.root.get("variants") {
            Some(Value::Table(t)) => t
                .keys()
                .map(|k| {
                    (
                        self.line_of(&format!("variants.{k}")).unwrap_or(0),
                        k.clone(),
                    )
                })
                .collect(),
            _ => Vec::new(),
        };
        names.sort();
        names.into_iter().map(|(_, n)| n).collect()
    }

    /// Line of a dotted key path, if the file writes it.
    pub fn line_of(&self, key: &str) -> Option<usize> {
        self.lines.iter().find(|(k, _)| k == key).map(|(_, l)| *l)
    }

    /// Adds a command-line override `key=value` (value in TOML syntax; a bare word is
    /// taken as a string).
    pub fn set(&mut self, assignment: &str) -> Result<(), ScenarioError> {
        let err = |message: String| ScenarioError {
            file: "--set".into(),
            line: None,
            key: None,
            variant: None,
            message,
            hint: Some("write --set section.key=value, e.g. --set timing.duration=5".into()),
        };
        let (key, value) = assignment
            .split_once('=')
            .ok_or_else(|| err(format!("'{assignment}' has no '='")))?;
        let key = key.trim();
        if key.is_empty() || key.split('.').any(|p| p.is_empty()) {
            return Err(err(format!("'{key}' is not a dotted key")));
        }
        let value = value.trim();
        let parsed: Value = match toml::from_str::<Table>(&format!("v = {value}")) {
            Ok(mut t) => t.remove("v").unwrap_or(Value::String(value.into())),
            Err(_) => Value::String(value.to_string()),
        };
        self.overrides.push((key.to_string(), parsed));
        Ok(())
    }

    fn override_table(&self) -> Table {
        let mut out = Table::new();
        for (key, value) in &self.overrides {
            let parts: Vec<&str> = key.split('.').collect();
            let mut table = &mut out;
            for p in &parts[..parts.len() - 1] {
                let entry = table
                    .entry(p.to_string())
                    .or_insert_with(|| Value::Table(Table::new()));
                if !entry.is_table() {
                    *entry = Value::Table(Table::new());
                }
                table = entry.as_table_mut().expect("just made a table");
            }
            table.insert(parts[parts.len() - 1].to_string(), value.clone());
        }
        out
    }

    /// The merged table for `variant` (None: the base alone).
    pub fn merged(&self, variant: Option<&str>) -> Result<Table, ScenarioError> {
        let mut base = self.root.clone();
        let variants = base.remove("variants");
        if let Some(name) = variant {
            let table = variants
                .as_ref()
                .and_then(|v| v.as_table())
                .and_then(|t| t.get(name))
                .and_then(|v| v.as_table())
                .ok_or_else(|| ScenarioError {
                    file: self.file.clone(),
                    line: None,
                    key: Some(format!("variants.{name}")),
                    variant: None,
                    message: format!("no variant named '{name}'"),
                    hint: Some(format!(
                        "variants in this file: {}",
                        self.variant_names().join(", ")
                    )),
                })?;
            merge(&mut base, table);
        }
        merge(&mut base, &self.override_table());
        Ok(base)
    }

    /// Where a key of the merged document was written: the override, the variant table,
    /// or the base table.
    pub fn locate(&self, key: &str, variant: Option<&str>) -> (String, Option<usize>) {
        if self
            .overrides
            .iter()
            .any(|(k, _)| k == key || key.starts_with(&format!("{k}.")))
        {
            return ("--set".into(), None);
        }
        if let Some(v) = variant {
            if let Some(line) = self.line_of(&format!("variants.{v}.{key}")) {
                return (self.file.clone(), Some(line));
            }
        }
        // The key itself, or its nearest written ancestor.
        let mut k = key.to_string();
        loop {
            if let Some(line) = self.line_of(&k) {
                return (self.file.clone(), Some(line));
            }
            match k.rfind('.') {
                Some(i) => k.truncate(i),
                None => return (self.file.clone(), None),
            }
        }
    }

    /// An error at `key`, located.
    pub fn error_at(
        &self,
        key: &str,
        variant: Option<&str>,
        message: impl Into<String>,
        hint: Option<String>,
    ) -> ScenarioError {
        let (file, line) = self.locate(key, variant);
        ScenarioError {
            file,
            line,
            key: Some(key.to_string()),
            variant: variant.map(String::from),
            message: message.into(),
            hint,
        }
    }

    /// Maps validation problems to located errors (the first one; all are listed in the
    /// message when there are several).
    pub fn invalid(&self, variant: Option<&str>, problems: &[Invalid]) -> ScenarioError {
        let first = &problems[0];
        let hint = first.hint.clone().unwrap_or_else(|| {
            format!(
                "fix `{}` in the file, or override it with --set {}=VALUE",
                first.key, first.key
            )
        });
        let mut err = self.error_at(&first.key, variant, first.message.clone(), Some(hint));
        if problems.len() > 1 {
            err.message
                .push_str(&format!(" (and {} more problems)", problems.len() - 1));
        }
        err
    }

    /// Deserialises the merged document of `variant` into `T`. Unknown keys and wrong
    /// types are reported at the key that carries them.
    pub fn resolve<T: DeserializeOwned>(&self, variant: Option<&str>) -> Result<T, ScenarioError> {
        let merged = self.merged(variant)?;
        let text = toml::to_string(&merged).map_err(|e| ScenarioError {
            file: self.file.clone(),
            line: None,
            key: None,
            variant: variant.map(String::from),
            message: format!("cannot re-serialise the scenario: {e}"),
            hint: None,
        })?;
        toml::from_str::<T>(&text).map_err(|e| {
            let key = e.span().and_then(|s| key_at(&text, s.start));
            let message = e.message().trim().replace('\n', " ");
            let hint = if message.contains("unknown field") {
                Some("remove the key or fix its spelling; the expected keys are listed".into())
            } else if message.contains("invalid type") {
                Some("check the value's type (number, string, list, table)".into())
            } else if message.contains("missing field") {
                Some("add the key to the table".into())
            } else {
                None
            };
            match key {
                Some(k) => self.error_at(&k, variant, message, hint),
                None => ScenarioError {
                    file: self.file.clone(),
                    line: None,
                    key: None,
                    variant: variant.map(String::from),
                    message,
                    hint,
                },
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Gains {
        k1: f64,
        #[serde(default)]
        k2: Option<f64>,
    }

    #[derive(Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Doc {
        name: String,
        controller: Gains,
    }

    const TEXT: &str = "name = \"x\"\n\n[controller]\nk1 = 12.0\n\n[variants.slow]\ncontroller.k1 = 3.0\n\n[variants.typo]\ncontroller.kk = 1.0\n\n[variants.wrong]\ncontroller.k2 = \"six\"\n";

    #[test]
    fn variants_merge_over_the_base() {
        let src = ScenarioSource::parse(TEXT, "s.toml").unwrap();
        assert_eq!(src.variant_names(), ["slow", "typo", "wrong"]);
        let base: Doc = src.resolve(None).unwrap();
        assert_eq!(base.controller.k1, 12.0);
        let slow: Doc = src.resolve(Some("slow")).unwrap();
        assert_eq!(slow.controller.k1, 3.0);
    }

    #[test]
    fn unknown_keys_and_wrong_types_name_line_and_key() {
        let src = ScenarioSource::parse(TEXT, "s.toml").unwrap();
        let e = src.resolve::<Doc>(Some("typo")).unwrap_err();
        assert_eq!(e.line, Some(10), "{e}");
        assert!(e.to_string().contains("unknown field `kk`"), "{e}");
        let e = src.resolve::<Doc>(Some("wrong")).unwrap_err();
        assert_eq!(e.line, Some(13), "{e}");
        assert_eq!(e.key.as_deref(), Some("controller.k2"), "{e}");
        let e = src.resolve::<Doc>(Some("nope")).unwrap_err();
        assert!(e.to_string().contains("slow, typo, wrong"), "{e}");
    }

    #[test]
    fn syntax_errors_have_lines_and_overrides_apply() {
        let e = ScenarioSource::parse("a = 1\nb = [1,\n", "bad.toml").unwrap_err();
        assert!(
            e.line.is_some() && e.to_string().starts_with("bad.toml:"),
            "{e}"
        );
        let mut src = ScenarioSource::parse(TEXT, "s.toml").unwrap();
        src.set("controller.k1=7").unwrap();
        let d: Doc = src.resolve(Some("slow")).unwrap();
        assert_eq!(d.controller.k1, 7.0);
        src.set("controller.k2=oops").unwrap();
        let e = src.resolve::<Doc>(None).unwrap_err();
        assert_eq!(e.file, "--set", "{e}");
        assert!(src.set("novalue").is_err());
    }

    #[test]
    fn validation_problems_are_located() {
        let src = ScenarioSource::parse(TEXT, "s.toml").unwrap();
        let e = src.invalid(
            Some("slow"),
            &[Invalid::new("controller.k1", "must be positive").hint("use 12")],
        );
        assert_eq!(e.line, Some(7));
        assert_eq!(
            e.to_string(),
            "s.toml:7: key `controller.k1` (variant `slow`): must be positive; hint: use 12"
        );
        let e = src.invalid(None, &[Invalid::new("controller.k1", "bad")]);
        assert_eq!(e.line, Some(4));
        assert!(
            e.to_string().ends_with("hint: fix `controller.k1` in the file, or override it with --set controller.k1=VALUE"),
            "{e}"
        );
    }
}
