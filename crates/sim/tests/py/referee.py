"""Read a simulator bag with two independent peers and print a JSON summary.

Usage: referee.py BAG_DIR

* `rosbags` (rosbag2 reader with its own CDR decoder, from metadata.yaml and the MCAP file);
* `mcap` + `mcap-ros2-support` (decodes the MCAP file from its embedded ros2msg schemas).

Prints {"rosbags": {topic: count}, "mcap": {topic: count}, "tracker": [first OK tracker
measurement fields], "beam_breaks": n, "temperature": [first x_left reading],
"joint_state": [first actual positions], "clock_ns": [first two clock stamps]}.
"""
import glob
import json
import math
import sys
from pathlib import Path

from mcap_ros2.reader import read_ros2_messages
from rosbags.highlevel import AnyReader


def main(bag):
    out = {'rosbags': {}, 'mcap': {}, 'beam_breaks': 0, 'clock_ns': []}
    with AnyReader([Path(bag)]) as reader:
        for conn, _t, raw in reader.messages():
            out['rosbags'][conn.topic] = out['rosbags'].get(conn.topic, 0) + 1
            if conn.topic == '/tracker/measurements':
                m = reader.deserialize(raw, conn.msgtype)
                if m.status == 1:
                    out['beam_breaks'] += 1
                    assert math.isnan(m.point.x), 'beam break must carry a NaN point'
                elif 'tracker' not in out:
                    out['tracker'] = {'range': m.range, 'cov0': float(m.covariance[0]),
                                      'humidity': m.air_humidity, 'index': m.refractive_index,
                                      'frame': m.header.frame_id,
                                      'stamp_ns': m.header.stamp.sec * 10**9 + m.header.stamp.nanosec}
    for path in sorted(glob.glob(str(Path(bag) / '*.mcap'))):
        for m in read_ros2_messages(path):
            topic = m.channel.topic
            out['mcap'][topic] = out['mcap'].get(topic, 0) + 1
            if topic == '/temperature/x_left' and 'temperature' not in out:
                out['temperature'] = {'value': m.ros_msg.temperature, 'variance': m.ros_msg.variance,
                                      'frame': m.ros_msg.header.frame_id}
            if topic == '/machine/joint_states' and 'joint_state' not in out:
                out['joint_state'] = {'name': list(m.ros_msg.name), 'position': list(m.ros_msg.position)}
            if topic == '/clock' and len(out['clock_ns']) < 2:
                c = m.ros_msg.clock
                out['clock_ns'].append(c.sec * 10**9 + c.nanosec)
    json.dump(out, sys.stdout)


if __name__ == '__main__':
    main(sys.argv[1])
