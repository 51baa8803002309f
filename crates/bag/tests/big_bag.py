#!/usr/bin/env python3
"""Writes an uncompressed MCAP of N franka measured_joint_states messages at 1 kHz (the
first such message of the shipped franka_plain.mcap, its stamp rewritten), in chunks of
~768 KiB, for the import's memory and time measurement (docs/benchmarks.md, "Bag import"):

    python3 crates/bag/tests/big_bag.py crates/bag/tests/data/franka_plain.mcap /tmp/big.mcap 1000000

Standard library only; the file is about 363 bytes per message."""
import struct, sys
src, dst, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
b = open(src, 'rb').read()
def records(buf, pos, end):
    while pos + 9 <= end:
        op = buf[pos]; ln = struct.unpack_from('<Q', buf, pos + 1)[0]
        yield op, buf[pos + 9:pos + 9 + ln]
        pos += 9 + ln
schema = channel = payload = None
for op, body in records(b, 8, len(b)):
    if op == 6:
        clen = struct.unpack_from('<I', body, 28)[0]
        rl = struct.unpack_from('<Q', body, 32 + clen)[0]
        inner = body[40 + clen:40 + clen + rl]
        chans = {}
        for op2, b2 in records(inner, 0, len(inner)):
            if op2 == 3 and schema is None and b'JointState' in b2: schema = b2
            if op2 == 4:
                cid = struct.unpack_from('<H', b2, 0)[0]
                tl = struct.unpack_from('<I', b2, 4)[0]
                chans[cid] = (b2[8:8 + tl], b2)
            if op2 == 5:
                cid = struct.unpack_from('<H', b2, 0)[0]
                if chans[cid][0].endswith(b'measured_joint_states') and payload is None:
                    channel = chans[cid][1]; payload = b2[22:]
        break
def rec(op, body): return bytes([op]) + struct.pack('<Q', len(body)) + body
sid = struct.unpack_from('<H', schema, 0)[0]
cid = struct.unpack_from('<H', channel, 0)[0]
t0 = 1_700_000_000 * 10**9
with open(dst, 'wb') as f:
    f.write(b'\x89MCAP0\r\n')
    f.write(rec(1, struct.pack('<I', 4) + b'ros2' + struct.pack('<I', 0)))
    f.write(rec(3, schema)); f.write(rec(4, channel))
    k = 0
    while k < n:
        msgs = []
        size = 0
        while k < n and size < 768 * 1024:
            t = t0 + k * 10**6
            p = bytearray(payload)
            struct.pack_into('<iI', p, 4, t // 10**9, t % 10**9)
            m = rec(5, struct.pack('<HIQQ', cid, k, t + 200000, t + 200000) + bytes(p))
            msgs.append(m); size += len(m); k += 1
        data = b''.join(msgs)
        body = struct.pack('<QQQI', 0, 0, len(data), 0) + struct.pack('<I', 0) + struct.pack('<Q', len(data)) + data
        f.write(rec(6, body))
    f.write(rec(0x0f, struct.pack('<I', 0)))
    f.write(rec(2, struct.pack('<QQI', 0, 0, 0)))
    f.write(b'\x89MCAP0\r\n')
