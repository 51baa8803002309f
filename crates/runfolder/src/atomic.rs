use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

static COMMIT: Mutex<()> = Mutex::new(());

/// Held while a finished output replaces an older one (a run folder or `figures/` renamed
/// aside, the new one renamed into place), so that whoever cleans up after an interrupt
/// (the command line's Ctrl-C handler, which takes it too) never removes a temporary
/// folder between those two renames, when it is the only complete copy.
pub fn commit_guard() -> MutexGuard<'static, ()> {
    COMMIT
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A hidden temporary sibling of `path` for this process: `.NAME.tmp-PID`.
pub fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// Writes `bytes` to `path` through a temporary sibling, flushed to disk, and a rename, so
/// that `path` holds either its old content or the new one, never a part.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temp_sibling(path);
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
