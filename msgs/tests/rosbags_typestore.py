"""The field and constant lists of ROS 2 message types as the `rosbags` type store of a ROS 2
release has them (rosbags ships each release's standard types): the reference the vendored
`.msg` files of msgs/interfaces are compared with (vendored_vs_rosbags.rs).

Usage: rosbags_typestore.py STORE TYPE... (STORE e.g. ROS2_JAZZY, TYPE e.g. sensor_msgs/msg/Image)
Prints {TYPE: {"fields": [[name, type]], "constants": [[name, type, value]]}} with types spelled
as in a .msg file: float64, string<=64, pkg/msg/Type, each with [N], [<=N] or [] for arrays.
"""

import json
import sys

from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.base import Nodetype


def spell(node):
    kind, desc = node
    if kind == Nodetype.BASE:
        name, bound = desc
        return f"{name}<={bound}" if bound else name
    if kind == Nodetype.NAME:
        return desc
    inner, n = desc
    if kind == Nodetype.ARRAY:
        return f"{spell(inner)}[{n}]"
    return f"{spell(inner)}[<={n}]" if n else f"{spell(inner)}[]"


store = get_typestore(getattr(Stores, sys.argv[1]))
out = {}
for t in sys.argv[2:]:
    if t not in store.fielddefs:
        out[t] = None
        continue
    consts, fields = store.fielddefs[t]
    out[t] = {
        "fields": [[name, spell(node)] for name, node in fields],
        "constants": [[name, ty, value] for name, ty, value in consts],
    }
json.dump(out, sys.stdout)
