//! The error type of the loop crate: a bad setting is the project's one keyed shape,
//! [`ConfigError`] (issue 32), at the dotted key a loop file (or a scenario file, or a
//! Python dict) writes; the layer that read the settings from a file locates it there.

use std::fmt;
use std::path::{Path, PathBuf};

use admittance_control::ConfigError;

/// Any error of the loop crate.
#[derive(Debug, Clone, PartialEq)]
pub enum LoopError {
    /// A setting of the loop, or of one of its components under its table
    /// (`controller.neural.k1[2]`), is out of its domain or inconsistent with another.
    Setting {
        /// The key, what is wrong and how to fix it.
        setting: ConfigError,
        /// The loop file the setting was read from, once the reader has located it.
        file: Option<PathBuf>,
    },
    /// A file cannot be used (missing, unreadable, not what its manifest lists): named by
    /// its path, since no setting is at fault.
    File {
        /// The file (or folder).
        path: PathBuf,
        /// What is wrong.
        message: String,
        /// How to fix it.
        hint: Option<String>,
    },
    /// A call argument has the wrong length.
    Dimension {
        /// The argument's name.
        argument: &'static str,
        /// The joint count.
        expected: usize,
        /// The length given.
        found: usize,
    },
}

impl fmt::Display for LoopError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoopError::Setting { setting, file } => {
                if let Some(file) = file {
                    write!(f, "{}: ", file.display())?;
                }
                write!(f, "{setting}")
            }
            LoopError::File {
                path,
                message,
                hint,
            } => {
                write!(f, "{}: {message}", path.display())?;
                match hint {
                    Some(h) => write!(f, "; hint: {h}"),
                    None => Ok(()),
                }
            }
            LoopError::Dimension {
                argument,
                expected,
                found,
            } => write!(f, "{argument}: expected {expected} values, got {found}"),
        }
    }
}

impl std::error::Error for LoopError {}

/// A component's error (its key already under the component's table, see
/// [`ConfigError::within`]) is a setting of the loop.
impl From<ConfigError> for LoopError {
    fn from(setting: ConfigError) -> Self {
        LoopError::Setting {
            setting,
            file: None,
        }
    }
}

impl LoopError {
    /// A bad setting at `key` without a hint.
    pub fn invalid(key: impl Into<String>, message: impl Into<String>) -> Self {
        ConfigError::new(key, message).into()
    }

    /// A file that cannot be used.
    pub fn file(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        LoopError::File {
            path: path.into(),
            message: message.into(),
            hint: None,
        }
    }

    /// The same error with a hint (a [`LoopError::Dimension`] needs none).
    pub fn hint(mut self, text: impl Into<String>) -> Self {
        match &mut self {
            LoopError::Setting { setting, .. } => setting.hint = Some(text.into()),
            LoopError::File { hint, .. } => *hint = Some(text.into()),
            LoopError::Dimension { .. } => {}
        }
        self
    }

    /// The one-line text every front end shows (the C ABI's `adm_last_error`, Python, the
    /// command line): the same as `to_string()`, hint included.
    pub fn text(&self) -> String {
        self.to_string()
    }

    /// The bad setting, if this is one.
    pub fn setting(&self) -> Option<&ConfigError> {
        match self {
            LoopError::Setting { setting, .. } => Some(setting),
            _ => None,
        }
    }

    /// The error as a bad setting, for a caller whose errors are settings: a setting as it
    /// is (its file, if located, is the caller's to name), any other error under no key.
    pub fn into_setting(self) -> ConfigError {
        match self {
            LoopError::Setting { setting, .. } => setting,
            LoopError::File {
                path,
                message,
                hint,
            } => ConfigError {
                key: String::new(),
                message: format!("{}: {message}", path.display()),
                hint,
            },
            other => ConfigError::new("", other.to_string()),
        }
    }

    /// A setting not yet located, located in the loop file `file` (the reader's part).
    pub fn located(self, file: &Path) -> Self {
        match self {
            LoopError::Setting {
                setting,
                file: None,
            } => LoopError::Setting {
                setting,
                file: Some(file.to_path_buf()),
            },
            other => other,
        }
    }

    /// The dotted key of the offending setting (empty for any other error).
    pub fn key(&self) -> String {
        self.setting().map(|s| s.key.clone()).unwrap_or_default()
    }

    /// The same setting error at `key` instead: a building block (a low-pass) names its
    /// own argument, its caller the setting it was given (`signals.filter_cutoff_hz`).
    pub fn at(self, key: &str) -> Self {
        match self {
            LoopError::Setting { setting, file } => LoopError::Setting {
                setting: ConfigError {
                    key: key.to_string(),
                    ..setting
                },
                file,
            },
            other => other,
        }
    }

    /// The same error with `prefix.` put before its key (a caller that nests the loop's
    /// settings under a table of its own).
    pub fn within(self, prefix: &str) -> Self {
        match self {
            LoopError::Setting { setting, file } => LoopError::Setting {
                setting: setting.within(prefix),
                file,
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
