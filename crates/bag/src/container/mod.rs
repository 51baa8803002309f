//! A bounded reader of MCAP files (the container rosbag2 writes; format: mcap.dev/spec).
//!
//! Records are read from the file one at a time, chunk by chunk, never the whole file:
//! memory is one record (at most [`MAX_RECORD_BYTES`], compressed and uncompressed) plus
//! the schemas and channels. Every declared length is checked against the bytes left in
//! the file and against the limit before anything is allocated; a chunk's decompression is
//! one call that ends with its input and must give exactly the declared size (chunk.rs).
//! A damaged record is an error naming the file, the chunk and its byte offset, or with
//! `accept_damage` skipped and listed; a file that ends inside a record (a killed
//! recorder) keeps the messages decodable before the end.

mod chunk;
mod message;
mod records;
mod registry;

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use crate::error::{BagError, CONVERT_COMMAND};
use chunk::ChunkError;
pub use message::{RawMessage, StreamOutcome};
use records::{Record, CHUNK, DATA_END, FOOTER};

/// The largest record (and a chunk's uncompressed records) the reader accepts: 256 MiB.
/// rosbag2 writes chunks of about 768 KiB; a larger declaration is damage.
pub const MAX_RECORD_BYTES: u64 = 256 << 20;

const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

struct Schema {
    name: String,
    encoding: String,
    data: Vec<u8>,
}

struct Channel {
    topic: String,
    encoding: String,
    schema: u16,
}

/// What went wrong at a place of the file.
enum Fault {
    /// The record is damaged but its length is sound: reading can go on after it.
    Record(String),
    /// The file cannot be read past this point (truncated, a length beyond the file).
    Fatal(String),
    /// Not damage: the file uses what this reader does not read.
    Unsupported(String),
    /// The visitor's error.
    Visit(BagError),
}

struct Reader<'p> {
    path: &'p Path,
    file: BufReader<File>,
    len: u64,
    pos: u64,
    schemas: HashMap<u16, Schema>,
    channels: HashMap<u16, Channel>,
    chunks: usize,
    accept: bool,
    last_log: Option<u64>,
    outcome: StreamOutcome,
}

fn io_error(path: &Path, e: impl std::fmt::Display) -> BagError {
    BagError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Streams the messages of one MCAP file to `visit` (see the module's documentation).
pub fn read(
    path: &Path,
    accept_damage: bool,
    visit: &mut dyn FnMut(&RawMessage) -> Result<(), BagError>,
) -> Result<StreamOutcome, BagError> {
    let file = File::open(path).map_err(|e| io_error(path, e))?;
    let meta = file.metadata().map_err(|e| io_error(path, e))?;
    if !meta.is_file() {
        return Err(io_error(path, "not a regular file"));
    }
    let mut r = Reader {
        path,
        file: BufReader::with_capacity(1 << 16, file),
        len: meta.len(),
        pos: 0,
        schemas: HashMap::new(),
        channels: HashMap::new(),
        chunks: 0,
        accept: accept_damage,
        last_log: None,
        outcome: StreamOutcome::default(),
    };
    r.run(accept_damage, visit)?;
    Ok(r.outcome)
}

impl Reader<'_> {
    fn bytes(&mut self, n: u64) -> Result<Vec<u8>, String> {
        let mut v = Vec::with_capacity(n as usize);
        (&mut self.file)
            .take(n)
            .read_to_end(&mut v)
            .map_err(|e| e.to_string())?;
        self.pos += v.len() as u64;
        if (v.len() as u64) < n {
            return Err(format!("the file ends {} bytes early", n - v.len() as u64));
        }
        Ok(v)
    }

    fn skip(&mut self, n: u64) -> Result<(), String> {
        self.file
            .seek(SeekFrom::Current(n as i64))
            .map_err(|e| e.to_string())?;
        self.pos += n;
        Ok(())
    }

    fn run(
        &mut self,
        accept: bool,
        visit: &mut dyn FnMut(&RawMessage) -> Result<(), BagError>,
    ) -> Result<(), BagError> {
        let head = self.bytes(8).unwrap_or_default();
        if head != MAGIC {
            return self.fail(
                accept,
                0,
                "the file does not start with the MCAP magic bytes".into(),
                true,
            );
        }
        let mut summary = false;
        loop {
            let at = self.pos;
            let fault = match self.record(summary, visit) {
                Ok(Some(op)) if op == FOOTER => return Ok(()),
                Ok(Some(op)) => {
                    summary |= op == DATA_END;
                    continue;
                }
                Ok(None) => continue,
                Err(f) => f,
            };
            match fault {
                Fault::Visit(e) => return Err(e),
                Fault::Unsupported(what) => {
                    return Err(BagError::Unsupported {
                        path: self.path.to_path_buf(),
                        message: format!("{what}; only uncompressed and zstd chunks are read: convert with `{CONVERT_COMMAND}` (uncompressed), or record with zstd"),
                    })
                }
                Fault::Record(m) => self.fail(accept, at, m, false)?,
                Fault::Fatal(m) => return self.fail(accept, at, m, true),
            }
        }
    }

    /// Strict: the error. Accepting damage: listed (a skipped chunk counted).
    fn fail(
        &mut self,
        accept: bool,
        at: u64,
        message: String,
        fatal: bool,
    ) -> Result<(), BagError> {
        let last = self
            .last_log
            .map_or("none".to_string(), |t| format!("{:.9} s", t as f64 * 1e-9));
        let message = format!("at byte {at}: {message}");
        if !accept {
            return Err(BagError::Damaged {
                path: self.path.to_path_buf(),
                messages_read: self.outcome.messages,
                last_log_time: last,
                message,
                hint: "a recorder that was killed leaves a truncated file: pass --accept-damaged to import the messages before the damage and skip damaged chunks (the loss is reported)".into(),
            });
        }
        let what = if fatal {
            format!(
                "reading stopped after {} messages (last log time {last})",
                self.outcome.messages
            )
        } else {
            self.outcome.skipped_chunks += 1;
            "record skipped".to_string()
        };
        self.outcome
            .damage
            .push(format!("{}: {message}; {what}", self.path.display()));
        Ok(())
    }

    /// One record: its opcode, or `None` for a truncated chunk that was salvaged.
    fn record(
        &mut self,
        summary: bool,
        visit: &mut dyn FnMut(&RawMessage) -> Result<(), BagError>,
    ) -> Result<Option<u8>, Fault> {
        let left = self.len.saturating_sub(self.pos);
        if left == 0 {
            return Err(Fault::Fatal(
                "the file ends without the footer record (truncated)".into(),
            ));
        }
        let head = self
            .bytes(9)
            .map_err(|e| Fault::Fatal(format!("a record header: {e}")))?;
        let op = head[0];
        let len = u64::from_le_bytes(head[1..9].try_into().unwrap_or_default());
        let left = self.len.saturating_sub(self.pos);
        let chunk_name = |n: usize| format!("chunk {n} (opcode 0x06)");
        let name = if op == CHUNK && !summary {
            self.chunks += 1;
            chunk_name(self.chunks)
        } else {
            format!("record opcode {op:#04x}")
        };
        if len > left {
            if op == CHUNK && !summary && self.accept {
                self.salvage(left, visit)?;
            }
            return Err(Fault::Fatal(format!(
                "{name} declares {len} bytes, the file has {left} left (truncated or a damaged length)"
            )));
        }
        if summary
            || !matches!(
                op,
                records::SCHEMA | records::CHANNEL | records::MESSAGE | CHUNK
            )
        {
            self.skip(len).map_err(Fault::Fatal)?;
            if op == FOOTER {
                let tail = self.bytes(8).unwrap_or_default();
                if tail != MAGIC {
                    return Err(Fault::Fatal(
                        "no MCAP magic bytes after the footer (truncated)".into(),
                    ));
                }
            }
            return Ok(Some(op));
        }
        if len > MAX_RECORD_BYTES {
            self.skip(len).map_err(Fault::Fatal)?;
            return Err(Fault::Record(format!(
                "{name} declares {len} bytes, above the reader's limit of {MAX_RECORD_BYTES}"
            )));
        }
        let body = self.bytes(len).map_err(Fault::Fatal)?;
        let result = if op == CHUNK {
            self.chunk(&body, visit)
        } else {
            match records::parse(op, &body) {
                Ok(r) => self
                    .check(&r, &HashMap::new(), &HashMap::new())
                    .and_then(|_| self.apply(r, visit)),
                Err(e) => Err(Fault::Record(e)),
            }
        };
        result.map_err(|f| match f {
            Fault::Record(m) => Fault::Record(format!("{name}: {m}")),
            other => other,
        })?;
        Ok(Some(op))
    }

    fn chunk(
        &mut self,
        body: &[u8],
        visit: &mut dyn FnMut(&RawMessage) -> Result<(), BagError>,
    ) -> Result<(), Fault> {
        let header = records::chunk_header(body, false).map_err(Fault::Record)?;
        let records = chunk::decompress(&header).map_err(|e| match e {
            ChunkError::Unsupported(m) => Fault::Unsupported(m),
            ChunkError::Damaged(m) => Fault::Record(m),
        })?;
        let (list, bad) = records::chunk_records(&records);
        if let Some(bad) = bad {
            return Err(Fault::Record(bad));
        }
        // All of the chunk is checked before any of it is used: a damaged chunk is
        // skipped whole.
        let (mut schemas, mut channels) = (HashMap::new(), HashMap::new());
        for r in &list {
            self.check(r, &schemas, &channels)?;
            match r {
                Record::Schema { id, .. } => {
                    schemas.insert(*id, ());
                }
                Record::Channel { id, .. } => {
                    channels.insert(*id, ());
                }
                _ => {}
            }
        }
        for r in list {
            self.apply(r, visit)?;
        }
        Ok(())
    }

    /// The decodable start of a truncated chunk (the last of a killed recording).
    fn salvage(
        &mut self,
        left: u64,
        visit: &mut dyn FnMut(&RawMessage) -> Result<(), BagError>,
    ) -> Result<(), Fault> {
        let Ok(body) = self.bytes(left.min(MAX_RECORD_BYTES)) else {
            return Ok(());
        };
        let Ok(header) = records::chunk_header(&body, true) else {
            return Ok(());
        };
        if header.records.len() as u64 >= header.records_len {
            return Ok(());
        }
        let out = chunk::salvage(&header);
        let (list, _) = records::chunk_records(&out);
        let (mut schemas, mut channels) = (HashMap::new(), HashMap::new());
        for r in list {
            if self.check(&r, &schemas, &channels).is_err() {
                break;
            }
            match &r {
                Record::Schema { id, .. } => {
                    schemas.insert(*id, ());
                }
                Record::Channel { id, .. } => {
                    channels.insert(*id, ());
                }
                _ => {}
            }
            self.apply(r, visit)?;
        }
        Ok(())
    }
}
