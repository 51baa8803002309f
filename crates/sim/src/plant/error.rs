//! The error type of the simulator: configuration problems name the key, call problems
//! name the argument.

use admittance_dynamics::{DimensionError, DynamicsError};
use admittance_loop::{ConfigError, LoopError};

/// Any error of the simulator crate.
///
/// A bad setting is the project's one keyed shape, [`ConfigError`] (issue 32), at the
/// dotted key of the offending value as it would appear in a scenario file below the
/// plant's table (e.g. `friction[2].v_s`, `environment.walls[0].normal`); a caller that
/// nests the plant's configuration under a table of its own puts its name before the key
/// ([`ConfigError::within`]).
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A configuration value is out of its domain, inconsistent with another, or names a
    /// joint or frame the model does not have.
    #[error("{0}")]
    Setting(ConfigError),
    /// Building the true model failed (e.g. a payload on a tip fixed to the base).
    #[error("building the plant's model: {0}")]
    Model(#[from] DynamicsError),
    /// A call argument has the wrong length.
    #[error("{0}")]
    Dimension(#[from] DimensionError),
}

impl SimError {
    /// A bad setting at `key`.
    pub fn config(key: impl Into<String>, message: impl Into<String>) -> Self {
        SimError::Setting(ConfigError::new(key, message))
    }

    /// A setting at `key` that names a `what` (`"joint"`, `"frame"`) the model does not
    /// have; the hint lists the ones it has (`known`, comma-separated).
    pub fn unknown_name(key: String, what: &str, name: &str, known: &str) -> Self {
        SimError::Setting(
            ConfigError::new(key, format!("unknown {what} '{name}'"))
                .hint(format!("the model has: {known}")),
        )
    }

    /// The dotted key of a configuration error, if this is one.
    pub fn key(&self) -> Option<&str> {
        self.setting().map(|s| s.key.as_str())
    }

    /// The bad setting, if this is one.
    pub fn setting(&self) -> Option<&ConfigError> {
        match self {
            SimError::Setting(s) => Some(s),
            _ => None,
        }
    }
}

/// The loop's signal chain inside the simulated sensors: its setting errors stay settings,
/// its argument errors stay argument errors.
impl From<LoopError> for SimError {
    fn from(e: LoopError) -> Self {
        match e {
            LoopError::Dimension {
                argument,
                expected,
                found,
            } => SimError::Dimension(DimensionError {
                argument,
                expected,
                found,
            }),
            other => SimError::Setting(other.into_setting()),
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
