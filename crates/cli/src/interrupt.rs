//! Ctrl-C: one line on stderr and exit code 130 (128 + SIGINT, what shells report for a
//! command interrupted from the keyboard), instead of dying silently, and no half-written
//! output left behind.
//!
//! The signal handler only does async-signal-safe things: it writes one byte to a pipe.
//! A watcher thread reading that pipe does the rest in ordinary code: it waits for any
//! replacement in progress to finish (`admittance_runfolder::commit_guard`, held while a
//! finished output is renamed into place), removes the temporary outputs the command
//! registered ([`remove_on_interrupt`]: the run's `.DIR.partial-PID` folder, the report's
//! temporary files), writes the prepared line ([`set_message`]) and ends the process with
//! `_exit(2)`. Every output is written to a temporary sibling and renamed into place when
//! complete (docs/outputs.md), so an interrupted command leaves the user's files as they
//! were. A second Ctrl-C, or a handler installed without its pipe, ends the process at once
//! with the line.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

/// The exit code of an interrupted command.
pub const EXIT_CODE: u8 = 130;

/// The line printed when no command set its own.
const DEFAULT_LINE: &[u8] = b"admittance: interrupted (Ctrl-C)\n";

static MESSAGE: OnceLock<Box<[u8]>> = OnceLock::new();

/// Temporary outputs to remove on Ctrl-C: a folder is removed only when it holds the
/// partial-run marker file named with it, a file always.
static CLEANUP: Mutex<Vec<(PathBuf, Option<&'static str>)>> = Mutex::new(Vec::new());

/// The bytes the handler writes: a fresh line first when stderr is a terminal (a progress
/// bar or the echoed `^C` may hold the current one), the message, a newline.
fn framed(message: &str) -> Box<[u8]> {
    let lead = if std::io::stderr().is_terminal() {
        "\n"
    } else {
        ""
    };
    format!("{lead}{message}\n").into_bytes().into_boxed_slice()
}

/// Sets the line printed on Ctrl-C (once per process; later calls are ignored). Call it
/// before the work that it describes starts.
pub fn set_message(message: &str) {
    let _ = MESSAGE.set(framed(message));
}

/// Registers a temporary output that Ctrl-C removes: with `marker`, a folder only when it
/// holds that file (without it the folder is complete, or not ours, and is left); without,
/// a temporary file or folder named for this process.
pub fn remove_on_interrupt(path: PathBuf, marker: Option<&'static str>) {
    let mut list = CLEANUP.lock().unwrap_or_else(|p| p.into_inner());
    list.push((path, marker));
}

/// The partial folder `admittance run --out out_dir` writes into (`.LEAF.partial-PID`
/// beside it, marked by `.admittance-partial`; docs/outputs.md).
pub fn run_partial(out_dir: &Path) -> PathBuf {
    let parent = out_dir
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    parent.join(format!(".{}.partial-{}", leaf(out_dir), std::process::id()))
}

/// The marker file inside a run's partial folder.
pub const PARTIAL_MARKER: &str = ".admittance-partial";

fn leaf(out_dir: &Path) -> String {
    out_dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| out_dir.display().to_string())
}

/// The line `admittance run --out out_dir` prints on Ctrl-C.
pub fn run_message(out_dir: &std::path::Path) -> String {
    format!(
        "admittance: interrupted (Ctrl-C); {} was left as it was (the run folder appears only \
         when complete) and the unfinished .{}.partial-{} was removed",
        out_dir.display(),
        leaf(out_dir),
        std::process::id()
    )
}

/// The line `admittance report DIR` prints on Ctrl-C.
pub fn report_message(dir: &Path) -> String {
    format!(
        "admittance: interrupted (Ctrl-C); the report files of {} were left as they were \
         (each is replaced only when complete)",
        dir.display()
    )
}

/// Removes what was registered, once every replacement in progress has finished.
fn clean_up() {
    let commit = admittance_runfolder::commit_guard();
    remove_registered();
    admittance_files::remove_pending();
    // Held until the process ends: nothing may be renamed into place any more.
    std::mem::forget(commit);
}

/// Removes a folder that the interrupted work may still be writing into: again while a
/// file created meanwhile keeps it from going (the work's writes into a removed folder fail).
fn remove_dir(path: &Path) {
    for _ in 0..50 {
        if std::fs::remove_dir_all(path).is_ok() || !path.exists() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// Removes every registered path: a folder with a marker only when it holds the marker, a
/// path without one (a temporary file or folder named for this process) always.
fn remove_registered() {
    let list = CLEANUP.lock().unwrap_or_else(|p| p.into_inner());
    for (path, marker) in list.iter() {
        let Ok(meta) = std::fs::symlink_metadata(path) else {
            continue;
        };
        match marker {
            Some(m) if meta.is_dir() && path.join(m).is_file() => remove_dir(path),
            None if meta.is_dir() => remove_dir(path),
            None => {
                let _ = std::fs::remove_file(path);
            }
            Some(_) => {}
        }
    }
}

fn message() -> &'static [u8] {
    MESSAGE.get().map(|m| &m[..]).unwrap_or(DEFAULT_LINE)
}

#[cfg(unix)]
mod unix {
    use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

    /// The pipe's write end (-1 until the watcher runs).
    pub static WAKE: AtomicI32 = AtomicI32::new(-1);
    /// Set by the first Ctrl-C.
    pub static SEEN: AtomicBool = AtomicBool::new(false);

    fn say_and_exit() -> ! {
        let m = super::message();
        // SAFETY: write(2) and _exit(2) are async-signal-safe; `m` is a static buffer that
        // is never freed or changed once set.
        unsafe {
            libc::write(2, m.as_ptr().cast(), m.len());
            libc::_exit(super::EXIT_CODE as libc::c_int);
        }
    }

    pub extern "C" fn on_sigint(_signal: libc::c_int) {
        let fd = WAKE.load(Ordering::SeqCst);
        if fd < 0 || SEEN.swap(true, Ordering::SeqCst) {
            say_and_exit();
        }
        let byte = 1u8;
        // SAFETY: write(2) is async-signal-safe.
        let written = unsafe { libc::write(fd, (&byte as *const u8).cast(), 1) };
        if written != 1 {
            say_and_exit();
        }
    }

    /// Starts the watcher thread; false when the pipe or thread cannot be made.
    pub fn start_watcher() -> bool {
        let mut fds = [0 as libc::c_int; 2];
        // SAFETY: `fds` has room for the two descriptors pipe(2) writes.
        if unsafe { libc::pipe(fds.as_mut_ptr()) } != 0 {
            return false;
        }
        let read_fd = fds[0];
        let spawned = std::thread::Builder::new()
            .name("ctrl-c".into())
            .spawn(move || loop {
                let mut byte = 0u8;
                // SAFETY: reads one byte into a local buffer from our own pipe.
                let n = unsafe { libc::read(read_fd, (&mut byte as *mut u8).cast(), 1) };
                if n == 1 {
                    super::clean_up();
                    say_and_exit();
                }
                if n == 0 {
                    return;
                }
            });
        if spawned.is_err() {
            return false;
        }
        WAKE.store(fds[1], Ordering::SeqCst);
        true
    }
}

/// Installs the Ctrl-C handler (SIGINT) for the rest of the process.
pub fn install() {
    #[cfg(unix)]
    // SAFETY: `on_sigint` only calls async-signal-safe functions.
    unsafe {
        unix::start_watcher();
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = unix::on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t;
        libc::sigemptyset(&mut action.sa_mask);
        action.sa_flags = libc::SA_RESTART;
        libc::sigaction(libc::SIGINT, &action, std::ptr::null_mut());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_run_message_names_the_folder_and_the_partial_one() {
        let m = run_message(std::path::Path::new("runs/deadzone"));
        assert!(m.starts_with("admittance: interrupted (Ctrl-C); runs/deadzone was left"));
        assert!(m.contains(&format!(".deadzone.partial-{}", std::process::id())));
        assert!(!m.contains('\n'));
        assert_eq!(
            run_partial(std::path::Path::new("runs/deadzone")),
            PathBuf::from(format!("runs/.deadzone.partial-{}", std::process::id()))
        );
        assert_eq!(
            run_partial(std::path::Path::new("deadzone")),
            PathBuf::from(format!("./.deadzone.partial-{}", std::process::id()))
        );
    }

    #[test]
    fn clean_up_removes_only_marked_folders_and_files() {
        let dir = tempfile::tempdir().unwrap();
        let marked = dir.path().join(".x.partial-1");
        std::fs::create_dir(&marked).unwrap();
        std::fs::write(marked.join(PARTIAL_MARKER), "").unwrap();
        std::fs::write(marked.join("a.csv"), "t\n").unwrap();
        let unmarked = dir.path().join("mine");
        std::fs::create_dir(&unmarked).unwrap();
        let file = dir.path().join(".report.md.tmp-1");
        std::fs::write(&file, "half").unwrap();
        remove_on_interrupt(marked.clone(), Some(PARTIAL_MARKER));
        remove_on_interrupt(unmarked.clone(), Some(PARTIAL_MARKER));
        remove_on_interrupt(file.clone(), None);
        remove_on_interrupt(dir.path().join("never-written"), None);
        remove_registered();
        assert!(!marked.exists() && !file.exists() && unmarked.exists());
    }
}
