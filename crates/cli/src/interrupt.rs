//! Ctrl-C: one line on stderr and exit code 130 (128 + SIGINT, what shells report for a
//! command interrupted from the keyboard), instead of dying silently.
//!
//! The line is prepared before the work starts ([`set_message`]), because the handler may
//! only do async-signal-safe things: it writes the prepared bytes with `write(2)` and ends
//! the process with `_exit(2)`. Nothing needs unwinding: every output is written to a
//! temporary sibling and renamed into place when complete (docs/outputs.md), so an
//! interrupted command leaves the user's files as they were.

use std::io::IsTerminal;
use std::sync::OnceLock;

/// The exit code of an interrupted command.
pub const EXIT_CODE: u8 = 130;

/// The line printed when no command set its own.
const DEFAULT_LINE: &[u8] = b"admittance: interrupted (Ctrl-C)\n";

static MESSAGE: OnceLock<Box<[u8]>> = OnceLock::new();

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

/// The line `admittance run --out out_dir` prints on Ctrl-C: where the unfinished folder is
/// and that the next run removes it (docs/outputs.md, "Where a run may write").
pub fn run_message(out_dir: &std::path::Path) -> String {
    let leaf = out_dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| out_dir.display().to_string());
    format!(
        "admittance: interrupted (Ctrl-C); {} was left as it was (the run folder appears only \
         when complete); an unfinished .{leaf}.partial-{} beside it, if any, is removed by the \
         next run",
        out_dir.display(),
        std::process::id()
    )
}

#[cfg(unix)]
extern "C" fn on_sigint(_signal: libc::c_int) {
    let message: &[u8] = MESSAGE.get().map(|m| &m[..]).unwrap_or(DEFAULT_LINE);
    // SAFETY: write(2) and _exit(2) are async-signal-safe; `message` is a static buffer that
    // is never freed or changed once set.
    unsafe {
        libc::write(2, message.as_ptr().cast(), message.len());
        libc::_exit(EXIT_CODE as libc::c_int);
    }
}

/// Installs the Ctrl-C handler (SIGINT) for the rest of the process.
pub fn install() {
    #[cfg(unix)]
    // SAFETY: `on_sigint` only calls async-signal-safe functions.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t;
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
    }
}
