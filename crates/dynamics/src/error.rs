//! Errors of model loading and of the algorithms' argument checks.

use std::fmt;

/// A problem found while reading a URDF: names the file, the line when known, the
/// element and what is wrong with it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UrdfError {
    /// The file (or the source name given to [`crate::Model::from_urdf_str`]).
    pub file: String,
    /// 1-based line of the offending element, when known.
    pub line: Option<u32>,
    /// The element, e.g. `joint 'left_s0' <limit>`.
    pub element: String,
    /// What is wrong, and where useful, how to fix it.
    pub problem: String,
}

impl fmt::Display for UrdfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(
                f,
                "{}:{}: {}: {}",
                self.file, line, self.element, self.problem
            ),
            None => write!(f, "{}: {}: {}", self.file, self.element, self.problem),
        }
    }
}

impl std::error::Error for UrdfError {}

/// Something questionable in a URDF that the loader accepted (e.g. an inertia no rigid
/// body can have): carried by the [`crate::Model`] (see [`crate::Model::warnings`]) so that
/// every tool can print it. `strict` loading turns these into errors.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadWarning {
    /// The file (or the source name given to [`crate::Model::from_urdf_str`]).
    pub file: String,
    /// 1-based line of the element, when known.
    pub line: Option<u32>,
    /// The element, e.g. `link 'panda_link3' <inertial> <inertia>`.
    pub element: String,
    /// What is questionable and what the loader did about it.
    pub problem: String,
}

impl fmt::Display for LoadWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(
                f,
                "{}:{}: {}: {}",
                self.file, line, self.element, self.problem
            ),
            None => write!(f, "{}: {}: {}", self.file, self.element, self.problem),
        }
    }
}

impl From<UrdfError> for LoadWarning {
    fn from(e: UrdfError) -> Self {
        Self {
            file: e.file,
            line: e.line,
            element: e.element,
            problem: e.problem,
        }
    }
}

/// An argument of a dynamics call has the wrong length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DimensionError {
    /// The argument, e.g. `"q"`.
    pub argument: &'static str,
    /// The length the model needs.
    pub expected: usize,
    /// The length given.
    pub found: usize,
}

impl fmt::Display for DimensionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "argument `{}` has {} values but the model has {} joints",
            self.argument, self.found, self.expected
        )
    }
}

impl std::error::Error for DimensionError {}

/// Checks that a slice has one value per joint.
#[inline(always)]
pub(crate) fn check_len(
    argument: &'static str,
    values: &[f64],
    expected: usize,
) -> Result<(), DimensionError> {
    if values.len() == expected {
        Ok(())
    } else {
        Err(DimensionError {
            argument,
            expected,
            found: values.len(),
        })
    }
}

/// Any error of this crate.
#[derive(Debug, thiserror::Error)]
pub enum DynamicsError {
    /// The URDF is malformed or describes something this crate does not model.
    #[error("{0}")]
    Urdf(#[from] UrdfError),
    /// The URDF file could not be read.
    #[error("{file}: cannot read the file: {source}")]
    Io {
        /// The path.
        file: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A call argument had the wrong length.
    #[error("{0}")]
    Dimension(#[from] DimensionError),
    /// An argument was outside its domain (e.g. a negative mass scale).
    #[error("{0}")]
    InvalidArgument(String),
}
