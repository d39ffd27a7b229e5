"""Peer for the recording benchmark: write the same messages with the Python `mcap` writer.

Usage: bench_mcap_writer.py MESSAGES.bin OUT.mcap COMPRESSION(zstd|lz4|none) CHUNK_SIZE
MESSAGES.bin holds: u32 topic count; per topic u16-len topic, u16-len type, u32-len definition;
then records (u16 topic index, u64 log time, u32 length, payload). Only the writing is timed;
prints JSON {"seconds", "bytes_in", "messages", "file_bytes"}.
"""
import json
import os
import struct
import sys
import time

from mcap.writer import CompressionType, Writer


def read_messages(path):
    with open(path, 'rb') as f:
        buf = f.read()
    (ntopics,) = struct.unpack_from('<I', buf, 0)
    pos = 4
    topics = []
    for _ in range(ntopics):
        parts = []
        for fmt in ('<H', '<H', '<I'):
            (n,) = struct.unpack_from(fmt, buf, pos)
            pos += struct.calcsize(fmt)
            parts.append(buf[pos:pos + n].decode())
            pos += n
        topics.append(parts)
    msgs = []
    while pos < len(buf):
        ch, t, n = struct.unpack_from('<HQI', buf, pos)
        pos += 14
        msgs.append((ch, t, buf[pos:pos + n]))
        pos += n
    return topics, msgs


def main(src, out, compression, chunk_size):
    topics, msgs = read_messages(src)
    comp = {'zstd': CompressionType.ZSTD, 'lz4': CompressionType.LZ4, 'none': CompressionType.NONE}[compression]
    t0 = time.perf_counter()
    with open(out, 'wb') as f:
        w = Writer(f, compression=comp, chunk_size=int(chunk_size))
        w.start(profile='ros2', library='python-mcap-bench')
        ids = []
        for name, typ, definition in topics:
            sid = w.register_schema(name=typ, encoding='ros2msg', data=definition.encode())
            ids.append(w.register_channel(topic=name, message_encoding='cdr', schema_id=sid,
                                          metadata={'offered_qos_profiles': ''}))
        for seq, (ch, t, data) in enumerate(msgs):
            w.add_message(channel_id=ids[ch], log_time=t, publish_time=t, data=data, sequence=seq)
        w.finish()
        f.flush()
        os.fsync(f.fileno())
    dt = time.perf_counter() - t0
    print(json.dumps({'seconds': dt, 'bytes_in': sum(len(m[2]) for m in msgs), 'messages': len(msgs),
                      'file_bytes': os.path.getsize(out)}))


if __name__ == '__main__':
    main(*sys.argv[1:5])
