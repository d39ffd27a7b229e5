#!/usr/bin/env python3
"""A real Cyclone DDS peer speaking ROS 2 types, for metrocell's interop tests.

The DDS types are built at run time from the same .msg files metrocell generates
its Rust types from (msgs/msg and msgs/interfaces), so every metrocell type is
available here without a ROS install. Only the CDR encoding and the DDS wire
protocol come from Cyclone DDS, which is the point of the test.

  ros2_peer.py listen  --topic /t --type pkg/msg/T [--count N] [--timeout S]
      prints each received sample as one JSON line on stdout.
  ros2_peer.py publish --topic /t --type pkg/msg/T --json '{...}' [--count N] [--rate HZ]
      publishes the sample (missing fields are zero/empty) N times.
  ros2_peer.py encode  --type pkg/msg/T --json '{...}'
      prints the CDR encoding (with encapsulation header) as hex; opens no participant.

--msg-dir DIR (repeatable) adds the types of DIR/<pkg>/msg/*.msg, e.g. a package metrocell
does not ship, to test how metrocell handles a type it does not know.

Topic /t is the DDS topic rt/t and type pkg/msg/T the DDS type pkg::msg::dds_::T_,
as ROS 2 maps them. QoS: reliable, volatile, keep last 10 (the ROS 2 default).
"""
import argparse
import dataclasses
import json
import os
import re
import sys
import time
import types as pytypes

import cyclonedds.idl.types as t
from cyclonedds.idl import IdlStruct

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PRIMITIVES = {
    "bool": bool, "byte": t.uint8, "char": t.uint8,
    "int8": t.int8, "uint8": t.uint8, "int16": t.int16, "uint16": t.uint16,
    "int32": t.int32, "uint32": t.uint32, "int64": t.int64, "uint64": t.uint64,
    "float32": t.float32, "float64": t.float64, "string": str, "wstring": str,
}
FIELD = re.compile(r"^(?P<type>[A-Za-z0-9_/]+)(?P<sbound><=\d+)?(?P<array>\[(?:<=)?\d*\])?\s+(?P<name>[a-z][a-z0-9_]*)(\s+.*)?$")


def msg_paths(extra_dirs=()):
    """Map 'pkg/Type' -> .msg path for every interface metrocell ships (and those of extra_dirs)."""
    found = {}
    for d in [os.path.join(ROOT, "msgs", "msg")]:
        for f in os.listdir(d):
            if f.endswith(".msg"):
                found["metrocell_msgs/" + f[:-4]] = os.path.join(d, f)
    for idir in [os.path.join(ROOT, "msgs", "interfaces"), *extra_dirs]:
        for pkg in os.listdir(idir):
            mdir = os.path.join(idir, pkg, "msg")
            if not os.path.isdir(mdir):
                continue
            for f in os.listdir(mdir):
                if f.endswith(".msg"):
                    found[pkg + "/" + f[:-4]] = os.path.join(mdir, f)
    return found


class Types:
    """Builds Cyclone IdlStruct classes for ROS types on demand."""

    def __init__(self, extra_dirs=()):
        self.paths = msg_paths(extra_dirs)
        self.classes = {}
        self.fields = {}

    def resolve(self, name, pkg):
        if "/" in name:
            parts = name.split("/")
            return parts[0] + "/" + parts[-1]
        if name == "Header":
            return "std_msgs/Header"
        return pkg + "/" + name

    def get(self, full):
        full = self.resolve(full, None)
        if full in self.classes:
            return self.classes[full]
        pkg, name = full.split("/")
        ann, fields = {}, []
        with open(self.paths[full]) as fh:
            for raw in fh:
                line = raw.split("#", 1)[0].strip()
                if not line:
                    continue
                m = FIELD.match(line)
                if m is None or "=" in line.split()[1]:
                    continue  # constants carry no wire data
                base, array, fname = m.group("type"), m.group("array"), m.group("name")
                if base in PRIMITIVES:
                    ty = PRIMITIVES[base]
                    if base in ("string", "wstring") and m.group("sbound"):
                        ty = t.bounded_str[int(m.group("sbound")[2:])]
                    nested = None
                else:
                    nested = self.resolve(base, pkg)
                    ty = self.get(nested)
                if array:
                    inner = array[1:-1]
                    if inner == "":
                        ty = t.sequence[ty]
                    elif inner.startswith("<="):
                        ty = t.sequence[ty, int(inner[2:])]
                    else:
                        ty = t.array[ty, int(inner)]
                ann[fname] = ty
                fields.append((fname, base, array, nested))

        if not ann:
            # rosidl gives a message without fields one uint8 member on the wire (as rosbags does).
            ann["structure_needs_at_least_one_member"] = t.uint8
            fields.append(("structure_needs_at_least_one_member", "uint8", None, None))

        def body(ns):
            ns["__annotations__"] = ann
        cls = pytypes.new_class(name, (IdlStruct,), {"typename": f"{pkg}::msg::dds_::{name}_"}, body)
        cls = dataclasses.dataclass(cls)
        self.classes[full] = cls
        self.fields[full] = fields
        return cls

    def from_json(self, full, obj):
        """Build a sample of type `full` from a JSON object; missing fields are zero."""
        full = self.resolve(full, None)
        cls = self.get(full)
        kwargs = {}
        for fname, base, array, nested in self.fields[full]:
            v = obj.get(fname) if obj else None
            kwargs[fname] = self.value(base, array, nested, v)
        return cls(**kwargs)

    def value(self, base, array, nested, v):
        if array:
            inner = array[1:-1]
            if inner and not inner.startswith("<="):
                n = int(inner)
                v = list(v) if v is not None else [None] * n
                return [self.value(base, None, nested, x) for x in v]
            return [self.value(base, None, nested, x) for x in (v or [])]
        if nested:
            return self.from_json(nested, v or {})
        if base in ("string", "wstring"):
            return "" if v is None else str(v)
        if base == "bool":
            return bool(v)
        if base.startswith("float"):
            return float(v or 0.0)
        return int(v or 0)


def to_json(sample):
    if dataclasses.is_dataclass(sample):
        return {f.name: to_json(getattr(sample, f.name)) for f in dataclasses.fields(sample)}
    if isinstance(sample, (list, tuple)):
        return [to_json(x) for x in sample]
    if isinstance(sample, (bytes, bytearray)):
        return list(sample)
    return sample


def dds_topic(name):
    return "rt" + (name if name.startswith("/") else "/" + name)


def qos():
    from cyclonedds.core import Policy, Qos
    from cyclonedds.util import duration
    return Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.Durability.Volatile,
               Policy.History.KeepLast(10))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["listen", "publish", "encode"])
    ap.add_argument("--topic")
    ap.add_argument("--type", required=True)
    ap.add_argument("--json", default="{}")
    ap.add_argument("--count", type=int, default=1)
    ap.add_argument("--settle", type=float, default=3.0,
                    help="publish: seconds to wait for readers where the binding cannot list them")
    ap.add_argument("--rate", type=float, default=10.0)
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--domain", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", "0")))
    ap.add_argument("--msg-dir", action="append", default=[])
    a = ap.parse_args()
    types = Types(a.msg_dir)
    cls = types.get(a.type)
    if a.mode == "encode":
        print(types.from_json(a.type, json.loads(a.json)).serialize().hex())
        return 0
    if os.environ.get("METROCELL_ISOLATED") != "1":
        print("ros2_peer.py: refusing to open a DDS participant outside a private network namespace; "
              "run through tests/isolated", file=sys.stderr)
        return 2
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    dp = DomainParticipant(a.domain)
    topic = Topic(dp, dds_topic(a.topic), cls, qos=qos())
    if a.mode == "publish":
        writer = DataWriter(dp, topic, qos=qos())
        sample = types.from_json(a.type, json.loads(a.json))
        deadline = time.time() + a.timeout
        # wait for a matched reader so nothing is published into the void (the older binding
        # built against Debian's Cyclone DDS for the secured peer has no matched-list call: there a
        # fixed settle time, --settle, stands in)
        matched = getattr(writer, "get_matched_subscriptions", None)
        if matched is None:
            time.sleep(min(a.settle, a.timeout))
        while matched is not None and matched() == [] and time.time() < deadline:
            time.sleep(0.05)
        for _ in range(a.count):
            writer.write(sample)
            time.sleep(1.0 / a.rate)
        time.sleep(0.5)
        return 0
    reader = DataReader(dp, topic, qos=qos())
    got, deadline = 0, time.time() + a.timeout
    print("ready", file=sys.stderr, flush=True)
    while got < a.count and time.time() < deadline:
        for s in reader.take(N=100):
            print(json.dumps(to_json(s)), flush=True)
            got += 1
        time.sleep(0.01)
    return 0 if got >= a.count else 1


if __name__ == "__main__":
    sys.exit(main())
