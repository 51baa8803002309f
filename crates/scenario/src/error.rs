//! Scenario errors: one line each, naming the file, the line, the key and the fix.

use std::fmt;

/// A scenario problem: the file (or `--set`), the line, the key and the fix; with every
/// further problem found in the same check, each on a line of its own.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioError {
    /// The scenario file, or `--set KEY=VALUE` for a command-line override.
    pub file: String,
    /// 1-based line where the offending key is written, when known.
    pub line: Option<usize>,
    /// Dotted key path, e.g. `controller.neural.k1`.
    pub key: Option<String>,
    /// The variant being resolved, when the problem is specific to one.
    pub variant: Option<String>,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub hint: Option<String>,
    /// Further problems found by the same check (printed after this one, one per line).
    pub more: Vec<ScenarioError>,
}

impl ScenarioError {
    /// A problem with the file as a whole (no line, no key).
    pub fn file(file: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            line: None,
            key: None,
            variant: None,
            message: message.into(),
            hint: None,
            more: Vec::new(),
        }
    }

    /// With a hint.
    pub fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.hint = Some(hint.into());
        self
    }

    fn fmt_one(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
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

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.fmt_one(f)?;
        for m in &self.more {
            writeln!(f)?;
            m.fmt_one(f)?;
        }
        Ok(())
    }
}

impl std::error::Error for ScenarioError {}
