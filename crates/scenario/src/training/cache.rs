//! The cache of trained observer networks (`[observer.training] cache_dir`): one model
//! file and one index entry per key (the data's identities, the target and every fit
//! setting). An entry is used only when it verifies: its key, the model file's content hash,
//! a checksum over the recorded fit results, and the arm and data settings the model file
//! itself records. Anything else is a miss and the network is trained again.

use std::path::{Path, PathBuf};

use admittance_learning::broad::{fnv1a64, ArmCheck, ArmIdentity, BroadModel, DataSettings};
use serde_json::{json, Value};

use super::TrainedNetwork;
use crate::spec::TrainingSpec;

/// Version of the cache entries (bump when what a key stands for changes).
pub(super) const CACHE_FORMAT_VERSION: u32 = 2;

/// The cache folder: `ADMITTANCE_CACHE_DIR`, or `cache_dir` relative to the scenario file.
pub(super) fn cache_dir(scenario_file: &Path, spec: &TrainingSpec) -> PathBuf {
    match std::env::var_os("ADMITTANCE_CACHE_DIR") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => super::data::resolve(scenario_file, &spec.cache_dir),
    }
}

/// The fit results an entry records, bound to its key and model by a checksum: an edited
/// index entry does not verify.
fn checksum(key_text: &str, model_hash: u64, t: &TrainedNetwork) -> u64 {
    let mut text = format!(
        "{key_text}|{model_hash:016x}|{}|{}|{}|{}",
        t.train_seconds.to_bits(),
        t.samples,
        t.validation_samples,
        t.lambda.to_bits()
    );
    for v in &t.validation_nrmse {
        text.push_str(&format!("|{}", v.to_bits()));
    }
    fnv1a64(text.as_bytes())
}

/// The entry at `model_path` / `meta_path` when it verifies against `key_text`, the arm
/// and the data settings.
pub(super) fn read_cache(
    model_path: &Path,
    meta_path: &Path,
    key_text: &str,
    arm: &ArmIdentity,
    settings: &DataSettings,
) -> Option<TrainedNetwork> {
    let meta: Value = serde_json::from_slice(
        &admittance_files::read_regular(meta_path, admittance_files::TEXT_LIMIT).ok()?,
    )
    .ok()?;
    if meta.get("format")?.as_str()? != "admittance-observer-cache"
        || meta.get("format_version")?.as_u64()? != CACHE_FORMAT_VERSION as u64
        || meta.get("key")?.as_str()? != key_text
    {
        return None;
    }
    let bytes = admittance_files::read_regular(model_path, admittance_files::DATA_LIMIT).ok()?;
    let model_hash = fnv1a64(&bytes);
    if meta.get("model_hash")?.as_str()? != format!("{model_hash:016x}") {
        return None; // another model file copied over this one
    }
    // A corrupted or truncated model file fails its own checksum.
    let model = BroadModel::from_bytes(&bytes, model_path).ok()?;
    if !matches!(model.check_arm(arm), Ok(ArmCheck::Matches))
        || !matches!(model.check_data_settings(settings), Ok(ArmCheck::Matches))
    {
        return None;
    }
    let hit = TrainedNetwork {
        model,
        train_seconds: meta.get("train_seconds")?.as_f64()?,
        validation_nrmse: meta
            .get("validation_nrmse")?
            .as_array()?
            .iter()
            .map(Value::as_f64)
            .collect::<Option<Vec<f64>>>()?,
        samples: meta.get("samples")?.as_u64()? as usize,
        validation_samples: meta.get("validation_samples")?.as_u64()? as usize,
        lambda: meta.get("lambda")?.as_f64()?,
        cached: true,
        validation_series: None,
    };
    let recorded = meta.get("checksum")?.as_str()?;
    (recorded == format!("{:016x}", checksum(key_text, model_hash, &hit))).then_some(hit)
}

/// Writes an entry: the model file, then its index entry (both atomically).
pub(super) fn write_cache(
    dir: &Path,
    model_path: &Path,
    meta_path: &Path,
    key_text: &str,
    t: &TrainedNetwork,
) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    let bytes = t.model.to_bytes();
    admittance_runfolder::write_atomic(model_path, &bytes).map_err(|e| e.to_string())?;
    let model_hash = fnv1a64(&bytes);
    let meta = json!({
        "format": "admittance-observer-cache",
        "format_version": CACHE_FORMAT_VERSION,
        "key": key_text,
        "model_hash": format!("{model_hash:016x}"),
        "train_seconds": t.train_seconds,
        "validation_nrmse": t.validation_nrmse,
        "samples": t.samples,
        "validation_samples": t.validation_samples,
        "lambda": t.lambda,
        "checksum": format!("{:016x}", checksum(key_text, model_hash, t)),
    });
    admittance_runfolder::write_atomic(
        meta_path,
        serde_json::to_string_pretty(&meta)
            .unwrap_or_default()
            .as_bytes(),
    )
    .map_err(|e| e.to_string())
}

/// The stem of an entry's files.
pub(super) fn entry_paths(dir: &Path, stem: &str) -> (PathBuf, PathBuf) {
    (
        dir.join(format!("{stem}.broad")),
        dir.join(format!("{stem}.json")),
    )
}
