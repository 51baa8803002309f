//! What an identification or network file records about how it was made, and the checks
//! that the flags and the other files agree with it (issue 30 item 6, issue 34 item 6):
//! `evaluate` and `train --nominal` take the input conditioning from the files, refuse a
//! flag that contradicts them, and refuse a network of another arm or a residual of
//! another identification, naming the file and what differs.

use std::path::{Path, PathBuf};

use admittance_dynamics::{Identification, Model};
use admittance_learning::broad::{fnv1a64, ArmCheck, BroadModel, TrainingTarget};
use admittance_scenario::{sample_rate_hz, ConditionedSamples, FreeMotionData};

use super::args::arm_identity;
use crate::CliError;

/// An identification file of the arm, with what it records of its making.
pub struct IdentificationFile {
    pub path: PathBuf,
    pub ident: Identification,
    /// FNV-1a 64 of the file's bytes (what a residual network records).
    pub checksum: u64,
    /// Cut-off (Hz) of the conditioning the fit's samples went through (0: as recorded).
    pub input_filter_hz: f64,
    /// How much later each joint's torque signal is than the motion (s), as the fit
    /// estimated it (empty: none).
    pub delay_s: Vec<f64>,
}

impl IdentificationFile {
    /// Reads `path` for `arm` (its fingerprint must match).
    pub fn load(path: &Path, arm: &Model) -> Result<Self, CliError> {
        // Regular files only (a FIFO would block the read for ever, issue 34 item 9).
        let bytes = admittance_files::read_regular(path, admittance_files::TEXT_LIMIT)
            .map_err(|e| CliError::input(format!("{}: cannot read: {e}", path.display())))?;
        let ident = Identification::load(path, arm).map_err(|e| CliError::input(e.to_string()))?;
        let input_filter_hz = recorded_filter_hz(&bytes, &ident);
        let delay_s = ident.summary.delay_s.clone();
        Ok(Self {
            path: path.to_path_buf(),
            checksum: fnv1a64(&bytes),
            input_filter_hz,
            delay_s,
            ident,
        })
    }

    /// `data` conditioned at `input_filter_hz` with each motion sample paired with each
    /// joint's torque `delay_s` later, as the identification was fitted
    /// (`admittance_scenario::ConditionedSamples`).
    pub fn paired(
        &self,
        path: &Path,
        data: &FreeMotionData,
        input_filter_hz: f64,
    ) -> Result<ConditionedSamples, CliError> {
        let mut rows = ConditionedSamples::new(data, input_filter_hz).map_err(|e| {
            CliError::usage(format!(
                "--input-filter-hz {input_filter_hz} with the data of {}: {e}",
                path.display()
            ))
        })?;
        rows.delay_torque(&self.delay_s, sample_rate_hz(data));
        Ok(rows)
    }
}

/// Inputs `[q, qdot, qddot]` and torques (row-major) of conditioned samples.
pub fn network_arrays(rows: &ConditionedSamples) -> (Vec<f64>, Vec<f64>) {
    let n = rows.dof;
    let mut x = Vec::with_capacity(3 * rows.tau.len());
    for k in 0..rows.tau.len() / n.max(1) {
        for s in [&rows.q, &rows.qdot, &rows.qddot] {
            x.extend_from_slice(&s[k * n..(k + 1) * n]);
        }
    }
    (x, rows.tau.clone())
}

/// The identification's conditioning: its summary's `input_filter_hz`, else (files written
/// before the summary held it) the `input_filter_hz` among what `admittance identify`
/// recorded it was made from, else 0.
fn recorded_filter_hz(bytes: &[u8], ident: &Identification) -> f64 {
    if ident.summary.input_filter_hz > 0.0 {
        return ident.summary.input_filter_hz;
    }
    serde_json::from_slice::<serde_json::Value>(bytes)
        .ok()
        .and_then(|v| v.pointer("/payload/data/input_filter_hz")?.as_f64())
        .filter(|hz| hz.is_finite() && *hz >= 0.0)
        .unwrap_or(0.0)
}

/// The input conditioning (Hz) for files that record theirs (`recorded`: file and cut-off):
/// the files' common value, which `flag` (when given) must equal; without recorded files,
/// `flag` or 0. Files that disagree are refused: they cannot be scored on the same
/// conditioned signals.
pub fn input_filter_hz(flag: Option<f64>, recorded: &[(String, f64)]) -> Result<f64, CliError> {
    let Some((first, hz)) = recorded.first() else {
        return Ok(flag.unwrap_or(0.0));
    };
    if let Some((other, other_hz)) = recorded.iter().find(|(_, h)| h.to_bits() != hz.to_bits()) {
        return Err(CliError::input(format!(
            "{first} was made with input filter {hz} Hz, {other} with {other_hz} Hz: they cannot be \
             scored on the same conditioned signals; give files made with the same --input-filter-hz"
        )));
    }
    match flag {
        Some(f) if f.to_bits() != hz.to_bits() => Err(CliError::usage(format!(
            "--input-filter-hz {f}, but {first} was made with input filter {hz} Hz: drop the flag \
             (the file's conditioning is used)"
        ))),
        _ => Ok(*hz),
    }
}

/// What a network file learned, as far as its consumer needs to know.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Learned {
    /// The free-motion torque (the paper's network).
    Torque,
    /// The residual of the identification given (checksum checked).
    IdentifiedResidual,
    /// The file records no target (format version 1): taken as its flag says.
    Unrecorded,
}

/// Checks a network file against the arm and, for a residual, the identification it was
/// trained on (`grow`'s checks); one line naming the file and what differs.
pub fn check_network(
    path: &Path,
    net: &BroadModel,
    arm: &Model,
    ident: Option<&IdentificationFile>,
) -> Result<Learned, CliError> {
    let file = path.display();
    match net.check_arm(&arm_identity(arm)) {
        Ok(ArmCheck::Matches) => {}
        Ok(ArmCheck::Unrecorded) => eprintln!(
            "admittance: warning: {file} records no arm (format version 1): not checked against --urdf"
        ),
        Err(e) => return Err(CliError::input(format!("{file}: {e}"))),
    }
    let Some(settings) = net.provenance().data else {
        return Ok(Learned::Unrecorded);
    };
    match settings.target {
        TrainingTarget::FreeMotionTorque => Ok(Learned::Torque),
        TrainingTarget::IdentifiedResidual { checksum } => match ident {
            None => Err(CliError::usage(format!(
                "{file} learned the residual of an identification (checksum {checksum:016x}): \
                 give that identification file with --identification"
            ))),
            Some(id) if id.checksum != checksum => Err(CliError::input(format!(
                "{file} learned the residual of the identification with checksum {checksum:016x}, \
                 but {} has checksum {:016x}: give the identification it was trained on",
                id.path.display(),
                id.checksum
            ))),
            Some(_) => Ok(Learned::IdentifiedResidual),
        },
        TrainingTarget::NominalResidual {
            nominal_inertia_scale,
        } => Err(CliError::usage(format!(
            "{file} learned the residual of the URDF model with inertias scaled by \
             {nominal_inertia_scale} (a scenario's hybrid observer): run it with its scenario; \
             here a residual must be of an identification file (`admittance train --nominal`)"
        ))),
    }
}

/// The network's own input conditioning, if it records one.
pub fn network_filter_hz(net: &BroadModel) -> Option<f64> {
    net.provenance().data.map(|d| d.input_filter_hz)
}
