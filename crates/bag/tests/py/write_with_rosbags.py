"""Write a rosbag2 MCAP bag with the Python `rosbags` writer, using its built-in ROS 2 types.

Usage: write_with_rosbags.py OUT_DIR N. Writes N sensor_msgs/msg/Temperature messages on
/temperature (sec=1000+i, nanosec=i*1000, frame_id=f"probe{i%3}", temperature=20+0.25*i,
variance=0.01*i) at log time 1e18 + i*1e6 ns, and N std_msgs/msg/String on /note
(data=f"note {i}") at log time 1e18 + i*1e6 + 500 ns.
"""
import sys
from pathlib import Path

from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore


def main(out, n):
    store = get_typestore(Stores.ROS2_HUMBLE)
    Temperature = store.types['sensor_msgs/msg/Temperature']
    Header = store.types['std_msgs/msg/Header']
    Time = store.types['builtin_interfaces/msg/Time']
    String = store.types['std_msgs/msg/String']
    with Writer(Path(out), version=9, storage_plugin=StoragePlugin.MCAP) as w:
        ct = w.add_connection('/temperature', Temperature.__msgtype__, typestore=store)
        cn = w.add_connection('/note', String.__msgtype__, typestore=store)
        for i in range(n):
            t0 = 10**18 + i * 10**6
            msg = Temperature(
                header=Header(stamp=Time(sec=1000 + i, nanosec=i * 1000), frame_id=f'probe{i % 3}'),
                temperature=20 + 0.25 * i,
                variance=0.01 * i,
            )
            w.write(ct, t0, store.serialize_cdr(msg, Temperature.__msgtype__))
            w.write(cn, t0 + 500, store.serialize_cdr(String(data=f'note {i}'), String.__msgtype__))


if __name__ == '__main__':
    main(sys.argv[1], int(sys.argv[2]))
