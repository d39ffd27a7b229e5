#!/usr/bin/env python3
"""Decode CDR payloads with mcap-ros2-support, using our full definition text as the schema.

Reads a JSON list of {"type": "pkg/msg/Type", "definition": "...", "cdr": "<hex>"} from stdin
and prints one JSON object per line: the decoded message as nested dicts and lists. This
checks that the ros2msg schema data metrocell writes is what MCAP tools can parse, and that
the CDR decodes to the same values with an independent decoder.
"""

import json
import sys

from mcap_ros2._dynamic import generate_dynamic


def plain(value):
    if isinstance(value, (bytes, bytearray)):
        return list(value)
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if hasattr(value, "__slots__"):
        return {name: plain(getattr(value, name)) for name in value.__slots__}
    if hasattr(value, "tolist"):
        return value.tolist()
    return value


def main():
    for item in json.load(sys.stdin):
        decoders = generate_dynamic(item["type"], item["definition"])
        message = decoders[item["type"]](bytes.fromhex(item["cdr"]))
        print(json.dumps(plain(message)))


if __name__ == "__main__":
    main()
