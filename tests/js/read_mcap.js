// Reads every .mcap file given on the command line the way Foxglove does: @mcap/core's indexed
// reader (summary, chunk indexes, CRCs) with @mcap/support's decompressors, each channel's
// ros2msg schema parsed by @foxglove/rosmsg and its CDR messages decoded by
// @foxglove/rosmsg2-serialization. Prints one JSON line per message:
// {"topic", "schema", "log_time", "publish_time", "message"}; integers beyond 2^53 as strings,
// typed arrays as plain arrays. Exits non-zero on any error.
"use strict";
const fs = require("fs");
const { McapIndexedReader } = require("@mcap/core");
const { loadDecompressHandlers } = require("@mcap/support");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");

function plain(v) {
  if (typeof v === "bigint") return Number.isSafeInteger(Number(v)) ? Number(v) : v.toString();
  if (ArrayBuffer.isView(v)) return Array.from(v, plain);
  if (Array.isArray(v)) return v.map(plain);
  if (v !== null && typeof v === "object") {
    const o = {};
    for (const [k, x] of Object.entries(v)) o[k] = plain(x);
    return o;
  }
  return v;
}

async function main() {
  const decompressHandlers = await loadDecompressHandlers();
  for (const path of process.argv.slice(2)) {
    const bytes = fs.readFileSync(path);
    const readable = {
      size: async () => BigInt(bytes.length),
      read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
    };
    const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    const readers = new Map();
    for (const [id, channel] of reader.channelsById) {
      const schema = reader.schemasById.get(channel.schemaId);
      if (channel.messageEncoding !== "cdr" || schema.encoding !== "ros2msg") {
        throw new Error(`${path}: channel ${channel.topic}: encoding ${channel.messageEncoding}/${schema.encoding}`);
      }
      const text = new TextDecoder().decode(schema.data);
      readers.set(id, { topic: channel.topic, schema: schema.name, reader: new MessageReader(parse(text, { ros2: true })) });
    }
    for await (const m of reader.readMessages()) {
      const r = readers.get(m.channelId);
      const message = r.reader.readMessage(m.data);
      process.stdout.write(JSON.stringify({ topic: r.topic, schema: r.schema, log_time: m.logTime.toString(), publish_time: m.publishTime.toString(), message: plain(message) }) + "\n");
    }
  }
}

main().catch((e) => {
  console.error(e && e.stack ? e.stack : String(e));
  process.exit(1);
});
