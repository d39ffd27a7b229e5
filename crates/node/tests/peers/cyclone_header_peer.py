"""Cyclone DDS peer for the node runtime's interop test.

Reads one std_msgs/Header from `rt/metrocell_interop/from_rust`, then publishes Headers on
`rt/metrocell_interop/from_cyclone` with frame_id = "cyclone:" + the frame_id it received, until
killed or 20 s pass. Prints `GOT <sec> <nanosec> <frame_id>` when it has read the sample.
"""
import sys
import time
from dataclasses import dataclass

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import int32, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


def main() -> int:
    qos = Qos(Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.Durability.Volatile,
              Policy.History.KeepLast(10))
    dp = DomainParticipant(0)
    reader = DataReader(dp, Topic(dp, "rt/metrocell_interop/from_rust", Header), qos=qos)
    writer = DataWriter(dp, Topic(dp, "rt/metrocell_interop/from_cyclone", Header), qos=qos)
    deadline = time.time() + 20
    got = None
    while time.time() < deadline:
        if got is None:
            for s in reader.take(N=10):
                got = s
                print(f"GOT {s.stamp.sec} {s.stamp.nanosec} {s.frame_id}", flush=True)
                break
        if got is not None:
            writer.write(Header(stamp=Time(sec=got.stamp.sec + 1, nanosec=got.stamp.nanosec),
                                frame_id="cyclone:" + got.frame_id))
        time.sleep(0.05)
    return 0 if got is not None else 1


if __name__ == "__main__":
    sys.exit(main())
