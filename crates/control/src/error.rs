//! Configuration errors and run-time faults.

use std::fmt;

/// A configuration value that cannot be used, named by its key: the one shape of a bad
/// setting in the project (issue 32).
///
/// `key` is the dotted path of the offending field inside the configuration struct
/// (`"saturation.rho"`, `"k1[3]"`, `"f_network.width"`), so that a scenario loader can map
/// it to a file and line; `message` says what is wrong, `hint` how to fix it when there is
/// more to say than the bound. Every layer above keeps the three: a caller that nests the
/// settings under a table puts the table before the key ([`ConfigError::within`]), the
/// layer that read the file locates it (a scenario at its line, the loop in `loop.toml`),
/// and every front end (`adm_last_error`, Python, the command line) shows the same
/// one-line text, `` key `k`: message; hint: ... ``.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConfigError {
    /// Dotted path of the offending field (empty: the settings as a whole).
    pub key: String,
    /// What is wrong.
    pub message: String,
    /// How to fix it, when there is more to say than the bound.
    pub hint: Option<String>,
}

impl ConfigError {
    /// An error for `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        ConfigError {
            key: key.into(),
            message: message.into(),
            hint: None,
        }
    }

    /// A deserialiser's complaint at `key` (an unknown field, a wrong type, a missing
    /// field), with the fix for its kind: the same for a scenario file, a loop file and a
    /// Python dict.
    pub fn unreadable(key: impl Into<String>, message: impl std::fmt::Display) -> Self {
        let message = message.to_string().trim().replace('\n', " ");
        let hint = if message.contains("unknown field") {
            Some("remove the key or fix its spelling; the expected keys are listed")
        } else if message.contains("invalid type") {
            Some("check the value's type (number, string, list, table)")
        } else if message.contains("missing field") {
            Some("add the key to the table")
        } else {
            None
        };
        let error = ConfigError::new(key, message);
        match hint {
            Some(h) => error.hint(h),
            None => error,
        }
    }

    /// The same error with a hint.
    pub fn hint(mut self, text: impl Into<String>) -> Self {
        self.hint = Some(text.into());
        self
    }

    /// The one-line text every front end shows (`` key `k`: message; hint: ... ``); the
    /// same as `to_string()`.
    pub fn text(&self) -> String {
        self.to_string()
    }

    /// The same error with `prefix.` put in front of the key.
    pub fn within(mut self, prefix: &str) -> Self {
        if !prefix.is_empty() {
            self.key = if self.key.is_empty() || self.key.starts_with('[') {
                format!("{prefix}{}", self.key)
            } else {
                format!("{prefix}.{}", self.key)
            };
        }
        self
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !self.key.is_empty() {
            write!(f, "key `{}`: ", self.key)?;
        }
        f.write_str(&self.message)?;
        if let Some(h) = &self.hint {
            write!(f, "; hint: {h}")?;
        }
        Ok(())
    }
}

impl std::error::Error for ConfigError {}

/// Why a step did not run its normal law (see [`crate::SafeHold`] for what is written
/// instead).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// An argument has the wrong length (`argument` names it: `"q"`, `"torque"`, ...).
    WrongLength {
        /// The argument.
        argument: &'static str,
        /// The controller's joint count.
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// A measured value (`q` or `qdot`) is NaN or infinite.
    NonFiniteMeasurement {
        /// `"q"` or `"qdot"`.
        argument: &'static str,
        /// First offending joint.
        joint: usize,
    },
    /// A joint's measured position has been bit-identical for `steps` consecutive steps
    /// while that joint was expected to move (see [`crate::SafeHoldConfig::stale_steps`]):
    /// a frozen encoder or dropped samples.
    StaleMeasurement {
        /// The first stale joint (chain order).
        joint: usize,
        /// Consecutive identical samples seen on it.
        steps: u32,
    },
    /// A reference (`q_ref`, `qdot_ref`, `qddot_ref`, or the desired trajectory of the
    /// admittance model) is NaN or infinite.
    NonFiniteReference {
        /// The argument.
        argument: &'static str,
        /// First offending joint.
        joint: usize,
    },
    /// The external-torque estimate is NaN or infinite.
    NonFiniteEstimate {
        /// First offending joint.
        joint: usize,
    },
    /// `dt` is not finite and positive.
    InvalidTimeStep,
    /// The control law itself produced a non-finite torque (e.g. diverged weights); the
    /// safe hold was written instead.
    NonFiniteOutput {
        /// First offending joint.
        joint: usize,
    },
    /// A dynamics or network call failed unexpectedly (should not happen after the checks
    /// above; reported rather than panicking).
    Internal(&'static str),
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Fault::WrongLength {
                argument,
                expected,
                found,
            } => {
                write!(
                    f,
                    "`{argument}` has {found} values, the controller has {expected} joints"
                )
            }
            Fault::NonFiniteMeasurement { argument, joint } => {
                write!(f, "measured `{argument}` is not finite at joint {joint}")
            }
            Fault::StaleMeasurement { joint, steps } => {
                write!(
                    f,
                    "measured `q` of joint {joint} unchanged for {steps} steps while it is expected to move"
                )
            }
            Fault::NonFiniteReference { argument, joint } => {
                write!(f, "reference `{argument}` is not finite at joint {joint}")
            }
            Fault::NonFiniteEstimate { joint } => {
                write!(f, "external torque estimate is not finite at joint {joint}")
            }
            Fault::InvalidTimeStep => write!(f, "time step is not finite and positive"),
            Fault::NonFiniteOutput { joint } => {
                write!(
                    f,
                    "the control law produced a non-finite torque at joint {joint}"
                )
            }
            Fault::Internal(what) => write!(f, "internal error: {what}"),
        }
    }
}

/// Outcome of one controller, admittance or observer step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[must_use]
pub enum StepStatus {
    /// The normal law ran; the output is its (clamped) result.
    Ok,
    /// A fault was detected; the documented safe output was written instead.
    Fault(Fault),
}

impl StepStatus {
    /// Whether the step ran normally.
    pub fn is_ok(&self) -> bool {
        matches!(self, StepStatus::Ok)
    }

    /// The fault, if any.
    pub fn fault(&self) -> Option<Fault> {
        match self {
            StepStatus::Ok => None,
            StepStatus::Fault(f) => Some(*f),
        }
    }
}

impl From<Result<(), Fault>> for StepStatus {
    fn from(r: Result<(), Fault>) -> Self {
        match r {
            Ok(()) => StepStatus::Ok,
            Err(f) => StepStatus::Fault(f),
        }
    }
}
