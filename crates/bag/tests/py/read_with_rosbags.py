"""Read a rosbag2 bag with the Python `rosbags` library and print every message as JSON.

Types are registered from the message definitions stored in the bag (not from a built-in
store), so the definitions themselves are checked. Output:
{"topics": {name: {"type", "count"}}, "messages": [{"topic", "log_time", "msg"}]}
"""
import sys
from pathlib import Path

from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from common import emit, to_plain


def main(path):
    store = get_typestore(Stores.EMPTY)
    out = {'topics': {}, 'messages': []}
    with Reader(Path(path)) as reader:
        for conn in reader.connections:
            types = get_types_from_msg(conn.msgdef.data, conn.msgtype)
            store.register(types)
            out['topics'][conn.topic] = {'type': conn.msgtype, 'count': conn.msgcount}
        for conn, timestamp, raw in reader.messages():
            msg = store.deserialize_cdr(raw, conn.msgtype)
            out['messages'].append({'topic': conn.topic, 'log_time': timestamp, 'msg': to_plain(msg)})
    emit(out)


if __name__ == '__main__':
    main(sys.argv[1])
