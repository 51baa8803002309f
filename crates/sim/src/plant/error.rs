//! The error type of the simulator: configuration problems name the key, call problems
//! name the argument.

use admittance_dynamics::{DimensionError, DynamicsError};

/// Any error of the simulator crate.
///
/// Configuration errors carry the dotted key of the offending value as it would appear
/// in a scenario file below the plant's table (e.g. `friction[2].v_s`,
/// `environment.walls[0].normal`); a caller that nests the plant's configuration under a
/// table of its own prefixes its name.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A configuration value is out of its domain or inconsistent with another.
    #[error("{key}: {message}")]
    Config {
        /// Dotted key of the offending value.
        key: String,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// A configuration names a joint (or frame) the model does not have.
    #[error("{key}: unknown {what} '{name}'; the model has: {known}")]
    UnknownName {
        /// Dotted key of the offending value.
        key: String,
        /// `"joint"` or `"frame"`.
        what: &'static str,
        /// The name given.
        name: String,
        /// The names the model has, comma-separated.
        known: String,
    },
    /// Building the true model failed (e.g. a payload on a tip fixed to the base).
    #[error("building the plant's model: {0}")]
    Model(#[from] DynamicsError),
    /// A call argument has the wrong length.
    #[error("{0}")]
    Dimension(#[from] DimensionError),
}

impl SimError {
    /// A [`SimError::Config`] for `key`.
    pub fn config(key: impl Into<String>, message: impl Into<String>) -> Self {
        SimError::Config {
            key: key.into(),
            message: message.into(),
        }
    }

    /// The dotted key of a configuration error, if this is one.
    pub fn key(&self) -> Option<&str> {
        match self {
            SimError::Config { key, .. } | SimError::UnknownName { key, .. } => Some(key),
            _ => None,
        }
    }
}

/// Checks a slice length against the model's joint count.
pub(crate) fn check_len(
    argument: &'static str,
    values: &[f64],
    expected: usize,
) -> Result<(), SimError> {
    if values.len() == expected {
        Ok(())
    } else {
        Err(SimError::Dimension(DimensionError {
            argument,
            expected,
            found: values.len(),
        }))
    }
}
