//! The MCAP records the import reads (Schema, Channel, Message, a Chunk's header), parsed
//! from bytes with every length checked against what is there (mcap.dev/spec: integers
//! little-endian; strings and byte arrays prefixed by their u32 length).

/// Opcodes (MCAP spec, "Records").
pub const FOOTER: u8 = 0x02;
pub const SCHEMA: u8 = 0x03;
pub const CHANNEL: u8 = 0x04;
pub const MESSAGE: u8 = 0x05;
pub const CHUNK: u8 = 0x06;
pub const DATA_END: u8 = 0x0f;

/// A cursor over untrusted bytes: every read is bounds-checked.
pub struct Bytes<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Bytes<'a> {
    pub fn new(buf: &'a [u8]) -> Self {
        Self { buf, pos: 0 }
    }

    pub fn pos(&self) -> usize {
        self.pos
    }

    pub fn left(&self) -> usize {
        self.buf.len() - self.pos
    }

    pub fn take(&mut self, n: u64, what: &str) -> Result<&'a [u8], String> {
        if n > self.left() as u64 {
            return Err(format!(
                "{what} declares {n} bytes, only {} are left",
                self.left()
            ));
        }
        let n = n as usize;
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        let s = self.take(N as u64, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    pub fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.array::<1>(what)?[0])
    }

    pub fn u16(&mut self, what: &str) -> Result<u16, String> {
        self.array(what).map(u16::from_le_bytes)
    }

    pub fn u32(&mut self, what: &str) -> Result<u32, String> {
        self.array(what).map(u32::from_le_bytes)
    }

    pub fn u64(&mut self, what: &str) -> Result<u64, String> {
        self.array(what).map(u64::from_le_bytes)
    }

    /// u32 length, then that many bytes.
    pub fn prefixed(&mut self, what: &str) -> Result<&'a [u8], String> {
        let n = self.u32(what)?;
        self.take(u64::from(n), what)
    }

    pub fn string(&mut self, what: &str) -> Result<&'a str, String> {
        std::str::from_utf8(self.prefixed(what)?).map_err(|_| format!("{what} is not UTF-8"))
    }

    pub fn rest(&mut self) -> &'a [u8] {
        let s = &self.buf[self.pos..];
        self.pos = self.buf.len();
        s
    }
}

/// A record the import uses; any other opcode is `Other`.
#[derive(Debug)]
pub enum Record<'a> {
    Schema {
        id: u16,
        name: &'a str,
        encoding: &'a str,
        data: &'a [u8],
    },
    Channel {
        id: u16,
        schema: u16,
        topic: &'a str,
        encoding: &'a str,
    },
    Message {
        channel: u16,
        log_time: u64,
        data: &'a [u8],
    },
    Other,
}

/// Parses a record's body.
pub fn parse(op: u8, body: &[u8]) -> Result<Record<'_>, String> {
    let mut b = Bytes::new(body);
    Ok(match op {
        SCHEMA => Record::Schema {
            id: b.u16("schema id")?,
            name: b.string("schema name")?,
            encoding: b.string("schema encoding")?,
            data: b.prefixed("schema data")?,
        },
        CHANNEL => {
            let id = b.u16("channel id")?;
            let schema = b.u16("channel schema id")?;
            let topic = b.string("channel topic")?;
            let encoding = b.string("channel message encoding")?;
            b.prefixed("channel metadata")?;
            Record::Channel {
                id,
                schema,
                topic,
                encoding,
            }
        }
        MESSAGE => {
            let channel = b.u16("message channel id")?;
            b.u32("message sequence")?;
            let log_time = b.u64("message log time")?;
            b.u64("message publish time")?;
            Record::Message {
                channel,
                log_time,
                data: b.rest(),
            }
        }
        _ => Record::Other,
    })
}

/// The fixed part of a Chunk record, and its (compressed) records.
pub struct ChunkHeader<'a> {
    pub uncompressed_size: u64,
    pub uncompressed_crc: u32,
    pub compression: &'a str,
    /// The declared length of the compressed records.
    pub records_len: u64,
    /// The compressed records present (all of them unless the chunk is truncated).
    pub records: &'a [u8],
}

/// Parses a chunk's body; with `truncated`, the records may be shorter than declared.
pub fn chunk_header(body: &[u8], truncated: bool) -> Result<ChunkHeader<'_>, String> {
    let mut b = Bytes::new(body);
    b.u64("chunk start time")?;
    b.u64("chunk end time")?;
    let uncompressed_size = b.u64("chunk uncompressed size")?;
    let uncompressed_crc = b.u32("chunk CRC")?;
    let compression = b.string("chunk compression")?;
    let records_len = b.u64("chunk records length")?;
    let left = b.left() as u64;
    if (records_len > left && !truncated) || records_len < left {
        return Err(format!(
            "the chunk's records declare {records_len} bytes, the record holds {left}"
        ));
    }
    Ok(ChunkHeader {
        uncompressed_size,
        uncompressed_crc,
        compression,
        records_len,
        records: b.rest(),
    })
}

/// The records of a chunk's uncompressed bytes, in order, each with its offset in the
/// chunk; on the first malformed record, those before it and what is wrong.
pub fn chunk_records(buf: &[u8]) -> (Vec<Record<'_>>, Option<String>) {
    let mut b = Bytes::new(buf);
    let mut out = Vec::new();
    while b.left() > 0 {
        let at = b.pos();
        let one = (|| {
            let op = b.u8("record opcode")?;
            let len = b.u64("record length")?;
            let body = b.take(len, "record")?;
            parse(op, body)
        })();
        match one {
            Ok(r) => out.push(r),
            Err(e) => return (out, Some(format!("record at byte {at} of the chunk: {e}"))),
        }
    }
    (out, None)
}
