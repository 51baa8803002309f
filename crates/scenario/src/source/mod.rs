//! A scenario file, parsed once into a tree whose every key and value keeps its position,
//! so that every configuration error names the file (or the `--set` override), the line
//! and the key, whether the value comes from the base tables, a variant's table or the
//! command line.
//!
//! Resolution of one variant: the file's top-level tables (without `variants`), deep-
//! merged with `[variants.NAME]`, then with the command-line overrides; the merged tree is
//! deserialised into the typed scenario by a deserializer that returns each error with the
//! path and position of the value it concerns.

mod de;
mod tree;
mod written;

use std::ops::Range;

use serde::de::DeserializeOwned;

use admittance_control::ConfigError;

use crate::error::ScenarioError;
use tree::{Node, Table, Value};

/// A command-line override `KEY=VALUE`, positioned after the file's text.
#[derive(Clone, Debug)]
struct Override {
    key: String,
    value_text: String,
    tree: Table,
    range: Range<usize>,
}

/// A parsed scenario file with positions, and its command-line overrides.
#[derive(Debug, Clone)]
pub struct ScenarioSource {
    file: String,
    text: String,
    root: Table,
    overrides: Vec<Override>,
}

/// Where a byte offset of the source was written.
enum Origin {
    File { line: usize },
    Set(String),
}

fn line_at(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|b| **b == b'\n')
        .count()
        + 1
}

fn syntax_error(file: &str, text: &str, e: &toml::de::Error) -> ScenarioError {
    let message = e.message().trim().replace('\n', " ");
    let line = e.span().map(|s| line_at(text, s.start)).or_else(|| {
        // The parser reports its nesting limit without a position: name the first line
        // where brackets or braces nest that deep.
        message
            .contains("recursion")
            .then(|| deepest_nesting_line(text))
    });
    let hint = if message.contains("recursion") {
        "nest tables and lists less deeply (a scenario never needs more than a few levels)"
    } else {
        "check the TOML syntax at that line"
    };
    ScenarioError {
        line,
        ..ScenarioError::file(file, format!("not valid TOML: {message}")).with_hint(hint)
    }
}

fn deepest_nesting_line(text: &str) -> usize {
    let (mut depth, mut best, mut best_line, mut line) = (0i64, 0i64, 1, 1);
    for b in text.bytes() {
        match b {
            b'[' | b'{' => {
                depth += 1;
                if depth > best {
                    best = depth;
                    best_line = line;
                }
            }
            b']' | b'}' => depth -= 1,
            b'\n' => line += 1,
            _ => {}
        }
    }
    best_line
}

impl ScenarioSource {
    /// Reads and parses a scenario file (syntax only).
    pub fn load(path: &std::path::Path) -> Result<Self, ScenarioError> {
        let file = path.display().to_string();
        let bytes = admittance_files::read_regular(path, admittance_files::TEXT_LIMIT)
            .map_err(|e| ScenarioError::file(&file, format!("cannot read the file: {e}")))?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let line = line_at(
                &String::from_utf8_lossy(&e.as_bytes()[..e.utf8_error().valid_up_to()]),
                usize::MAX,
            );
            ScenarioError {
                line: Some(line),
                ..ScenarioError::file(&file, "is not UTF-8 text")
                    .with_hint("save the scenario as UTF-8")
            }
        })?;
        Self::parse(&text, &file)
    }

    /// Parses scenario text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, ScenarioError> {
        let parsed = toml::de::DeTable::parse(text).map_err(|e| syntax_error(file, text, &e))?;
        let root = tree::from_de_table(parsed.get_ref(), 0).map_err(|b| ScenarioError {
            line: Some(line_at(text, b.span.start)),
            ..ScenarioError::file(file, b.message)
        })?;
        Ok(Self {
            file: file.to_string(),
            text: text.to_string(),
            root,
            overrides: Vec::new(),
        })
    }

    /// The file name used in errors.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The file's text, as read.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The command-line overrides, as `KEY=VALUE`.
    pub fn overrides(&self) -> impl Iterator<Item = String> + '_ {
        self.overrides
            .iter()
            .map(|o| format!("{}={}", o.key, o.value_text))
    }

    /// The scenario as run: the file's text with every override written in (at the key's
    /// place in the base tables and in every variant table that sets it), preceded by a
    /// comment listing them. Comments and layout of the file are kept.
    pub fn text_as_run(&self, seed: Option<u64>) -> String {
        let assignments: Vec<(String, String)> = self
            .overrides
            .iter()
            .map(|o| (o.key.clone(), o.value_text.clone()))
            .collect();
        written::with_overrides(&self.text, &assignments, seed)
    }

    /// Names of the `[variants.NAME]` tables, in file order.
    pub fn variant_names(&self) -> Vec<String> {
        match self.root.iter().find(|(k, _)| k == "variants") {
            Some((
                _,
                Node {
                    value: Value::Table(t),
                    ..
                },
            )) => {
                let mut names: Vec<(usize, String)> = t
                    .iter()
                    .map(|(k, n)| (n.key_span.start, k.clone()))
                    .collect();
                names.sort();
                names.into_iter().map(|(_, n)| n).collect()
            }
            _ => Vec::new(),
        }
    }

    /// Adds a command-line override `key=value` (value in TOML syntax; a bare word is
    /// taken as a string).
    pub fn set(&mut self, assignment: &str) -> Result<(), ScenarioError> {
        let err = |message: String| {
            ScenarioError::file("--set", message)
                .with_hint("write --set section.key=value, e.g. --set duration=5")
        };
        let (key, value) = assignment
            .split_once('=')
            .ok_or_else(|| err(format!("'{assignment}' has no '='")))?;
        let key = key.trim();
        if key.is_empty()
            || key.split('.').any(|p| {
                p.is_empty()
                    || !p
                        .bytes()
                        .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
            })
        {
            return Err(err(format!("'{key}' is not a dotted key")));
        }
        let value = value.trim();
        let start = self.text.len()
            + 1
            + self
                .overrides
                .iter()
                .map(|o| o.range.end - o.range.start + 1)
                .sum::<usize>();
        let source = format!("v = {value}");
        let node = match toml::de::DeTable::parse(&source) {
            Ok(t) => {
                let table = tree::from_de_table(t.get_ref(), start)
                    .map_err(|b| err(format!("{key}: {}", b.message)))?;
                table.into_iter().next().map(|(_, n)| n)
            }
            Err(e) => {
                // A bare word is a string; a malformed number or list is an error.
                let looks_like_data = value.starts_with(|c: char| {
                    c.is_ascii_digit() || matches!(c, '-' | '+' | '.' | '[' | '{' | '"' | '\'')
                });
                if looks_like_data {
                    return Err(err(format!(
                        "'{value}' is not a TOML value: {}",
                        e.message().trim()
                    )));
                }
                None
            }
        };
        let range = start..start + source.len();
        let node = node.unwrap_or(Node {
            span: range.clone(),
            key_span: range.clone(),
            value: Value::String(value.to_string()),
        });
        let parts: Vec<&str> = key.split('.').collect();
        let table = build_nested(&parts, node, &range);
        self.overrides.push(Override {
            key: key.to_string(),
            value_text: value.to_string(),
            tree: table,
            range,
        });
        Ok(())
    }

    fn origin(&self, offset: usize) -> Origin {
        if offset < self.text.len() || self.overrides.is_empty() {
            return Origin::File {
                line: line_at(&self.text, offset),
            };
        }
        for o in &self.overrides {
            if offset < o.range.end + 1 {
                return Origin::Set(format!("--set {}={}", o.key, o.value_text));
            }
        }
        Origin::File {
            line: line_at(&self.text, offset),
        }
    }

    /// The merged tree of `variant` (None: the base alone), without the `variants` table.
    fn merged(&self, variant: Option<&str>) -> Result<Table, ScenarioError> {
        let mut base: Table = self
            .root
            .iter()
            .filter(|(k, _)| k != "variants")
            .cloned()
            .collect();
        if let Some(name) = variant {
            let table = tree::lookup(&self.root, "variants")
                .and_then(|v| match &v.value {
                    Value::Table(t) => t.iter().find(|(k, _)| k == name).map(|(_, n)| n),
                    _ => None,
                })
                .and_then(|n| match &n.value {
                    Value::Table(t) => Some(t),
                    _ => None,
                })
                .ok_or_else(|| {
                    let names = self.variant_names();
                    ScenarioError {
                        key: Some(format!("variants.{name}")),
                        ..ScenarioError::file(&self.file, format!("no variant named '{name}'"))
                            .with_hint(if names.is_empty() {
                                "this file has no [variants.NAME] tables; run it without --variant"
                                    .to_string()
                            } else {
                                format!("variants in this file: {}", names.join(", "))
                            })
                    }
                })?;
            tree::merge(&mut base, table);
        }
        for o in &self.overrides {
            tree::merge(&mut base, &o.tree);
        }
        Ok(base)
    }

    fn located(
        &self,
        key: &str,
        span: Option<Range<usize>>,
        variant: Option<&str>,
        message: String,
        hint: Option<String>,
    ) -> ScenarioError {
        let (file, line) = match span.map(|s| self.origin(s.start)) {
            Some(Origin::File { line }) => (self.file.clone(), Some(line)),
            Some(Origin::Set(s)) => (s, None),
            None => (self.file.clone(), None),
        };
        ScenarioError {
            file,
            line,
            key: (!key.is_empty()).then(|| key.to_string()),
            variant: variant.map(String::from),
            message,
            hint,
            more: Vec::new(),
        }
    }

    /// An error at `key` (dotted; list elements by index), located where the value that
    /// variant sees was written (or its nearest written parent).
    pub fn error_at(
        &self,
        key: &str,
        variant: Option<&str>,
        message: impl Into<String>,
        hint: Option<String>,
    ) -> ScenarioError {
        let span = self.merged(variant).ok().and_then(|t| {
            // A list element is `name[i]` in a key, `name.i` in the tree.
            let path = key.replace('[', ".").replace(']', "");
            tree::nearest(&t, &path).map(|(_, n)| n.key_span.clone())
        });
        self.located(key, span, variant, message.into(), hint)
    }

    /// Maps validation problems to located errors: the first one, with every other one in
    /// [`ScenarioError::more`].
    pub fn invalid(&self, variant: Option<&str>, problems: &[ConfigError]) -> ScenarioError {
        let one = |p: &ConfigError| {
            let hint = p.hint.clone().unwrap_or_else(|| {
                format!(
                    "fix `{}` in the file, or override it with --set {}=VALUE",
                    p.key, p.key
                )
            });
            self.error_at(&p.key, variant, p.message.clone(), Some(hint))
        };
        let Some(first) = problems.first() else {
            return ScenarioError::file(&self.file, "invalid scenario");
        };
        let mut err = one(first);
        err.more = problems[1..].iter().map(one).collect();
        err
    }

    /// Deserialises the merged document of `variant` into `T`. Unknown keys and wrong
    /// types are reported at the key that carries them.
    pub fn resolve<T: DeserializeOwned>(&self, variant: Option<&str>) -> Result<T, ScenarioError> {
        let merged = self.merged(variant)?;
        de::from_table::<T>(&merged, 0..0).map_err(|e| {
            let (path, span) = match e.at {
                Some((p, s)) => (p, Some(s)),
                None => (String::new(), None),
            };
            let setting = ConfigError::unreadable(&path, &e.message);
            self.located(&path, span, variant, setting.message, setting.hint)
        })
    }
}

/// `{a: {b: {c: leaf}}}` with every level positioned at `range`.
fn build_nested(parts: &[&str], leaf: Node, range: &Range<usize>) -> Table {
    let mut node = Node {
        key_span: range.clone(),
        ..leaf
    };
    for part in parts[1..].iter().rev() {
        node = Node {
            span: range.clone(),
            key_span: range.clone(),
            value: Value::Table(vec![(part.to_string(), node)]),
        };
    }
    vec![(parts[0].to_string(), node)]
}

#[cfg(test)]
mod tests;
