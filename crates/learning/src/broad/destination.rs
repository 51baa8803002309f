//! Where a model file may be written, and writing it atomically: a model file replaces
//! only a model file (never a user's other files, a folder or a device), and a crash
//! leaves either the old file or the new one, never a torn one.

use super::error::BroadError;
use super::io::MAGIC;
use super::model::BroadModel;
use std::io::Read;
use std::path::{Path, PathBuf};

fn refuse(path: &Path, reason: impl Into<String>) -> BroadError {
    BroadError::Destination {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// What kind of thing is at a path, for messages.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a folder";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_block_device() || t.is_char_device() {
            return "a device";
        }
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "not a regular file"
}

/// Whether the regular file at `path` starts with the model files' magic bytes.
fn is_model_file(path: &Path) -> std::io::Result<bool> {
    let mut head = [0u8; 8];
    let mut f = std::fs::File::open(path)?;
    let mut got = 0;
    while got < head.len() {
        match f.read(&mut head[got..])? {
            0 => break,
            k => got += k,
        }
    }
    Ok(got == head.len() && &head == MAGIC)
}

/// Checks that a model file may be written at `path`, before any work is done, and
/// returns the file to write:
///
/// * a new name in an existing folder: that path;
/// * an existing model file (it starts with the model files' magic bytes, any version,
///   even corrupted after them): that path, replaced;
/// * a symbolic link to an existing model file: the file it points to (the link stays).
///
/// Everything else is refused with [`BroadError::Destination`] saying what is there: a
/// folder, a device, a FIFO, a socket (or a link to one), a dangling link, a missing
/// folder, and an existing file that is not a model file (a model file never replaces
/// what this tool did not write: remove it or choose another name).
pub fn check_model_destination(path: &Path) -> Result<PathBuf, BroadError> {
    let text = path.as_os_str().to_string_lossy();
    if text.is_empty() {
        return Err(refuse(path, "an empty path"));
    }
    if text.ends_with('/') || path.file_name().is_none() {
        return Err(refuse(path, "names a folder, not a file"));
    }
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            return match std::fs::metadata(dir) {
                Ok(m) if m.is_dir() => Ok(path.to_path_buf()),
                Ok(m) => Err(refuse(
                    path,
                    format!("{} is {}, not a folder", dir.display(), kind_of(&m)),
                )),
                Err(e) => Err(refuse(path, format!("its folder {}: {e}", dir.display()))),
            };
        }
        Err(e) => return Err(refuse(path, e.to_string())),
        Ok(_) => {}
    }
    // Follow links to what is really there.
    let target = std::fs::canonicalize(path).map_err(|e| {
        refuse(
            path,
            format!(
                "a symbolic link that cannot be followed ({e}); remove it or choose another name"
            ),
        )
    })?;
    let meta = std::fs::metadata(&target).map_err(|e| refuse(path, e.to_string()))?;
    let via = if target.as_path() != path
        && std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink())
    {
        format!(" (a link to {})", target.display())
    } else {
        String::new()
    };
    if !meta.is_file() {
        return Err(refuse(
            path,
            format!(
                "is {}{via}; a model file is written only to a new name or over a model file",
                kind_of(&meta)
            ),
        ));
    }
    match is_model_file(&target) {
        Ok(true) => Ok(target),
        Ok(false) => Err(refuse(
            path,
            format!(
                "exists{via} and is not a model file; refusing to replace it (remove it or choose another name)"
            ),
        )),
        Err(e) => Err(refuse(
            path,
            format!("exists{via} and cannot be read to tell whether it is a model file: {e}"),
        )),
    }
}

/// Writes `bytes` to `path` atomically and exclusively (`admittance_files::write_atomic`: a
/// temporary file with an unpredictable name in the same folder, created with `O_EXCL` and
/// `O_NOFOLLOW`, fsync'ed, renamed over `path`).
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), BroadError> {
    admittance_files::write_atomic(path, bytes).map_err(|e| BroadError::Io {
        path: path.to_path_buf(),
        source: e,
    })
}

impl BroadModel {
    /// Writes the model to `path` atomically (a temporary file in the same folder,
    /// fsync'ed, renamed over `path`), so a crash leaves either the old file or the new
    /// one. `path` must pass [`check_model_destination`]: a new name, or an existing model
    /// file (through a symbolic link: the file it points to); anything else is refused
    /// and left untouched.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), BroadError> {
        let target = check_model_destination(path.as_ref())?;
        write_atomic(&target, &self.to_bytes())
    }
}
