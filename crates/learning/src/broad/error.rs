//! Error type of the broad network.

use std::path::PathBuf;

/// Everything that can go wrong when fitting, growing, evaluating, saving or loading a
/// [`BroadModel`](super::BroadModel). No public function of the module panics on bad
/// input; it returns one of these.
#[derive(Debug, thiserror::Error)]
pub enum BroadError {
    /// A dimension is zero or does not match what the model or the data expects.
    #[error("dimension mismatch in {what}: expected {expected}, got {got}")]
    Dimension {
        /// Which quantity was checked.
        what: &'static str,
        /// The expected size.
        expected: usize,
        /// The size that was passed.
        got: usize,
    },
    /// A data set has no rows.
    #[error("{what} has no samples")]
    Empty {
        /// Which data set.
        what: &'static str,
    },
    /// A non-finite value (NaN or infinity) in a data set or an input vector.
    #[error("non-finite value {value} in {what}, row {row}, column {column}")]
    NonFinite {
        /// Which array (e.g. "training inputs").
        what: &'static str,
        /// Row (sample) index, 0-based.
        row: usize,
        /// Column index, 0-based.
        column: usize,
        /// The offending value.
        value: f64,
    },
    /// A configuration value is out of its domain.
    #[error("invalid configuration: {0}")]
    Config(String),
    /// The regularised normal matrix was not positive definite for any candidate lambda.
    #[error("Cholesky factorisation failed for every lambda tried ({tried:?}); increase lambda")]
    NotPositiveDefinite {
        /// The absolute lambdas that were tried.
        tried: Vec<f64>,
    },
    /// `fit` needs a validation set to choose between several lambdas.
    #[error("a lambda grid of {0} values needs a validation set to choose from")]
    NeedValidation(usize),
    /// The model holds no growth state (it was stripped, or loaded from a file saved
    /// without it), so nodes cannot be added incrementally.
    #[error("the model holds no growth state (Gram matrix); refit to grow it")]
    NoGrowthState,
    /// The data passed to `grow` is not the data the model was trained on.
    #[error("growth data does not match the training data: {0}")]
    GrowthDataMismatch(String),
    /// Greville update failed (dimension or numerical problem).
    #[error("pseudo-inverse update: {0}")]
    Greville(String),
    /// Input/output error while reading or writing a model file.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A model file is corrupted, truncated or not a model file.
    #[error("{}: {reason}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A model file of a format version this build cannot read.
    #[error("{}: unsupported format_version {found} (this build reads version {supported})", path.display())]
    UnsupportedVersion {
        /// The file.
        path: PathBuf,
        /// Version found in the file.
        found: u64,
        /// Version this build reads.
        supported: u64,
    },
    /// The checksum stored in a model file does not match its contents.
    #[error("{}: checksum mismatch (stored {stored:#018x}, computed {computed:#018x}): the file is corrupted", path.display())]
    Checksum {
        /// The file.
        path: PathBuf,
        /// Checksum stored in the file.
        stored: u64,
        /// Checksum computed from the contents.
        computed: u64,
    },
}
