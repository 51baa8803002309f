//! `summary.json`: its format marker and version, and the test that tells a run folder
//! (which `run --out` may replace) from anything else (which it must not touch).
//!
//! ```json
//! {"format": "admittance-run", "format_version": 1, "scenario": NAME, "joints": [...],
//!  "variants": {VARIANT: {METRIC: value, ...}, ...}}
//! ```

use std::path::Path;

use serde_json::Value;

/// The `format` string of `summary.json`.
pub const FORMAT: &str = "admittance-run";
/// The `format_version` this build writes.
pub const FORMAT_VERSION: u64 = 1;
/// The `format_version`s this build reads.
pub const SUPPORTED_VERSIONS: &[u64] = &[1];

/// Key of the format marker.
pub const KEY_FORMAT: &str = "format";
/// Key of the format version.
pub const KEY_FORMAT_VERSION: &str = "format_version";
/// Key of the scenario name.
pub const KEY_SCENARIO: &str = "scenario";
/// Key of the scenario file the run was made from, as an absolute path: what the relative
/// paths of the folder's `scenario.toml` are relative to (`admittance deploy RUN_DIR`).
pub const KEY_SCENARIO_FILE: &str = "scenario_file";
/// Key of the joint names (chain order).
pub const KEY_JOINTS: &str = "joints";
/// Key of the per-variant metrics.
pub const KEY_VARIANTS: &str = "variants";
/// Key of the variant names in the scenario's order (the `variants` object is sorted by
/// name).
pub const KEY_VARIANT_ORDER: &str = "variant_order";
/// Key of the load warnings of the arm's description (a list of strings).
pub const KEY_WARNINGS: &str = "warnings";
/// Key of the health verdicts of every variant (`crate::health::summary_value`).
pub const KEY_HEALTH: &str = "health";
/// Key of the plant that produced the run, when it is not this project's simulator: the
/// Python co-simulation writes `"plant": "mujoco"` (same metric names as experiment B).
pub const KEY_PLANT: &str = "plant";
/// The value of [`KEY_PLANT`] of a MuJoCo co-simulation.
pub const PLANT_MUJOCO: &str = "mujoco";

/// What is at a path that `run --out` was given.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OutTarget {
    /// Nothing: a new folder will be made.
    Absent,
    /// A folder this tool wrote (its `summary.json` carries the marker): may be replaced.
    RunFolder,
    /// A folder that is empty: may be used.
    EmptyFolder,
    /// Anything else (a user's folder, a file, a device, a link): must not be touched.
    Other(String),
}

/// Whether `summary` (parsed `summary.json`) carries this tool's marker, with any version.
pub fn has_marker(summary: &Value) -> bool {
    summary.get(KEY_FORMAT).and_then(Value::as_str) == Some(FORMAT)
        && summary
            .get(KEY_FORMAT_VERSION)
            .and_then(Value::as_u64)
            .is_some()
}

/// Classifies what is at `path` for `run --out` (links are not followed: a link is
/// [`OutTarget::Other`]).
pub fn classify_out(path: &Path) -> OutTarget {
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return OutTarget::Absent,
        Err(e) => return OutTarget::Other(format!("cannot be inspected ({e})")),
    };
    if meta.file_type().is_symlink() {
        return OutTarget::Other("is a symbolic link".into());
    }
    if !meta.is_dir() {
        return OutTarget::Other("is a file, not a folder".into());
    }
    let mut entries = match std::fs::read_dir(path) {
        Ok(e) => e,
        Err(e) => return OutTarget::Other(format!("cannot be listed ({e})")),
    };
    if entries.next().is_none() {
        return OutTarget::EmptyFolder;
    }
    if is_run_folder(path) {
        OutTarget::RunFolder
    } else {
        OutTarget::Other("is a folder that `admittance run` did not write (no summary.json with \"format\": \"admittance-run\")".into())
    }
}

/// Whether `dir` is a run folder this tool wrote: a folder whose `summary.json` is a
/// regular file carrying the marker.
pub fn is_run_folder(dir: &Path) -> bool {
    let path = dir.join(crate::files::SUMMARY);
    let Ok(meta) = std::fs::symlink_metadata(&path) else {
        return false;
    };
    // A summary is at most a few MB; anything far larger is not ours.
    if !meta.is_file() || meta.len() > 64 << 20 {
        return false;
    }
    admittance_files::read_regular(&path, admittance_files::TEXT_LIMIT)
        .ok()
        .and_then(|b| serde_json::from_slice::<Value>(&b).ok())
        .is_some_and(|v| has_marker(&v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_marked_folders_are_run_folders() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        assert_eq!(classify_out(&out), OutTarget::Absent);
        std::fs::create_dir(&out).unwrap();
        assert_eq!(classify_out(&out), OutTarget::EmptyFolder);
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        assert!(matches!(classify_out(&out), OutTarget::Other(_)));
        std::fs::write(
            out.join("summary.json"),
            r#"{"format": "something-else", "format_version": 1}"#,
        )
        .unwrap();
        assert!(matches!(classify_out(&out), OutTarget::Other(_)));
        std::fs::write(
            out.join("summary.json"),
            r#"{"format": "admittance-run", "format_version": 1}"#,
        )
        .unwrap();
        assert_eq!(classify_out(&out), OutTarget::RunFolder);
        let file = dir.path().join("file");
        std::fs::write(&file, "x").unwrap();
        assert!(matches!(classify_out(&file), OutTarget::Other(_)));
    }
}
