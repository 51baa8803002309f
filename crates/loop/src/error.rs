//! The error type of the loop crate: every configuration problem names the dotted key of
//! the offending value as a scenario file (or a Python dict) writes it.

use admittance_control::ConfigError;

/// Any error of the loop crate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LoopError {
    /// A setting of the loop is out of its domain or inconsistent with another.
    #[error("{key}: {message}")]
    Invalid {
        /// Dotted key of the offending value (`observer.cutoff_hz`).
        key: String,
        /// What is wrong.
        message: String,
        /// How to fix it, when there is more to say than the bound.
        hint: Option<&'static str>,
    },
    /// A component (controller, admittance model, observer) refused its settings; the
    /// component's key is relative to `section`.
    #[error("{section}: {source}")]
    Component {
        /// Dotted key of the component's table (`controller.neural`).
        section: String,
        /// The component's own error.
        source: ConfigError,
    },
    /// A call argument has the wrong length.
    #[error("{argument}: expected {expected} values, got {found}")]
    Dimension {
        /// The argument's name.
        argument: &'static str,
        /// The joint count.
        expected: usize,
        /// The length given.
        found: usize,
    },
}

impl LoopError {
    /// A [`LoopError::Invalid`] at `key` without a hint.
    pub fn invalid(key: impl Into<String>, message: impl Into<String>) -> Self {
        LoopError::Invalid {
            key: key.into(),
            message: message.into(),
            hint: None,
        }
    }

    /// The same error with a hint (only [`LoopError::Invalid`] carries one).
    pub fn hint(mut self, text: &'static str) -> Self {
        if let LoopError::Invalid { hint, .. } = &mut self {
            *hint = Some(text);
        }
        self
    }

    /// The error with its hint, as one line (`key: message; hint: ...`): what a front end
    /// shows (the C ABI's `adm_last_error`, Python, the command line).
    pub fn text(&self) -> String {
        match self {
            LoopError::Invalid { hint: Some(h), .. } => format!("{self}; hint: {h}"),
            LoopError::Component { source, .. } => match &source.hint {
                Some(h) => format!("{self}; hint: {h}"),
                None => self.to_string(),
            },
            _ => self.to_string(),
        }
    }

    /// The error located in `file` when its key is a setting (a key that names a file
    /// already, as the deployment's checks do, is left as it is).
    pub fn located(self, file: &std::path::Path) -> Self {
        let key = self.key();
        if key.contains('/') || key.contains(std::path::MAIN_SEPARATOR) || key.is_empty() {
            return self;
        }
        let prefix = file.display().to_string();
        match self {
            LoopError::Invalid { key, message, hint } => LoopError::Invalid {
                key: format!("{prefix}: {key}"),
                message,
                hint,
            },
            LoopError::Component { section, source } => LoopError::Component {
                section: format!("{prefix}: {section}"),
                source,
            },
            other => other,
        }
    }

    /// The dotted key of the offending value (empty for a [`LoopError::Dimension`]).
    pub fn key(&self) -> String {
        match self {
            LoopError::Invalid { key, .. } => key.clone(),
            LoopError::Component { section, source } if source.key.is_empty() => section.clone(),
            LoopError::Component { section, source } => format!("{section}.{}", source.key),
            LoopError::Dimension { .. } => String::new(),
        }
    }

    /// The same error with `prefix.` put before its key (a caller that nests the loop's
    /// settings under a table of its own).
    pub fn within(self, prefix: &str) -> Self {
        match self {
            LoopError::Invalid { key, message, hint } => LoopError::Invalid {
                key: format!("{prefix}.{key}"),
                message,
                hint,
            },
            LoopError::Component { section, source } => LoopError::Component {
                section: format!("{prefix}.{section}"),
                source,
            },
            other => other,
        }
    }
}

/// Checks a slice length against the joint count.
pub(crate) fn check_len(
    argument: &'static str,
    values: &[f64],
    expected: usize,
) -> Result<(), LoopError> {
    if values.len() == expected {
        Ok(())
    } else {
        Err(LoopError::Dimension {
            argument,
            expected,
            found: values.len(),
        })
    }
}
