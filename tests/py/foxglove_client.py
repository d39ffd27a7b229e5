"""A Foxglove WebSocket protocol client (ws-protocol v1) that checks a server's channels.

Connects with subprotocol foxglove.sdk.v1 (or foxglove.websocket.v1), collects the advertised channels until every
topic given is there, subscribes to them, and decodes the first message of each with rosbags
from the channel's own ros2msg schema (an independent CDR decoder). Prints one JSON object:
{"server": name, "channels": {topic: {...}}, "messages": {topic: decoded fields}}.

    python foxglove_client.py ws://127.0.0.1:8766 /clock /temperature/x_left ... [--timeout 30]
"""
import argparse
import asyncio
import json
import struct
import sys
import time

import websockets
from foxglove_websocket.types import BinaryOpcode
from rosbags.typesys import Stores, get_typestore, get_types_from_msg

SEPARATOR = "=" * 80
# foxglove.sdk.v1 is the foxglove crate's name for ws-protocol v1 (same messages, inline schemas);
# foxglove.websocket.v1 is what older servers and this package's own server speak.
SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]


def register_schema(store, name, schema):
    """Register a ros2msg full definition (type text, then '====' / 'MSG: pkg/Type' blocks)."""
    types = {}
    blocks = schema.split("\n" + SEPARATOR + "\n")
    types.update(get_types_from_msg(blocks[0], name))
    for block in blocks[1:]:
        header, _, text = block.partition("\n")
        assert header.startswith("MSG: "), f"schema block of {name} starts with {header!r}"
        pkg, typ = header[5:].strip().split("/")
        types.update(get_types_from_msg(text, f"{pkg}/msg/{typ}"))
    store.register(types)


def plain(value, depth=0):
    """Decoded message → JSON-able (numpy arrays to lists, nested messages to dicts)."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if hasattr(value, "__dataclass_fields__"):
        return {k: plain(getattr(value, k), depth + 1) for k in value.__dataclass_fields__ if k != "__msgtype__"}
    if isinstance(value, (list, tuple)):
        return [plain(v, depth + 1) for v in value]
    return value


async def run(url, topics, timeout):
    deadline = time.monotonic() + timeout
    out = {"channels": {}, "messages": {}, "server": None}
    store = get_typestore(Stores.EMPTY)
    async with websockets.connect(url, subprotocols=SUBPROTOCOLS, max_size=None) as ws:
        out["subprotocol"] = ws.subprotocol
        channels = {}
        subscribed = {}
        while time.monotonic() < deadline and len(out["messages"]) < len(topics):
            try:
                frame = await asyncio.wait_for(ws.recv(), timeout=max(0.1, deadline - time.monotonic()))
            except asyncio.TimeoutError:
                break
            if isinstance(frame, str):
                msg = json.loads(frame)
                if msg["op"] == "serverInfo":
                    out["server"] = msg["name"]
                elif msg["op"] == "advertise":
                    for ch in msg["channels"]:
                        channels[ch["id"]] = ch
                        out["channels"][ch["topic"]] = {k: ch[k] for k in ("encoding", "schemaName", "schemaEncoding")}
                    new = [ch for ch in channels.values() if ch["topic"] in topics and ch["id"] not in subscribed.values()]
                    if new:
                        subs = []
                        for ch in new:
                            sid = len(subscribed) + 1
                            subscribed[sid] = ch["id"]
                            subs.append({"id": sid, "channelId": ch["id"]})
                            register_schema(store, ch["schemaName"], ch["schema"])
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
                continue
            if frame[0] != BinaryOpcode.MESSAGE_DATA:
                continue
            sid, log_time = struct.unpack_from("<IQ", frame, 1)
            ch = channels[subscribed[sid]]
            if ch["topic"] in out["messages"]:
                continue
            payload = bytes(frame[13:])
            decoded = store.deserialize_cdr(payload, ch["schemaName"])
            out["messages"][ch["topic"]] = {"log_time_ns": log_time, "payload_bytes": len(payload), "fields": plain(decoded)}
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("url")
    ap.add_argument("topics", nargs="+")
    ap.add_argument("--timeout", type=float, default=30.0)
    a = ap.parse_args()
    json.dump(asyncio.run(run(a.url, a.topics, a.timeout)), sys.stdout)
    print()


if __name__ == "__main__":
    main()
