//! A chunk's records, decompressed within bounds: the declared size is checked against
//! [`MAX_RECORD_BYTES`] and (zstd) against the sizes the frames declare before anything is
//! allocated; one decompression call that ends with its input; the output must have
//! exactly the declared size and, when the writer stored one, the declared CRC.

use std::borrow::Cow;
use std::io::Read;

use super::records::ChunkHeader;
use super::MAX_RECORD_BYTES;

/// Why a chunk cannot be read.
pub enum ChunkError {
    /// A compression this reader does not decode (lz4): not damage, the whole file is
    /// refused.
    Unsupported(String),
    /// The chunk is damaged.
    Damaged(String),
}

fn damaged(m: String) -> ChunkError {
    ChunkError::Damaged(m)
}

/// The sum of the content sizes the zstd frames declare, when every frame declares one.
fn zstd_declared_size(src: &[u8]) -> Result<Option<u64>, String> {
    let (mut at, mut total) = (0usize, 0u64);
    while at < src.len() {
        let rest = &src[at..];
        let len = zstd::zstd_safe::find_frame_compressed_size(rest).map_err(|c| {
            format!(
                "zstd frame at byte {at} of the chunk's records: {}",
                zstd::zstd_safe::get_error_name(c)
            )
        })?;
        let size = match zstd::zstd_safe::get_frame_content_size(rest) {
            Ok(Some(s)) => s,
            Ok(None) => return Ok(None),
            Err(_) => {
                return Err(format!(
                    "zstd frame at byte {at} of the chunk's records: a bad frame header"
                ))
            }
        };
        total = total.saturating_add(size);
        at = at.saturating_add(len.max(1));
    }
    Ok(Some(total))
}

/// The chunk's uncompressed records (borrowed when uncompressed).
pub fn decompress<'a>(c: &ChunkHeader<'a>) -> Result<Cow<'a, [u8]>, ChunkError> {
    let declared = c.uncompressed_size;
    if declared > MAX_RECORD_BYTES {
        return Err(damaged(format!(
            "declared uncompressed size {declared} bytes is above the reader's limit of {MAX_RECORD_BYTES} bytes"
        )));
    }
    let out: Cow<'a, [u8]> = match c.compression {
        "" => Cow::Borrowed(c.records),
        "zstd" => {
            match zstd_declared_size(c.records).map_err(damaged)? {
                Some(s) if s != declared => {
                    return Err(damaged(format!(
                        "declared uncompressed size {declared} bytes, its zstd frames hold {s}"
                    )))
                }
                _ => {}
            }
            // Capacity = the declared size: a larger output is an error, not a reallocation.
            let v = zstd::bulk::decompress(c.records, declared as usize)
                .map_err(|e| damaged(format!("zstd decompression failed: {e}")))?;
            Cow::Owned(v)
        }
        "lz4" => {
            return Err(ChunkError::Unsupported(
                "chunks compressed with `lz4`".into(),
            ))
        }
        other => {
            return Err(ChunkError::Unsupported(format!(
                "chunks compressed with `{}`",
                other.escape_debug()
            )))
        }
    };
    if out.len() as u64 != declared {
        return Err(damaged(format!(
            "declared uncompressed size {declared} bytes, the records are {} bytes",
            out.len()
        )));
    }
    if c.uncompressed_crc != 0 {
        let crc = crc32fast::hash(&out);
        if crc != c.uncompressed_crc {
            return Err(damaged(format!(
                "CRC of the uncompressed records is {crc:#010x}, the chunk declares {:#010x}",
                c.uncompressed_crc
            )));
        }
    }
    Ok(out)
}

/// What can be decoded from the start of a truncated chunk (the file ends inside it): at
/// most the declared size (and the limit); streaming zstd stops at the end of its input.
pub fn salvage(c: &ChunkHeader<'_>) -> Vec<u8> {
    let cap = c.uncompressed_size.min(MAX_RECORD_BYTES);
    match c.compression {
        "" => c.records[..c.records.len().min(cap as usize)].to_vec(),
        "zstd" => {
            let mut out = Vec::new();
            if let Ok(d) = zstd::stream::read::Decoder::with_buffer(c.records) {
                // The decoder reports an error at the truncation; what came before is kept.
                let _ = d.take(cap).read_to_end(&mut out);
            }
            out
        }
        _ => Vec::new(),
    }
}
