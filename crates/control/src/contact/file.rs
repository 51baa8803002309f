//! Contact-floor files: JSON, versioned, checksummed (the pattern of identification files,
//! docs/outputs.md). Written atomically; a file that is not a contact floor is never
//! overwritten.

use std::path::Path;

use serde_json::Value;

use super::floor::ContactFloor;
use crate::error::ConfigError;

/// The `format` tag of contact-floor files.
pub const CONTACT_FLOOR_FORMAT: &str = "admittance-contact-floor";
/// The `format_version` this build writes (it reads 1 too: version 2 added the levels'
/// drop away from rest, absent in 1).
pub const CONTACT_FLOOR_FORMAT_VERSION: u64 = 2;

/// A problem of the file as a whole: no key of its own (the caller that named the file
/// puts its setting before it), the path at the head of the message.
fn err(path: &Path, m: impl std::fmt::Display) -> ConfigError {
    ConfigError::new("", format!("{}: {m}", path.display()))
}

/// FNV-1a 64 of the payload's canonical JSON text (keys sorted).
fn checksum(payload: &Value) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in payload.to_string().bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

impl ContactFloor {
    /// Writes the floor atomically (a temporary file renamed into place). An existing file at
    /// `path` is replaced only when it is a contact floor.
    pub fn save(&self, path: &Path) -> Result<(), ConfigError> {
        self.validate()
            .map_err(|e| err(path, format!("not saved: {e}")))?;
        if path.exists() && read_envelope(path).is_err() {
            return Err(err(
                path,
                "exists and is not a contact-floor file: not overwritten (choose another --out)",
            ));
        }
        let payload = serde_json::to_value(self).map_err(|e| err(path, e))?;
        let envelope = serde_json::json!({
            "format": CONTACT_FLOOR_FORMAT,
            "format_version": CONTACT_FLOOR_FORMAT_VERSION,
            "checksum": checksum(&payload),
            "payload": payload,
        });
        let text = serde_json::to_string_pretty(&envelope).map_err(|e| err(path, e))? + "\n";
        admittance_files::write_atomic(path, text.as_bytes())
            .map_err(|e| err(path, format!("cannot write: {e}")))
    }

    /// Reads and checks a contact-floor file.
    pub fn load(path: &Path) -> Result<ContactFloor, ConfigError> {
        let floor: ContactFloor = serde_json::from_value(read_envelope(path)?)
            .map_err(|e| err(path, format!("payload: {e}")))?;
        floor
            .validate()
            .map_err(|e| err(path, format!("payload.{e}")))?;
        Ok(floor)
    }
}

/// The checked envelope's payload.
fn read_envelope(path: &Path) -> Result<Value, ConfigError> {
    let text = admittance_files::read_regular_text(path, admittance_files::TEXT_LIMIT)
        .map_err(|e| err(path, format!("cannot read: {e}")))?;
    let mut v: Value = serde_json::from_str(&text)
        .map_err(|e| err(path, format!("is not a contact-floor file (not JSON: {e})")))?;
    if v.get("format").and_then(Value::as_str) != Some(CONTACT_FLOOR_FORMAT) {
        return Err(err(
            path,
            format!("is not a contact-floor file (no \"format\": \"{CONTACT_FLOOR_FORMAT}\")"),
        ));
    }
    match v.get("format_version").and_then(Value::as_u64) {
        Some(1 | CONTACT_FLOOR_FORMAT_VERSION) => {}
        other => {
            return Err(err(
                path,
                format!(
                "format_version {other:?}: this build reads versions 1 to {CONTACT_FLOOR_FORMAT_VERSION}"
            ),
            ))
        }
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
        return Err(err(
            path,
            format!("checksum mismatch (stored {stored}, computed {computed}): the file was changed or damaged"),
        ));
    }
    Ok(payload)
}
