//! Finding the MCAP files of a bag and streaming their messages.

use std::path::{Path, PathBuf};

use crate::container::{RawMessage, StreamOutcome};
use crate::error::BagError;

/// The MCAP file's first bytes.
const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";
/// A sqlite3 database's first bytes.
const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";

fn io(path: &Path, e: impl std::fmt::Display) -> BagError {
    BagError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Refuses anything but a regular file (a FIFO would block the reader for ever, a device
/// read without end) from its metadata, before the file is opened.
fn regular_file(path: &Path) -> Result<(), BagError> {
    let meta = std::fs::metadata(path).map_err(|e| io(path, e))?;
    if meta.is_file() {
        return Ok(());
    }
    Err(BagError::NotABag {
        path: path.to_path_buf(),
        reason: format!(
            "{}; a bag is a folder of .mcap files or one regular .mcap file",
            special_kind(&meta.file_type())
        ),
    })
}

/// What a file that is not a regular file is, in words.
pub fn special_kind(t: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a folder"
    } else {
        "not a regular file"
    }
}

fn head(path: &Path) -> Result<Vec<u8>, BagError> {
    use std::io::Read;
    regular_file(path)?;
    let mut buf = Vec::with_capacity(16);
    std::fs::File::open(path)
        .and_then(|f| f.take(16).read_to_end(&mut buf))
        .map_err(|e| io(path, e))?;
    Ok(buf)
}

/// The `.mcap` files of a bag, in name order (a split recording's parts): the bag is a
/// rosbag2 folder (`metadata.yaml` is not needed), its `metadata.yaml`, or one `.mcap`
/// file. A sqlite3 bag is refused with the conversion command.
pub fn locate(bag: &Path) -> Result<Vec<PathBuf>, BagError> {
    let meta = std::fs::metadata(bag).map_err(|e| io(bag, e))?;
    if meta.is_dir() {
        return locate_in_folder(bag);
    }
    if bag.file_name().is_some_and(|n| n == "metadata.yaml") {
        let dir = bag.parent().filter(|d| !d.as_os_str().is_empty());
        return locate_in_folder(dir.unwrap_or(Path::new(".")));
    }
    let start = head(bag)?;
    if start.starts_with(SQLITE_MAGIC) || bag.extension().is_some_and(|e| e == "db3") {
        return Err(BagError::Sqlite {
            path: bag.to_path_buf(),
        });
    }
    if !start.starts_with(MCAP_MAGIC) {
        return Err(BagError::NotABag {
            path: bag.to_path_buf(),
            reason: "the file does not start with the MCAP magic bytes".into(),
        });
    }
    Ok(vec![bag.to_path_buf()])
}

fn locate_in_folder(dir: &Path) -> Result<Vec<PathBuf>, BagError> {
    let mut mcap = Vec::new();
    let mut db3 = false;
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| io(dir, e))? {
        let path = entry.map_err(|e| io(dir, e))?.path();
        let name = path.file_name().map(|n| n.to_string_lossy().to_string());
        names.extend(name);
        match path.extension().and_then(|e| e.to_str()) {
            Some("mcap") => mcap.push(path),
            Some("db3") => db3 = true,
            _ => {}
        }
    }
    if mcap.is_empty() {
        if db3 {
            return Err(BagError::Sqlite {
                path: dir.to_path_buf(),
            });
        }
        names.sort();
        return Err(BagError::NotABag {
            path: dir.to_path_buf(),
            reason: format!(
                "no .mcap file in the folder (it holds: {})",
                names.join(", ")
            ),
        });
    }
    mcap.sort();
    for f in &mcap {
        if !head(f)?.starts_with(MCAP_MAGIC) {
            return Err(BagError::NotABag {
                path: f.clone(),
                reason: "the file does not start with the MCAP magic bytes".into(),
            });
        }
    }
    Ok(mcap)
}

/// Streams the messages of one MCAP file to `visit`, record by record with bounded
/// memory (`crate::container`). Damaged data (truncation, a failed chunk CRC or
/// decompression, a declared size that does not hold) is an error naming the file, the
/// byte offset, the chunk, the messages read before and the last log time; with
/// `accept_damage` a damaged chunk is skipped and counted, a truncated file keeps the
/// messages before the end, and the loss is returned in the outcome to be reported.
pub fn stream(
    file: &Path,
    accept_damage: bool,
    mut visit: impl FnMut(&RawMessage) -> Result<(), BagError>,
) -> Result<StreamOutcome, BagError> {
    regular_file(file)?;
    crate::container::read(file, accept_damage, &mut visit)
}
