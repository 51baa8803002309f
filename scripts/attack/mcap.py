"""Just enough of the MCAP layout (mcap.dev/spec) to damage a bag on purpose: the records,
the fields of a chunk's header, the message records of an uncompressed chunk."""
import struct
import zlib

MAGIC = b"\x89MCAP0\r\n"
OP_MESSAGE, OP_CHUNK = 0x05, 0x06


def records(buf, start=len(MAGIC), end=None):
    """(opcode, offset of the record, offset of its content, content length) of each record
    between start and end, stopping at the first one that does not fit."""
    end = len(buf) if end is None else end
    pos = start
    while pos + 9 <= end:
        op = buf[pos]
        (length,) = struct.unpack_from("<Q", buf, pos + 1)
        if pos + 9 + length > end:
            return
        yield op, pos, pos + 9, length
        pos += 9 + length


def chunks(buf):
    """Each chunk's header fields as {name: (absolute offset, size)} plus its compressed
    records' offset, size and compression."""
    out = []
    for op, rec, content, length in records(buf):
        if op != OP_CHUNK:
            continue
        c = content
        fields = {"record_length": (rec + 1, 8), "message_start_time": (c, 8),
                  "message_end_time": (c + 8, 8), "uncompressed_size": (c + 16, 8),
                  "uncompressed_crc": (c + 24, 4), "compression_length": (c + 28, 4)}
        (clen,) = struct.unpack_from("<I", buf, c + 28)
        compression = bytes(buf[c + 32:c + 32 + clen]).decode()
        fields["records_length"] = (c + 32 + clen, 8)
        data = c + 32 + clen + 8
        (dlen,) = struct.unpack_from("<Q", buf, c + 32 + clen)
        out.append({"fields": fields, "compression": compression, "data": data,
                    "data_length": dlen, "crc_at": c + 24})
    return out


def flip_bit(buf, offset, bit):
    b = bytearray(buf)
    b[offset + bit // 8] ^= 1 << (bit % 8)
    return b


def messages_of_plain_chunk(buf, chunk):
    """(offset of the message record, offset of log_time, offset of its data, data length)
    of each message in an uncompressed chunk."""
    out = []
    start, end = chunk["data"], chunk["data"] + chunk["data_length"]
    for op, rec, content, length in records(buf, start, end):
        if op == OP_MESSAGE:
            out.append((rec, content + 6, content + 22, length - 22))
    return out


def fix_crc(buf, chunk):
    """Recomputes a chunk's uncompressed CRC (only for an uncompressed chunk with a CRC)."""
    (stored,) = struct.unpack_from("<I", buf, chunk["crc_at"])
    if stored and chunk["compression"] == "":
        data = bytes(buf[chunk["data"]:chunk["data"] + chunk["data_length"]])
        struct.pack_into("<I", buf, chunk["crc_at"], zlib.crc32(data) & 0xFFFFFFFF)
