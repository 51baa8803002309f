//! Reading and writing the tool's files safely, the one place every crate goes through.
//!
//! * [`write_atomic`] / [`write_atomic_with`]: a file is written into a temporary file in
//!   the destination's folder, with an unpredictable name, created exclusively
//!   (`O_CREAT | O_EXCL | O_NOFOLLOW`: a link planted at that name is never followed),
//!   fsynced and renamed over the destination; the destination is replaced only when it is
//!   missing or a regular file, never followed when it is a symbolic link.
//! * [`temp_dir_beside`]: the same for a folder that is filled and then renamed into place;
//!   [`exchange`] swaps it with the folder it replaces in one step.
//! * [`read_regular`] / [`read_regular_text`] / [`open_regular`]: only a regular file is
//!   read (a FIFO, a device or a socket is refused from its metadata, and opened without
//!   blocking in case it was swapped in since), and never more than a stated bound
//!   ([`TEXT_LIMIT`] for TOML, JSON and URDF files, [`DATA_LIMIT`] for CSV and network files).
//! * [`remove_pending`]: the temporary files and folders still being written, removed by
//!   the command line's Ctrl-C handler.

#![warn(missing_docs)]

mod exchange;
mod read;
mod write;

pub use exchange::exchange;
pub use read::{open_regular, read_regular, read_regular_text, DATA_LIMIT, TEXT_LIMIT};
pub use write::{release, remove_pending, temp_dir_beside, write_atomic, write_atomic_with};

/// What kind of thing a path's metadata describes, for messages.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a folder";
    }
    if t.is_symlink() {
        return "a symbolic link";
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
    if t.is_file() {
        return "a regular file";
    }
    "not a regular file"
}

/// A size in bytes for messages: `64 MiB`, `1 GiB`, `312 bytes`.
fn size_text(bytes: u64) -> String {
    const MIB: u64 = 1 << 20;
    if bytes >= 1 << 30 && bytes % (1 << 30) == 0 {
        format!("{} GiB", bytes >> 30)
    } else if bytes >= MIB {
        format!("{:.1} MiB", bytes as f64 / MIB as f64)
    } else {
        format!("{bytes} bytes")
    }
}
