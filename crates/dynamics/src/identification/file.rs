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
/// The newest `format_version` this build writes and reads. Version 3 added the joint
/// terms' `spring_range` (springs linear beyond it), written only by files that hold one
/// (others stay version 2, which older builds read: without the range they would evaluate
/// such springs differently, so they refuse version 3). Version 2 added `gravity`, `lock`
/// and `drop` (a version 1 file was made with gravity `(0, 0, -9.81)` in the base's axes
/// and no lock or drop recorded).
pub const IDENTIFICATION_FORMAT_VERSION: u64 = 3;
/// The version of a file whose joint terms hold no spring range.
const VERSION_WITHOUT_SPRING_RANGES: u64 = 2;
/// Gravity of a file that does not state it (version 1).
const VERSION_1_GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

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
    /// Lock positions the model was loaded with (rad or m), as given (`--lock`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub lock: BTreeMap<String, f64>,
    /// Joints whose branches were left out of the model (`--drop`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub drop: Vec<String>,
    /// Gravity in the base's axes the model was fitted with (m/s^2); absent in version 1
    /// files, which were fitted with `(0, 0, -9.81)`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<[f64; 3]>,
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
            lock: urdf_model.lock_options().iter().cloned().collect(),
            drop: urdf_model
                .dropped_branches()
                .iter()
                .map(|b| b.joint.clone())
                .collect(),
            gravity: Some(urdf_model.gravity.into()),
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
            "format_version": if self.joint_terms.iter().any(|t| t.spring_range.is_some()) {
                IDENTIFICATION_FORMAT_VERSION
            } else {
                VERSION_WITHOUT_SPRING_RANGES
            },
            "checksum": checksum(&payload),
            "payload": payload,
        });
        let text = serde_json::to_string_pretty(&envelope).map_err(|e| err(path, e))? + "\n";
        admittance_files::write_atomic(path, text.as_bytes())
            .map_err(|e| err(path, format!("cannot write: {e}")))
    }

    /// Reads an identification file and applies it to `urdf_model`, which must be the
    /// model it was identified from (same fingerprint).
    pub fn load(path: &Path, urdf_model: &Model) -> Result<Identification, DynamicsError> {
        let file = read_file(path)?;
        let found = format!("{:016x}", urdf_model.fingerprint());
        if found != file.urdf_fingerprint {
            return Err(err(path, format!(
                "was identified for another arm model ({} from {} to {}, joints [{}], fingerprint {}; this model '{}' has {found}, joints [{}]): load it with the URDF it was made from and the same --base, --tip, --lock and --drop",
                file.urdf, file.base, file.tip, file.joints.join(", "), file.urdf_fingerprint, urdf_model.source,
                urdf_model.joint_names().collect::<Vec<_>>().join(", ")
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
        let options = crate::UrdfOptions {
            base: Some(file.base.clone()),
            tip: Some(file.tip.clone()),
            lock: file.lock.iter().map(|(j, v)| (j.clone(), *v)).collect(),
            drop: file.drop.clone(),
            ..crate::UrdfOptions::default()
        };
        let model = Model::from_urdf_file_with(&urdf_path, &options).map_err(|e| {
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
        let names: Vec<&str> = urdf_model.joint_names().collect();
        if file.joints != names {
            return Err(err(path, format!(
                "names the joints [{}], the arm's chain has [{}]: the file was edited or is for another arm",
                file.joints.join(", "),
                names.join(", ")
            )));
        }
        check_gravity(file, urdf_model).map_err(|m| err(path, m))?;
        check_physical(file).map_err(|m| err(path, m))?;
        check_summary(&file.summary, n).map_err(|m| err(path, m))?;
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

/// The model's gravity is the one the file was fitted with: the fingerprint covers the arm,
/// not its mount, and a base turned another way (a lock on a joint above it, or a file of
/// version 1 made when gravity was always the base's own -z) fits other parameters.
fn check_gravity(file: &IdentificationFile, model: &Model) -> Result<(), String> {
    let stated = file.gravity.unwrap_or(VERSION_1_GRAVITY);
    let g = model.gravity;
    let close = stated
        .iter()
        .zip(g.iter())
        .all(|(a, b)| (a - b).abs() <= 1e-9 * (1.0 + a.abs()));
    if close {
        return Ok(());
    }
    let locks: Vec<String> = file.lock.iter().map(|(j, v)| format!("{j}={v}")).collect();
    Err(format!(
        "was fitted with gravity ({:.4}, {:.4}, {:.4}) m/s^2 in {}'s axes, this model has ({:.4}, {:.4}, {:.4}): load the arm with the base{} it was identified with, or identify it again{}",
        stated[0], stated[1], stated[2], file.base, g.x, g.y, g.z,
        if locks.is_empty() { String::new() } else { format!(" and locks ({})", locks.join(", ")) },
        if file.gravity.is_none() { " (the file predates gravity following a turned base's mount)" } else { "" }
    ))
}

/// The largest magnitude a stored coefficient may have (kg, kg m, kg m^2, N m and their
/// rates): no arm's link or joint comes near it, a damaged or edited file may.
pub const MAX_COEFFICIENT: f64 = 1e6;

/// What the physics requires of a file's contents (docs/outputs.md, "Identification
/// files"): every number finite and within [`MAX_COEFFICIENT`], every body of positive mass
/// and physically consistent inertia, every joint's terms physical
/// ([`JointTerms::physical_problem`]). The message names the body or joint and the value.
fn check_physical(file: &IdentificationFile) -> Result<(), String> {
    use crate::algorithms::regressor::PARAMETERS_PER_BODY;
    use crate::identification::is_physically_consistent;
    use crate::spatial::Inertia;
    let joint = |i: usize| file.joints.get(i).map_or("?", String::as_str);
    for (k, v) in file.inertial_parameters.iter().enumerate() {
        if !(v.abs() <= MAX_COEFFICIENT) {
            return Err(format!(
                "inertial_parameters[{k}] (body {}, moved by joint '{}') is {v:e}: not a finite number within +-{MAX_COEFFICIENT:e}",
                k / PARAMETERS_PER_BODY,
                joint(k / PARAMETERS_PER_BODY)
            ));
        }
    }
    for (i, p) in file
        .inertial_parameters
        .chunks_exact(PARAMETERS_PER_BODY)
        .enumerate()
    {
        let p: &[f64; PARAMETERS_PER_BODY] = p.try_into().expect("chunks of 10");
        if !(p[0] > 0.0) {
            return Err(format!(
                "body {i} (moved by joint '{}') has mass {} kg: a body's mass must be positive",
                joint(i),
                p[0]
            ));
        }
        if !is_physically_consistent(&Inertia::from_parameters(p)) {
            return Err(format!(
                "body {i} (moved by joint '{}') is not physically possible (mass {} kg, first moment [{}, {}, {}] kg m, inertia [{}, {}, {}, {}, {}, {}] kg m^2 about the joint frame): its pseudo-inertia is not positive definite",
                joint(i), p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9]
            ));
        }
    }
    for (i, t) in file.joint_terms.iter().enumerate() {
        if let Some(problem) = t.physical_problem() {
            return Err(format!(
                "joint_terms[{i}] (joint '{}'): {problem}",
                joint(i)
            ));
        }
        let mut values = vec![t.armature, t.viscous, t.coulomb_width, t.offset];
        values.extend(t.coulomb.iter().chain(&t.spring));
        if let Some(v) = values.iter().find(|v| v.abs() > MAX_COEFFICIENT) {
            return Err(format!(
                "joint_terms[{i}] (joint '{}') holds {v:e}: beyond +-{MAX_COEFFICIENT:e}",
                joint(i)
            ));
        }
    }
    Ok(())
}

/// The largest torque delay a summary may state (s): `identify` tries at most 30 ms.
const MAX_DELAY_S: f64 = 1.0;

/// What consumers take from the summary (the input conditioning, the torque delay, the
/// acceleration gain) and the errors it reports must be values `identify` can write: a
/// cut-off of 0 (none) or a finite positive frequency, delays finite and within
/// [`MAX_DELAY_S`], a gain from 0 to 1, errors and times finite and not negative.
fn check_summary(s: &IdentificationSummary, n: usize) -> Result<(), String> {
    let hz = s.input_filter_hz;
    if !(0.0..=MAX_COEFFICIENT).contains(&hz) {
        return Err(format!(
            "summary.input_filter_hz is {}: must be 0 (no conditioning) or a finite positive cut-off (Hz)",
            short(hz)
        ));
    }
    if !(0.0..=1.0).contains(&s.acceleration_gain) {
        return Err(format!(
            "summary.acceleration_gain is {}: must be 0 to 1",
            s.acceleration_gain
        ));
    }
    if !(s.acceleration_power.is_empty() || s.acceleration_power.len() == n) {
        return Err(format!(
            "summary.acceleration_power has {} values for {n} joints",
            s.acceleration_power.len()
        ));
    }
    if let Some((j, p)) = s
        .acceleration_power
        .iter()
        .enumerate()
        .find(|(_, p)| !(p.is_finite() && **p >= 0.0))
    {
        return Err(format!(
            "summary.acceleration_power[{j}] is {}: must be a finite mean square >= 0",
            short(*p)
        ));
    }
    if !(s.prior_scale > 0.0 && s.prior_scale.is_finite()) {
        return Err(format!(
            "summary.prior_scale is {}: must be a finite positive factor",
            s.prior_scale
        ));
    }
    if !(s.delay_s.is_empty() || s.delay_s.len() == n) {
        return Err(format!(
            "summary.delay_s has {} values for {n} joints",
            s.delay_s.len()
        ));
    }
    if let Some(d) = s.delay_s.iter().find(|d| !(d.abs() <= MAX_DELAY_S)) {
        return Err(format!(
            "summary.delay_s holds {} s: a torque delay is finite and within +-{MAX_DELAY_S} s",
            short(*d)
        ));
    }
    if !(s.training_range.is_empty() || s.training_range.len() == n) {
        return Err(format!(
            "summary.training_range has {} pairs for {n} joints",
            s.training_range.len()
        ));
    }
    if let Some([low, high]) = s
        .training_range
        .iter()
        .find(|[low, high]| !(low.is_finite() && high.is_finite() && low <= high))
    {
        return Err(format!(
            "summary.training_range holds [{}, {}]: each joint's lowest and highest position, finite, lowest first",
            short(*low),
            short(*high)
        ));
    }
    if !(s.training_speed.is_empty() || s.training_speed.len() == n) {
        return Err(format!(
            "summary.training_speed has {} values for {n} joints",
            s.training_speed.len()
        ));
    }
    if let Some(v) = s
        .training_speed
        .iter()
        .find(|v| !(**v >= 0.0 && v.is_finite()))
    {
        return Err(format!(
            "summary.training_speed holds {}: each joint's highest training speed, finite and not negative",
            short(*v)
        ));
    }
    let errors = [
        ("expected_false_torque_rms", &s.expected_false_torque_rms),
        ("prior_false_torque_rms", &s.prior_false_torque_rms),
    ];
    for (key, values) in errors {
        if let Some(v) = values.iter().find(|v| !(**v >= 0.0 && v.is_finite())) {
            return Err(format!(
                "summary.{key} holds {}: an rms error is finite and not negative",
                short(*v)
            ));
        }
    }
    for (key, v) in [("ridge", s.ridge), ("step_response_s", s.step_response_s)] {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(format!(
                "summary.{key} is {v}: must be finite and not negative"
            ));
        }
    }
    Ok(())
}

/// A number as a message shows it: plain, or with an exponent when far from 1.
fn short(v: f64) -> String {
    if v != 0.0 && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// The checked envelope's payload.
fn read_envelope(path: &Path) -> Result<Value, DynamicsError> {
    let text = admittance_files::read_regular_text(path, admittance_files::TEXT_LIMIT)
        .map_err(|e| err(path, format!("cannot read: {e}")))?;
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
        Some(1..=IDENTIFICATION_FORMAT_VERSION) => {}
        other => return Err(err(path, format!("format_version {other:?}: this build reads versions 1 to {IDENTIFICATION_FORMAT_VERSION}"))),
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
