//! Arguments of `train` and `grow` checked before any work: numbers in their domains with
//! our own messages, the memory and work limits, the model file to write, and which exit
//! code each learning error gets.

use std::path::{Path, PathBuf};

use admittance_dynamics::Model;
use admittance_learning::broad::{check_model_destination, ArmIdentity, BroadError, Budget};
use clap::Args;

use crate::CliError;

/// `--nodes`: a positive integer (clap would read `-5` as an unknown flag).
pub fn positive_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(v) if v > 0 => Ok(v),
        _ => Err("the value must be a positive integer (1, 2, 3, ...)".into()),
    }
}

fn finite(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err("the value must be a finite number".into()),
        Err(_) => Err("not a number".into()),
    }
}

/// `--folds`: an integer >= 2.
pub fn fold_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(v) if v >= 2 => Ok(v),
        _ => Err("the value must be an integer >= 2 (contiguous stretches of the rows)".into()),
    }
}

/// A cut-off in Hz: finite and >= 0 (0: no filter).
pub fn non_negative_hz(text: &str) -> Result<f64, String> {
    match finite(text)? {
        v if v >= 0.0 => Ok(v),
        _ => Err("the value must be >= 0 Hz (0: the columns as recorded)".into()),
    }
}

/// A fraction of the rows, in (0, 1).
pub fn open_fraction(text: &str) -> Result<f64, String> {
    match finite(text)? {
        v if v > 0.0 && v < 1.0 => Ok(v),
        _ => Err("the value must be a fraction between 0 and 1, e.g. 0.2".into()),
    }
}

/// A limit: finite and > 0.
pub fn positive_number(text: &str) -> Result<f64, String> {
    match finite(text)? {
        v if v > 0.0 => Ok(v),
        _ => Err("the value must be a positive number".into()),
    }
}

/// `--max-memory-gb` and `--max-tflop`: the budget of a fit or growth.
#[derive(Args)]
pub struct BudgetArgs {
    /// Refuse a fit whose estimated peak memory is above this many GB (10^9 bytes).
    #[arg(long, default_value_t = 8.0, value_parser = positive_number, allow_negative_numbers = true)]
    max_memory_gb: f64,
    /// Refuse a fit whose estimated work is above this many 10^12 floating-point
    /// operations (the default, 100, is about three hours on two cores).
    #[arg(long, default_value_t = 100.0, value_parser = positive_number, allow_negative_numbers = true)]
    max_tflop: f64,
}

impl BudgetArgs {
    pub fn budget(&self) -> Budget {
        Budget {
            // Saturates at u64::MAX for absurdly large limits.
            max_memory_bytes: (self.max_memory_gb * 1e9) as u64,
            max_flop: self.max_tflop * 1e12,
        }
    }
}

/// `--urdf`, `--base`, `--tip` when they are optional (`grow`: to check the arm's model).
#[derive(Args)]
pub struct OptionalArmArgs {
    /// URDF of the arm: the model's recorded arm (joint names and model fingerprint) must
    /// be this one.
    #[arg(long)]
    urdf: Option<PathBuf>,
    /// Base link (default: the URDF's root link).
    #[arg(long, requires = "urdf")]
    base: Option<String>,
    /// Tip link (default: the single leaf link).
    #[arg(long, requires = "urdf")]
    tip: Option<String>,
}

impl OptionalArmArgs {
    /// The arm's model, if `--urdf` was given (a missing or bad URDF is bad input).
    pub fn load(&self) -> Result<Option<Model>, CliError> {
        let Some(urdf) = &self.urdf else {
            return Ok(None);
        };
        Model::from_urdf_file(urdf, self.base.as_deref(), self.tip.as_deref())
            .map(Some)
            .map_err(|e| CliError::input(e.to_string()))
    }
}

/// The identity recorded in model files for `model`.
pub fn arm_identity(model: &Model) -> ArmIdentity {
    ArmIdentity::new(model.joint_names(), model.fingerprint())
}

/// `--out` must be a new name or a model file (through a link: the file it points to),
/// checked before any work starts.
pub fn check_out(path: &Path) -> Result<(), CliError> {
    check_model_destination(path)
        .map(|_| ())
        .map_err(|e| CliError::usage(format!("--out {e}")))
}

/// The exit code and message of a learning error: bad data or model file 3, a request
/// beyond the limits or a refused `--out` 2 (with what to change), a failed fit 1.
pub fn learn_error(e: BroadError) -> CliError {
    let message = e.to_string();
    match e {
        BroadError::TooManyNodes { .. } => CliError::usage(format!(
            "--nodes: {message} (rows held out by --validation-fraction not counted); use fewer nodes"
        )),
        BroadError::MemoryBudget { .. } => CliError::usage(format!(
            "{message}: use fewer --nodes, or raise the limit with --max-memory-gb if the machine has the memory"
        )),
        BroadError::WorkBudget { .. } => CliError::usage(format!(
            "{message}: use fewer --nodes or rows, or raise the limit with --max-tflop"
        )),
        BroadError::Config(_) | BroadError::Destination { .. } => CliError::usage(message),
        BroadError::Dimension { .. }
        | BroadError::Empty { .. }
        | BroadError::NoMotion { .. }
        | BroadError::NonFinite { .. }
        | BroadError::OutOfRange { .. }
        | BroadError::GrowthDataMismatch(_)
        | BroadError::ArmMismatch(_)
        | BroadError::SettingsMismatch(_)
        | BroadError::NoGrowthState
        | BroadError::Format { .. }
        | BroadError::UnsupportedVersion { .. }
        | BroadError::Checksum { .. } => CliError::input(message),
        _ => CliError {
            code: 1,
            message,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_checked_with_our_messages() {
        assert_eq!(positive_count("40"), Ok(40));
        for bad in ["-5", "0", "1.5", "x", ""] {
            assert!(
                positive_count(bad)
                    .unwrap_err()
                    .contains("positive integer"),
                "{bad}"
            );
        }
        assert_eq!(non_negative_hz("0"), Ok(0.0));
        assert_eq!(non_negative_hz("10"), Ok(10.0));
        for bad in ["nan", "NaN", "inf", "-1", "abc"] {
            assert!(non_negative_hz(bad).is_err(), "{bad}");
        }
        assert!(open_fraction("0.2").is_ok());
        for bad in ["0", "1", "nan", "-0.2", "1.5"] {
            assert!(open_fraction(bad).is_err(), "{bad}");
        }
        assert!(positive_number("0").is_err() && positive_number("inf").is_err());
    }
}
