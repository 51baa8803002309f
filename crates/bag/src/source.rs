//! Finding the MCAP files of a bag and streaming their messages.

use std::path::{Path, PathBuf};

use crate::error::{BagError, CONVERT_COMMAND};

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

fn head(path: &Path) -> Result<Vec<u8>, BagError> {
    use std::io::Read;
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

/// One message, with what its channel says about it.
pub struct RawMessage<'a> {
    /// Topic.
    pub topic: &'a str,
    /// The schema's name (the ROS type), or "" without a schema.
    pub type_name: &'a str,
    /// The schema's encoding (`ros2msg`) and text.
    pub schema: Option<(&'a str, &'a [u8])>,
    /// The message encoding (`cdr`).
    pub encoding: &'a str,
    /// Log (receive) time, ns since the epoch.
    pub log_time: u64,
    /// The payload.
    pub data: &'a [u8],
}

/// What happened while streaming a file: messages read, and the damage that stopped the
/// reading early when damage is accepted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StreamOutcome {
    /// Messages handed to the visitor.
    pub messages: usize,
    /// The MCAP reader's error that ended the file early (accepted damage).
    pub damage: Option<String>,
}

fn fmt_time(ns: Option<u64>) -> String {
    ns.map_or("none".to_string(), |t| format!("{:.9} s", t as f64 * 1e-9))
}

/// Streams the messages of one MCAP file to `visit`. Damaged data (truncation, a failed
/// chunk CRC or decompression) is an error naming the file, the messages read before and
/// the last log time; with `accept_damage` the messages before it are kept and the damage
/// is returned in the outcome to be reported.
pub fn stream(
    file: &Path,
    accept_damage: bool,
    mut visit: impl FnMut(&RawMessage) -> Result<(), BagError>,
) -> Result<StreamOutcome, BagError> {
    let bytes = std::fs::read(file).map_err(|e| io(file, e))?;
    let mut outcome = StreamOutcome::default();
    let mut last_log = None;
    let damaged = |message: String, read: usize, last: Option<u64>| {
        BagError::Damaged {
        path: file.to_path_buf(),
        messages_read: read,
        last_log_time: fmt_time(last),
        message,
        hint: "a recorder that was killed leaves a truncated file: pass --accept-damaged to import the messages before the damage (the loss is reported)".into(),
    }
    };
    let mut messages = match mcap::MessageStream::new(&bytes) {
        Ok(s) => s,
        Err(e) => return Err(damaged(e.to_string(), 0, None)),
    };
    loop {
        // The MCAP reader parses untrusted bytes: a panic in it is reported as damage.
        let next = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| messages.next()))
            .unwrap_or_else(|_| Some(Err(mcap::McapError::BadIndex)));
        let message = match next {
            None => break,
            Some(Ok(m)) => m,
            Some(Err(mcap::McapError::UnsupportedCompression(c))) => {
                return Err(BagError::Unsupported {
                    path: file.to_path_buf(),
                    message: format!(
                        "chunks compressed with `{c}`; only uncompressed and zstd chunks are read: convert with `{CONVERT_COMMAND}` (uncompressed), or record with zstd"
                    ),
                })
            }
            Some(Err(e)) if accept_damage => {
                outcome.damage = Some(format!(
                    "{}: reading stopped after {} messages (last log time {}): {e}",
                    file.display(),
                    outcome.messages,
                    fmt_time(last_log)
                ));
                break;
            }
            Some(Err(e)) => return Err(damaged(e.to_string(), outcome.messages, last_log)),
        };
        let schema = message.channel.schema.as_deref();
        visit(&RawMessage {
            topic: &message.channel.topic,
            type_name: schema.map_or("", |s| s.name.as_str()),
            schema: schema.map(|s| (s.encoding.as_str(), &*s.data)),
            encoding: &message.channel.message_encoding,
            log_time: message.log_time,
            data: &message.data,
        })?;
        outcome.messages += 1;
        last_log = Some(message.log_time);
    }
    Ok(outcome)
}
