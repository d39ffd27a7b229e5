"""Write a rosbag2 MCAP bag with the Python `rosbags` writer (metadata version 9), standard types.

Usage: write_rosbags_std_types.py OUT_DIR N

* /rb/latched  std_msgs/msg/String, one message data="cell model v3" at log time T0,
  offered QoS reliable + transient_local, keep_last 1 (a latched topic).
* /rb/temperature  sensor_msgs/msg/Temperature, N messages i = 0..N-1 at T0 + 1 s + i * 20 ms:
  header.stamp = (1000 + i, i * 1000), frame_id = f"probe{i % 3}", temperature = 20 + 0.25 * i,
  variance = 0.01 * i; offered QoS reliable + volatile.
* /rb/point  geometry_msgs/msg/PointStamped, N messages at T0 + 1 s + i * 20 ms + 5 ms:
  header.stamp = (2000 + i, 7), frame_id = "tracker", point = (0.1 * i, -0.2 * i, 1e-6 * i);
  offered QoS reliable + volatile.

T0 = 1.7e18 ns. The rosbags writer stores QoS in v9 form (names such as `transient_local`).
"""
import sys
from pathlib import Path

from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

T0 = 1_700_000_000_000_000_000
INF = QosTime(sec=9223372036, nsec=854775807)


def qos(durability, depth):
    return Qos(QosHistory.KEEP_LAST, depth, QosReliability.RELIABLE, durability, INF, INF,
               QosLiveliness.AUTOMATIC, INF, False)


def main(out, n):
    store = get_typestore(Stores.ROS2_HUMBLE)
    T = store.types
    Header, Time = T['std_msgs/msg/Header'], T['builtin_interfaces/msg/Time']
    Temperature, PointStamped, Point, String = (T['sensor_msgs/msg/Temperature'], T['geometry_msgs/msg/PointStamped'],
                                                 T['geometry_msgs/msg/Point'], T['std_msgs/msg/String'])
    with Writer(Path(out), version=9, storage_plugin=StoragePlugin.MCAP) as w:
        cl = w.add_connection('/rb/latched', String.__msgtype__, typestore=store,
                              offered_qos_profiles=[qos(QosDurability.TRANSIENT_LOCAL, 1)])
        ct = w.add_connection('/rb/temperature', Temperature.__msgtype__, typestore=store,
                              offered_qos_profiles=[qos(QosDurability.VOLATILE, 10)])
        cp = w.add_connection('/rb/point', PointStamped.__msgtype__, typestore=store,
                              offered_qos_profiles=[qos(QosDurability.VOLATILE, 10)])
        w.write(cl, T0, store.serialize_cdr(String(data='cell model v3'), String.__msgtype__))
        for i in range(n):
            t = T0 + 10**9 + i * 20_000_000
            temp = Temperature(header=Header(stamp=Time(sec=1000 + i, nanosec=i * 1000), frame_id=f'probe{i % 3}'),
                               temperature=20 + 0.25 * i, variance=0.01 * i)
            w.write(ct, t, store.serialize_cdr(temp, Temperature.__msgtype__))
            pt = PointStamped(header=Header(stamp=Time(sec=2000 + i, nanosec=7), frame_id='tracker'),
                              point=Point(x=0.1 * i, y=-0.2 * i, z=1e-6 * i))
            w.write(cp, t + 5_000_000, store.serialize_cdr(pt, PointStamped.__msgtype__))


if __name__ == '__main__':
    main(sys.argv[1], int(sys.argv[2]))
