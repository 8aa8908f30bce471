// A recording of the soccer demo read by the MCAP project's own reader (@mcap/core): what
// Foxglove, the mcap tools and other readers will see. Run by run.sh, which sets ARBITER,
// ARBITER_SOURCE and NODE_MODULES.
import { test } from "node:test";
import assert from "node:assert/strict";
import { execFileSync } from "node:child_process";
import { mkdtempSync, readFileSync, rmSync } from "node:fs";
import { createRequire } from "node:module";
import { tmpdir } from "node:os";
import path from "node:path";

const require = createRequire(path.join(process.env.NODE_MODULES, "noop.js"));
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { decompress } = require("fzstd");

const work = mkdtempSync(path.join(tmpdir(), "arbiter-mcap-"));
const recording = path.join(work, "run.mcap");
const trace = path.join(work, "run.jsonl");
execFileSync(process.env.ARBITER, [
  "run", path.join(process.env.ARBITER_SOURCE, "configs/soccer/walk_and_kick.yaml"),
  "--steps", "220", "-q", "--record", recording, "--trace", trace,
]);
const bytes = readFileSync(recording);
const decompressHandlers = { zstd: (data, size) => decompress(data, new Uint8Array(Number(size))) };

async function indexed() {
  return McapIndexedReader.Initialize({
    readable: {
      size: async () => BigInt(bytes.length),
      read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
    },
    decompressHandlers,
  });
}

test.after(() => rmSync(work, { recursive: true, force: true }));

test("the channels are json messages with JSON Schemas", async () => {
  const reader = await indexed();
  const topics = [...reader.channelsById.values()].map((channel) => channel.topic).sort();
  assert.deepEqual(topics, ["/arbiter/header", "/arbiter/inputs", "/arbiter/log", "/arbiter/scene",
                            "/arbiter/step"]);
  for (const channel of reader.channelsById.values()) {
    assert.equal(channel.messageEncoding, "json");
    const schema = reader.schemasById.get(channel.schemaId);
    assert.equal(schema.encoding, "jsonschema");
    assert.equal(JSON.parse(new TextDecoder().decode(schema.data)).type, "object");
  }
  assert.equal(reader.header.profile, "arbiter");
});

test("the statistics and chunk indexes agree with the messages", async () => {
  const reader = await indexed();
  const stats = reader.statistics;
  const counts = new Map();
  let total = 0n;
  for await (const message of reader.readMessages()) {
    counts.set(message.channelId, (counts.get(message.channelId) ?? 0n) + 1n);
    total += 1n;
    assert.ok(message.logTime >= stats.messageStartTime && message.logTime <= stats.messageEndTime);
  }
  assert.equal(stats.messageCount, total);
  // One header, 220 steps, 220 inputs, 220 pictures of the field, the safe pass at the end (which
  // draws nothing), and the two reports logged (the ball kicked, then the goal).
  assert.equal(total, 664n);
  for (const [channel, count] of stats.channelMessageCounts) assert.equal(counts.get(channel), count);
  assert.equal(BigInt(reader.chunkIndexes.length), BigInt(stats.chunkCount));
  assert.ok(reader.chunkIndexes.length >= 1);
  const names = reader.metadataIndexes.map((index) => index.name);
  assert.ok(names.includes("arbiter.config"));
  assert.ok(names.includes("arbiter.summary"));
});

test("the step messages are the trace's step records, with their time", async () => {
  const reader = await indexed();
  const step = [...reader.channelsById.values()].find((c) => c.topic === "/arbiter/step");
  const lines = readFileSync(trace, "utf8").trim().split("\n").slice(1);
  const messages = [];
  for await (const message of reader.readMessages({ topics: ["/arbiter/step"] })) {
    assert.equal(message.channelId, step.id);
    messages.push(new TextDecoder().decode(message.data));
  }
  assert.equal(messages.length, lines.length);
  messages.forEach((text, i) => {
    assert.match(text, /^\{"step": \d+, ("safe": true, )?"t": [0-9.e-]+, "duration": [0-9.e-]+, /);
    assert.equal(text, lines[i]);
  });
});

test("a linear read checks every CRC and ends with the footer", () => {
  const reader = new McapStreamReader({ validateCrcs: true, decompressHandlers });
  reader.append(bytes);
  const types = [];
  for (let record; (record = reader.nextRecord()); ) types.push(record.type);
  assert.ok(types.includes("Message"));
  assert.ok(reader.done());
  assert.equal(types[0], "Header");
  assert.ok(types.includes("DataEnd"));
  assert.equal(types.at(-1), "Footer");
});
