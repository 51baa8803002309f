//! Identification files: JSON, versioned, checksummed, carrying the arm they belong to
//! and the data they were made from (docs/outputs.md, "Identification files"). Written
//! atomically; a file that is not an identification file is never overwritten.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::algorithms::regressor::inertial_parameters;
use crate::error::DynamicsError;
use crate::identification::{Identification, IdentificationSummary, JointTerms};
use crate::model::Model;

/// The `format` tag of identification files.
pub const IDENTIFICATION_FORMAT: &str = "admittance-identification";
/// The `format_version` this build writes and reads.
pub const IDENTIFICATION_FORMAT_VERSION: u64 = 1;

/// What an identification file holds (its `payload`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IdentificationFile {
    /// The URDF the model was identified from, as loaded (absolute path when it was a file).
    pub urdf: String,
    /// The chain's base link and tip frame.
    pub base: String,
    /// The tip frame.
    pub tip: String,
    /// Joint names in chain order.
    pub joints: Vec<String>,
    /// [`Model::fingerprint`] of the URDF model (hex): which arm this belongs to.
    pub urdf_fingerprint: String,
    /// Identified inertial parameters, 10 per body (Pinocchio's order).
    pub inertial_parameters: Vec<f64>,
    /// Identified joint terms.
    pub joint_terms: Vec<JointTerms>,
    /// What was chosen and measured.
    pub summary: IdentificationSummary,
    /// The data it was made from (files, checksums, filters), as the caller recorded it.
    pub data: BTreeMap<String, Value>,
    /// The program that wrote it.
    pub created_by: String,
}

fn err(path: &Path, m: impl std::fmt::Display) -> DynamicsError {
    DynamicsError::InvalidArgument(format!("{}: {m}", path.display()))
}

/// FNV-1a 64 of the payload's canonical JSON text (keys sorted).
fn checksum(payload: &Value) -> String {
    let text = payload.to_string();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

impl Identification {
    /// The file contents for this identification of `urdf_model` (the model it was
    /// identified from), with `data` describing the recordings.
    pub fn to_file(&self, urdf_model: &Model, data: BTreeMap<String, Value>) -> IdentificationFile {
        let urdf = std::fs::canonicalize(&urdf_model.source)
            .map(|p| p.display().to_string())
            .unwrap_or_else(|_| urdf_model.source.clone());
        IdentificationFile {
            urdf,
            base: urdf_model.base_link.clone(),
            tip: urdf_model.tip().name.clone(),
            joints: urdf_model.joint_names().map(str::to_string).collect(),
            urdf_fingerprint: format!("{:016x}", urdf_model.fingerprint()),
            inertial_parameters: inertial_parameters(&self.model),
            joint_terms: self.joint_terms.clone(),
            summary: self.summary.clone(),
            data,
            created_by: format!("admittance-dynamics {}", env!("CARGO_PKG_VERSION")),
        }
    }

    /// Writes the identification atomically (a temporary file renamed into place). An
    /// existing file at `path` is replaced only when it is an identification file.
    pub fn save(
        &self,
        path: &Path,
        urdf_model: &Model,
        data: BTreeMap<String, Value>,
    ) -> Result<(), DynamicsError> {
        if path.exists() && read_envelope(path).is_err() {
            return Err(err(
                path,
                "exists and is not an identification file: not overwritten (choose another --out)",
            ));
        }
        let payload =
            serde_json::to_value(self.to_file(urdf_model, data)).map_err(|e| err(path, e))?;
        let envelope = serde_json::json!({
            "format": IDENTIFICATION_FORMAT,
            "format_version": IDENTIFICATION_FORMAT_VERSION,
            "checksum": checksum(&payload),
            "payload": payload,
        });
        let text = serde_json::to_string_pretty(&envelope).map_err(|e| err(path, e))? + "\n";
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let tmp: PathBuf = dir.join(format!(
            ".{}.tmp{}",
            path.file_name()
                .and_then(|s| s.to_str())
                .unwrap_or("identification"),
            std::process::id()
        ));
        std::fs::write(&tmp, text).map_err(|e| err(&tmp, format!("cannot write: {e}")))?;
        std::fs::rename(&tmp, path).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            err(
                path,
                format!("cannot move the written file into place: {e}"),
            )
        })
    }

    /// Reads an identification file and applies it to `urdf_model`, which must be the
    /// model it was identified from (same fingerprint).
    pub fn load(path: &Path, urdf_model: &Model) -> Result<Identification, DynamicsError> {
        let file = read_file(path)?;
        let found = format!("{:016x}", urdf_model.fingerprint());
        if found != file.urdf_fingerprint {
            return Err(err(path, format!(
                "was identified for another arm model ({} with fingerprint {}; this model '{}' has {found}): load it with the URDF it was made from",
                file.urdf, file.urdf_fingerprint, urdf_model.source
            )));
        }
        Self::from_file(path, &file, urdf_model)
    }

    /// Reads an identification file and the URDF it names (a relative path is taken
    /// from the file's folder first, then from the working directory).
    pub fn load_with_urdf(path: &Path) -> Result<(Identification, Model), DynamicsError> {
        let file = read_file(path)?;
        let stated = PathBuf::from(&file.urdf);
        let beside = path
            .parent()
            .map(|d| d.join(&stated))
            .filter(|p| stated.is_relative() && p.exists());
        let urdf_path = beside.unwrap_or(stated);
        let model =
            Model::from_urdf_file(&urdf_path, Some(&file.base), Some(&file.tip)).map_err(|e| {
                err(
                    path,
                    format!(
                        "names the URDF {}, which does not load: {e}",
                        urdf_path.display()
                    ),
                )
            })?;
        Ok((Self::load(path, &model)?, model))
    }

    fn from_file(
        path: &Path,
        file: &IdentificationFile,
        urdf_model: &Model,
    ) -> Result<Identification, DynamicsError> {
        let n = urdf_model.nq();
        if file.joint_terms.len() != n || file.inertial_parameters.len() != 10 * n {
            return Err(err(path, format!("holds {} joint terms and {} parameters for an arm of {n} joints: the file is damaged", file.joint_terms.len(), file.inertial_parameters.len())));
        }
        if let Some(i) = file.joint_terms.iter().position(|t| !t.is_valid()) {
            return Err(err(
                path,
                format!(
                    "joint_terms[{i}] holds a non-finite value or a non-positive coulomb_width"
                ),
            ));
        }
        if let Some(i) = file.inertial_parameters.iter().position(|v| !v.is_finite()) {
            return Err(err(
                path,
                format!("inertial_parameters[{i}] is not a finite number"),
            ));
        }
        let model = crate::algorithms::regressor::with_inertial_parameters(
            urdf_model,
            &file.inertial_parameters,
        )?;
        Ok(Identification {
            model,
            joint_terms: file.joint_terms.clone(),
            summary: file.summary.clone(),
        })
    }
}

/// The checked envelope's payload.
fn read_envelope(path: &Path) -> Result<Value, DynamicsError> {
    let text = std::fs::read_to_string(path).map_err(|e| err(path, format!("cannot read: {e}")))?;
    let mut v: Value = serde_json::from_str(&text).map_err(|e| {
        err(
            path,
            format!("is not an identification file (not JSON: {e})"),
        )
    })?;
    if v.get("format").and_then(Value::as_str) != Some(IDENTIFICATION_FORMAT) {
        return Err(err(
            path,
            format!("is not an identification file (no \"format\": \"{IDENTIFICATION_FORMAT}\")"),
        ));
    }
    match v.get("format_version").and_then(Value::as_u64) {
        Some(IDENTIFICATION_FORMAT_VERSION) => {}
        other => return Err(err(path, format!("format_version {other:?}: this build reads version {IDENTIFICATION_FORMAT_VERSION}"))),
    }
    let stored = v
        .get("checksum")
        .and_then(Value::as_str)
        .unwrap_or("")
        .to_string();
    let payload = v
        .get_mut("payload")
        .map(Value::take)
        .ok_or_else(|| err(path, "has no payload"))?;
    let computed = checksum(&payload);
    if stored != computed {
        return Err(err(path, format!("checksum mismatch (stored {stored}, computed {computed}): the file was changed or damaged")));
    }
    Ok(payload)
}

fn read_file(path: &Path) -> Result<IdentificationFile, DynamicsError> {
    serde_json::from_value(read_envelope(path)?).map_err(|e| err(path, format!("payload: {e}")))
}
