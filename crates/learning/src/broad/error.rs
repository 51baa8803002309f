//! Error type of the broad network.

use super::limits::format_bytes;
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
    /// Every input column is constant (no motion): nothing can be learnt or validated, and
    /// an error relative to a target that does not vary is meaningless.
    #[error("{what}: every input column is constant (no motion in the recording); record the arm moving (e.g. `admittance excite`)")]
    NoMotion {
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
    /// A value of a data set is beyond [`MAX_ABS_DATA_VALUE`](super::MAX_ABS_DATA_VALUE)
    /// in magnitude (a unit error or a corrupted value: its square would overflow the
    /// sums of the fit).
    #[error("value {value:e} in {what}, row {row}, column {column}, is beyond +-{limit:e}")]
    OutOfRange {
        /// Which array (e.g. "training targets").
        what: &'static str,
        /// Row (sample) index, 0-based.
        row: usize,
        /// Column index, 0-based.
        column: usize,
        /// The offending value.
        value: f64,
        /// The limit.
        limit: f64,
    },
    /// A fit or growth produced a non-finite weight or error measure; nothing was kept.
    #[error("the fit is not finite: {0}")]
    NonFiniteResult(String),
    /// More enhancement nodes than training rows.
    #[error("{nodes} nodes need at least as many training rows, the data have {rows}")]
    TooManyNodes {
        /// Nodes asked for.
        nodes: usize,
        /// Training rows.
        rows: usize,
    },
    /// The estimated memory of a fit or growth is above the budget (or its byte count
    /// overflows 64 bits: `needed_bytes` is `None`).
    #[error("{nodes} nodes need {} of memory, more than the limit of {}", format_bytes(*.needed_bytes), format_bytes(Some(*.limit_bytes)))]
    MemoryBudget {
        /// Estimated peak memory, bytes; `None` beyond 64 bits.
        needed_bytes: Option<u64>,
        /// The limit, bytes.
        limit_bytes: u64,
        /// Nodes asked for.
        nodes: usize,
    },
    /// The estimated work of a fit or growth is above the budget.
    #[error("the fit needs about {needed_flop:.1e} floating-point operations, more than the limit of {limit_flop:.1e}")]
    WorkBudget {
        /// Estimated work.
        needed_flop: f64,
        /// The limit.
        limit_flop: f64,
    },
    /// The model was trained for another arm (joint names or the arm model's fingerprint
    /// differ); the message says what differs.
    #[error("{0}")]
    ArmMismatch(String),
    /// The model was trained with other data settings (input filter, validation split,
    /// target) than the user expects; the message lists them.
    #[error("{0}")]
    SettingsMismatch(String),
    /// A path a model file may not be written to (a directory, a device, a FIFO, a file
    /// that is not a model file...).
    #[error("{}: {reason}", path.display())]
    Destination {
        /// The path.
        path: PathBuf,
        /// Why not.
        reason: String,
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
    /// `fit` needs a validation set (or cross-validation folds) to choose between several
    /// lambdas.
    #[error("a lambda grid of {0} values needs a validation set or cross-validation folds to choose from")]
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
    #[error("{}: unsupported format_version {found} (this build reads versions 1 to {supported})", path.display())]
    UnsupportedVersion {
        /// The file.
        path: PathBuf,
        /// Version found in the file.
        found: u64,
        /// Newest version this build reads.
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
