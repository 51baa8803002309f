//! Reading only regular files, with a size bound, so that a FIFO never blocks a command
//! and `/dev/zero` or a huge file never exhausts memory.

use std::fs::File;
use std::io::{Error, ErrorKind, Read};
use std::path::Path;

/// The most read from a TOML, JSON or URDF file: 64 MiB.
pub const TEXT_LIMIT: u64 = 64 << 20;
/// The most read from a CSV time series or a network file: 1 GiB.
pub const DATA_LIMIT: u64 = 1 << 30;

fn refused(meta: &std::fs::Metadata) -> Error {
    Error::new(
        ErrorKind::InvalidInput,
        format!(
            "is {}, not a regular file: only regular files are read",
            super::kind_of(meta)
        ),
    )
}

fn too_large(size: u64, limit: u64) -> Error {
    Error::new(
        ErrorKind::InvalidData,
        format!(
            "is {}, more than the {} read from a file of this kind",
            super::size_text(size),
            super::size_text(limit)
        ),
    )
}

/// Opens `path` for reading when it is a regular file (through links) of at most `limit`
/// bytes; the file is opened without blocking and checked again once open, so a FIFO
/// swapped in after the first check is refused too. Read the result through
/// `Read::take(limit)` when the file may still grow.
pub fn open_regular(path: &Path, limit: u64) -> std::io::Result<File> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(refused(&meta));
    }
    if meta.len() > limit {
        return Err(too_large(meta.len(), limit));
    }
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(refused(&meta));
    }
    if meta.len() > limit {
        return Err(too_large(meta.len(), limit));
    }
    Ok(file)
}

/// Reads the regular file at `path`, at most `limit` bytes (see [`open_regular`]).
pub fn read_regular(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let file = open_regular(path, limit)?;
    let mut bytes = Vec::with_capacity(file.metadata()?.len() as usize);
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64, limit));
    }
    Ok(bytes)
}

/// Reads the regular file at `path` as UTF-8 text, at most `limit` bytes.
pub fn read_regular_text(path: &Path, limit: u64) -> std::io::Result<String> {
    String::from_utf8(read_regular(path, limit)?)
        .map_err(|e| Error::new(ErrorKind::InvalidData, format!("is not UTF-8 text: {e}")))
}
