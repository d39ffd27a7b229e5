"""Read .mcap files with `mcap` + `mcap-ros2-support` and print every message as JSON.

Usage: read_with_mcap.py FILE.mcap [FILE.mcap ...]. Output as read_with_rosbags.py, plus the
header profile of each file.
"""
import sys

from mcap.reader import make_reader
from mcap_ros2.reader import read_ros2_messages

from common import emit, to_plain


def main(paths):
    out = {'topics': {}, 'messages': [], 'profiles': []}
    for path in paths:
        with open(path, 'rb') as f:
            out['profiles'].append(make_reader(f).get_header().profile)
        for m in read_ros2_messages(path):
            t = out['topics'].setdefault(m.channel.topic, {'type': m.schema.name, 'count': 0})
            t['count'] += 1
            out['messages'].append({
                'topic': m.channel.topic,
                'log_time': m.log_time_ns,
                'msg': to_plain(m.ros_msg),
            })
    emit(out)


if __name__ == '__main__':
    main(sys.argv[1:])
