use std::path::Path;
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

/// Writes `bytes` to `path` atomically and exclusively (`admittance_files::write_atomic`: a
/// temporary file with an unpredictable name beside it, created with `O_EXCL` and
/// `O_NOFOLLOW`, flushed to disk and renamed), so that `path` holds either its old content or
/// the new one, never a part, and a link planted beside it or at it is never written through.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    admittance_files::write_atomic(path, bytes)
}
