#!/usr/bin/env python3
"""Field and constant lists of ROS 2 Jazzy message types from the rosbags type store — an
independent source (rosbags ships its own copy of the Jazzy definitions) for checking the
vendored .msg files. Reads a JSON list of 'pkg/msg/Type' on stdin and prints one JSON object:
{type: {"fields": [[name, "type text"]], "constants": [[name, type, value]]}}, with type texts
written as in .msg files ('string<=8', 'pkg/Type[<=1]', 'float64[9]'); a type the store lacks
maps to null. Opens no DDS participant."""
import json
import sys

from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.base import Nodetype


def text(desc):
    kind, detail = desc
    if kind == Nodetype.BASE:
        name, bound = detail
        return f"{name}<={bound}" if bound else name
    if kind == Nodetype.NAME:
        pkg, _, name = detail.split("/")
        return f"{pkg}/{name}"
    inner, n = detail
    if kind == Nodetype.ARRAY:
        return f"{text(inner)}[{n}]"
    if kind == Nodetype.SEQUENCE:
        return f"{text(inner)}[<={n}]" if n else f"{text(inner)}[]"
    raise ValueError(f"unknown node type {kind}")


def main():
    store = get_typestore(Stores.ROS2_JAZZY)
    out = {}
    for ty in json.load(sys.stdin):
        if ty not in store.fielddefs:
            out[ty] = None
            continue
        consts, fields = store.fielddefs[ty]
        out[ty] = {
            "fields": [[n, text(d)] for n, d in fields],
            "constants": [[n, t, v] for n, t, v in consts],
        }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
