//! Writing files atomically and exclusively: a temporary file with an unpredictable name in
//! the destination's folder, created with `O_CREAT | O_EXCL | O_NOFOLLOW` (a link planted at
//! that name makes the open fail instead of writing through it), fsynced and renamed over
//! the destination, which holds its old content or the new one, never a part.

use std::fs::File;
use std::hash::{BuildHasher, Hasher};
use std::io::{BufWriter, Error, ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Temporary files and folders being written, removed on Ctrl-C by [`remove_pending`].
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|p| p.into_inner())
}

fn forget(path: &Path) {
    pending().retain(|p| p != path);
}

/// 64 unpredictable bits: the standard library's randomly keyed hasher (seeded from the
/// operating system) over a counter, the process id and the clock.
fn unpredictable() -> u64 {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(COUNTER.fetch_add(1, Ordering::Relaxed));
    h.write_u32(std::process::id());
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    h.write_u128(nanos);
    h.finish()
}

fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// A hidden name beside `path` that nobody can guess: `.NAME.tmp-XXXXXXXXXXXXXXXX`.
fn temp_name(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "file".into());
    folder_of(path).join(format!(".{name}.tmp-{:016x}", unpredictable()))
}

/// Refuses a destination that exists and is not a regular file: a symbolic link (never
/// followed, never replaced), a folder, a FIFO, a device, a socket.
fn check_destination(path: &Path) -> std::io::Result<()> {
    if path.file_name().is_none() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "names a folder, not a file",
        ));
    }
    match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.is_file() => Ok(()),
        Ok(meta) => Err(Error::new(
            ErrorKind::AlreadyExists,
            format!(
                "is {}: not replaced (a file is written only to a new name or over a regular \
                 file; remove it or choose another name)",
                super::kind_of(&meta)
            ),
        )),
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e),
    }
}

/// Creates a new file exclusively at an unpredictable name beside `path`.
fn create_temp(path: &Path) -> std::io::Result<(PathBuf, File)> {
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC);
    }
    let mut last = None;
    for _ in 0..8 {
        let tmp = temp_name(path);
        match options.open(&tmp) {
            Ok(file) => {
                pending().push(tmp.clone());
                return Ok((tmp, file));
            }
            Err(e) if e.kind() == ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| Error::other("no temporary name could be created")))
}

/// Writes the file `path` with `write` (through a buffered writer) atomically: see the
/// module's documentation. `path` must be missing or a regular file; on any error the
/// temporary file is removed and `path` is left as it was.
pub fn write_atomic_with<T>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<T>,
) -> std::io::Result<T> {
    check_destination(path)?;
    let (tmp, file) = create_temp(path)?;
    let result = (|| {
        let mut w = BufWriter::new(file);
        let value = write(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        check_destination(path)?;
        std::fs::rename(&tmp, path)?;
        Ok(value)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    forget(&tmp);
    if result.is_ok() {
        // Make the rename durable; best effort (not every platform opens a folder).
        if let Ok(dir) = File::open(folder_of(path)) {
            let _ = dir.sync_all();
        }
    }
    result
}

/// Writes `bytes` to `path` atomically (see [`write_atomic_with`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Creates a new empty folder with an unpredictable hidden name beside `path`
/// (`.NAME.tmp-XXXXXXXXXXXXXXXX`; `mkdir` fails on anything already there, a link
/// included), to be filled and renamed into place. It is removed by [`remove_pending`]
/// until [`release`] says it has been renamed or removed.
pub fn temp_dir_beside(path: &Path) -> std::io::Result<PathBuf> {
    let mut last = None;
    for _ in 0..8 {
        let tmp = temp_name(path);
        match std::fs::create_dir(&tmp) {
            Ok(()) => {
                pending().push(tmp.clone());
                return Ok(tmp);
            }
            Err(e) if e.kind() == ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| Error::other("no temporary name could be created")))
}

/// Says that a folder from [`temp_dir_beside`] was renamed into place or removed.
pub fn release(tmp: &Path) {
    forget(tmp);
}

/// Removes every temporary file and folder still being written by this process (the
/// command line's Ctrl-C handler calls it before exiting).
pub fn remove_pending() {
    for path in pending().drain(..) {
        match std::fs::symlink_metadata(&path) {
            Ok(meta) if meta.is_dir() => {
                let _ = std::fs::remove_dir_all(&path);
            }
            Ok(_) => {
                let _ = std::fs::remove_file(&path);
            }
            Err(_) => {}
        }
    }
}
