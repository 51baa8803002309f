//! A deployment folder (`admittance deploy`, docs/your_robot.md): everything a robot's loop
//! needs and nothing simulated, each file checksummed in a manifest.
//!
//! ```text
//!   DIR/loop.toml          the loop's settings (crate::RobotConfig), paths relative to DIR
//!   DIR/arm.urdf           the arm (a copy)
//!   DIR/identification.json, DIR/observer.broad, DIR/contact_floor.json   when used
//!   DIR/manifest.json      {"format": "admittance-deployment", "version": 1,
//!                           "made_by": {...}, "files": {NAME: {"bytes": N, "fnv1a64": HEX}}}
//! ```
//!
//! [`Deployment::load`] reads the manifest and every file it lists once, checks sizes and
//! checksums (the project's FNV-1a 64), and refuses a file that the loop file names but the
//! manifest does not list: a missing, edited or foreign file is an error naming it. Nothing
//! is trained here, ever.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use admittance_learning::broad::fnv1a64;
use serde_json::{json, Value};

use crate::error::LoopError;
use crate::robot_config::RobotConfig;

/// The manifest's file name.
pub const MANIFEST_FILE: &str = "manifest.json";
/// The loop file's name.
pub const LOOP_FILE: &str = "loop.toml";
/// `format` of a manifest.
pub const DEPLOYMENT_FORMAT: &str = "admittance-deployment";
/// `version` of a manifest this library reads and writes.
pub const DEPLOYMENT_VERSION: u64 = 1;

/// A verified deployment folder: its loop file and the bytes of every file it lists.
#[derive(Clone, Debug)]
pub struct Deployment {
    /// The folder.
    pub dir: PathBuf,
    /// The parsed loop file.
    pub config: RobotConfig,
    /// What made the folder (the manifest's `made_by`).
    pub made_by: Value,
    files: BTreeMap<String, Vec<u8>>,
}

fn redeploy() -> &'static str {
    "write the folder again with `admittance deploy SCENARIO --out DIR`"
}

impl Deployment {
    /// Reads and verifies the folder `dir` (see the module documentation).
    pub fn load(dir: &Path) -> Result<Self, LoopError> {
        Self::load_with(dir, &[])
    }

    /// As [`Deployment::load`], with `KEY=VALUE` overrides of `loop.toml` applied in order
    /// (`signals.filter_cutoff_hz=10`, `controller.pd.kp=[100, 150, 50, 50, 10, 10, 2]`).
    pub fn load_with(dir: &Path, overrides: &[&str]) -> Result<Self, LoopError> {
        let manifest_path = dir.join(MANIFEST_FILE);
        if !dir.is_dir() {
            return Err(LoopError::file(
                dir,
                "is not a deployment folder (a folder with manifest.json and loop.toml)",
            )
            .hint(redeploy()));
        }
        let manifest: Value = read(&manifest_path, admittance_files::TEXT_LIMIT).and_then(|b| {
            serde_json::from_slice(&b).map_err(|e| LoopError::file(&manifest_path, e.to_string()))
        })?;
        if manifest.get("format").and_then(Value::as_str) != Some(DEPLOYMENT_FORMAT)
            || manifest.get("version").and_then(Value::as_u64) != Some(DEPLOYMENT_VERSION)
        {
            return Err(LoopError::file(
                &manifest_path,
                format!("is not a {DEPLOYMENT_FORMAT} manifest of version {DEPLOYMENT_VERSION}"),
            )
            .hint(redeploy()));
        }
        let listed = manifest
            .get("files")
            .and_then(Value::as_object)
            .ok_or_else(|| {
                LoopError::file(&manifest_path, "has no `files` table").hint(redeploy())
            })?;
        let mut files = BTreeMap::new();
        for (name, entry) in listed {
            let path = safe_join(dir, name)?;
            let bytes = read(&path, admittance_files::DATA_LIMIT)?;
            let want = entry.get("fnv1a64").and_then(Value::as_str).unwrap_or("");
            let found = format!("{:016x}", fnv1a64(&bytes));
            let size = entry.get("bytes").and_then(Value::as_u64);
            if want != found || size != Some(bytes.len() as u64) {
                return Err(LoopError::file(
                    &path,
                    format!(
                        "does not match the manifest (checksum {found}, {} bytes; manifest: {want}, {size:?} bytes): edited or replaced after deployment",
                        bytes.len()
                    ),
                )
                .hint(redeploy()));
            }
            files.insert(name.clone(), bytes);
        }
        let loop_text = files.get(LOOP_FILE).ok_or_else(|| {
            LoopError::file(&manifest_path, "does not list loop.toml").hint(redeploy())
        })?;
        let loop_path = dir.join(LOOP_FILE);
        let text = std::str::from_utf8(loop_text)
            .map_err(|e| LoopError::file(&loop_path, format!("not UTF-8: {e}")))?;
        let config = RobotConfig::from_toml_with(text, &loop_path, overrides)?;
        let deployment = Self {
            dir: dir.to_path_buf(),
            config,
            made_by: manifest.get("made_by").cloned().unwrap_or(Value::Null),
            files,
        };
        deployment.check_listed()?;
        Ok(deployment)
    }

    /// Every file the loop file names is one the manifest lists (and so was verified).
    fn check_listed(&self) -> Result<(), LoopError> {
        let c = &self.config;
        let named = [
            ("arm.urdf", Some(&c.arm.urdf)),
            (
                "observer.identification",
                c.observer.identification.as_ref(),
            ),
            ("observer.network", c.observer.network.as_ref()),
            ("contact.floor", c.contact.as_ref().map(|s| &s.floor)),
        ];
        for (key, path) in named {
            let Some(path) = path else { continue };
            if self.file_bytes(path).is_none() {
                return Err(LoopError::invalid(
                    key,
                    format!("`{}` is not a file the manifest lists", path.display()),
                )
                .hint(redeploy())
                .located(&self.dir.join(LOOP_FILE)));
            }
        }
        Ok(())
    }

    /// The verified bytes of a file the loop file names (relative to the folder).
    pub fn file_bytes(&self, path: &Path) -> Option<&[u8]> {
        let name = path.to_str()?.trim_start_matches("./");
        self.files.get(name).map(Vec::as_slice)
    }

    /// The names of the files the manifest lists.
    pub fn file_names(&self) -> impl Iterator<Item = &str> {
        self.files.keys().map(String::as_str)
    }
}

/// `dir/name` for a plain file name of the manifest (no folder, no `..`).
fn safe_join(dir: &Path, name: &str) -> Result<PathBuf, LoopError> {
    let plain = !name.is_empty()
        && !name.starts_with('.')
        && !name.contains(['/', '\\'])
        && name != MANIFEST_FILE;
    if plain {
        Ok(dir.join(name))
    } else {
        Err(LoopError::file(
            dir.join(MANIFEST_FILE),
            format!("lists `{name}`, which is not a plain file name of the folder"),
        ))
    }
}

fn read(path: &Path, limit: u64) -> Result<Vec<u8>, LoopError> {
    admittance_files::read_regular(path, limit)
        .map_err(|e| LoopError::file(path, format!("cannot be read: {e}")).hint(redeploy()))
}

/// Writes a deployment folder: `files` (name, bytes; `loop.toml` among them) and the
/// manifest listing them with `made_by`. `dir` must be missing, empty or a deployment
/// folder (whose files are replaced); each file is written atomically.
pub fn write_deployment(
    dir: &Path,
    files: &[(String, Vec<u8>)],
    made_by: Value,
) -> Result<(), LoopError> {
    if dir.exists() {
        let empty = std::fs::read_dir(dir)
            .map_err(|e| LoopError::file(dir, e.to_string()))?
            .next()
            .is_none();
        if !empty && !dir.join(MANIFEST_FILE).is_file() {
            return Err(LoopError::file(
                dir,
                "exists and is not a deployment folder: not overwritten (choose another --out)",
            ));
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| LoopError::file(dir, e.to_string()))?;
    let mut listed = serde_json::Map::new();
    for (name, bytes) in files {
        let path = safe_join(dir, name)?;
        admittance_files::write_atomic(&path, bytes)
            .map_err(|e| LoopError::file(&path, format!("cannot write: {e}")))?;
        listed.insert(
            name.clone(),
            json!({"bytes": bytes.len(), "fnv1a64": format!("{:016x}", fnv1a64(bytes))}),
        );
    }
    let manifest = json!({
        "format": DEPLOYMENT_FORMAT,
        "version": DEPLOYMENT_VERSION,
        "checksum": "fnv1a64 of each file's bytes (the project's checksum, admittance_learning::broad::fnv1a64)",
        "made_by": made_by,
        "files": listed,
    });
    let text = serde_json::to_string_pretty(&manifest).unwrap_or_default() + "\n";
    let path = dir.join(MANIFEST_FILE);
    admittance_files::write_atomic(&path, text.as_bytes())
        .map_err(|e| LoopError::file(&path, format!("cannot write: {e}")))
}
