// Recordings of the demos as Foxglove and Lichtblick open them: every channel's JSON Schema is
// one Lichtblick's parser accepts (lichtblick_rules.mjs) and names the config's behaviours,
// actuators and state machines; every message validates against its channel's schema (ajv);
// log times are the run's own clock; what the run reported is on the foxglove.Log channel. Run
// by run.sh, which sets ARBITER, ARBITER_SOURCE and NODE_MODULES.
import { test } from "node:test";
import assert from "node:assert/strict";
import { execFileSync, spawn } from "node:child_process";
import { copyFileSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import { createRequire } from "node:module";
import { tmpdir } from "node:os";
import path from "node:path";
import { lichtblickFields } from "./lichtblick_rules.mjs";

const require = createRequire(path.join(process.env.NODE_MODULES, "noop.js"));
const { McapIndexedReader } = require("@mcap/core");
const { decompress } = require("fzstd");
const Ajv2020 = require("ajv/dist/2020").default;
const foxgloveSchemas = require("@foxglove/schemas/jsonschema");

const work = mkdtempSync(path.join(tmpdir(), "arbiter-foxglove-"));
test.after(() => rmSync(work, { recursive: true, force: true }));
const decoder = new TextDecoder();

// Records `config` (under configs/) with `args`; the recording and its trace, read whole.
async function record(name, config, args) {
  const file = path.join(work, `${name}.mcap`);
  const trace = path.join(work, `${name}.jsonl`);
  execFileSync(process.env.ARBITER, [
    "run", path.join(process.env.ARBITER_SOURCE, "configs", config), "-q",
    "--record", file, "--trace", trace, ...args,
  ]);
  return read(file, trace);
}

async function read(file, trace) {
  const bytes = readFileSync(file);
  const reader = await McapIndexedReader.Initialize({
    readable: {
      size: async () => BigInt(bytes.length),
      read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
    },
    decompressHandlers: { zstd: (data, size) => decompress(data, new Uint8Array(Number(size))) },
  });
  const channels = new Map();  // id -> {topic, schemaName, schema}
  for (const channel of reader.channelsById.values()) {
    const schema = reader.schemasById.get(channel.schemaId);
    assert.equal(channel.messageEncoding, "json");
    assert.equal(schema.encoding, "jsonschema");
    channels.set(channel.id, {
      topic: channel.topic, schemaName: schema.name, schema: JSON.parse(decoder.decode(schema.data)),
    });
  }
  const messages = [];
  for await (const message of reader.readMessages()) {
    messages.push({
      topic: channels.get(message.channelId).topic, channelId: message.channelId,
      logTime: message.logTime, publishTime: message.publishTime,
      text: decoder.decode(message.data), data: JSON.parse(decoder.decode(message.data)),
    });
  }
  let rateHz;
  for await (const metadata of reader.readMetadata({ name: "arbiter.config" })) {
    rateHz = Number(metadata.metadata.get("rate_hz"));
  }
  return { channels, messages, rateHz, of: (topic) => messages.filter((m) => m.topic === topic) };
}

const demos = {
  soccer: await record("soccer", "soccer/walk_and_kick.yaml", ["--steps", "220"]),
  goalie: await record("goalie", "soccer/goalie.yaml", []),  // its config's 240 steps
};

test("the rules restated from Lichtblick's parser reject what it rejects", () => {
  const ok = { type: "object", properties: { a: { type: "integer", const: 1 } } };
  assert.equal(lichtblickFields(ok, "X").get("a"), "int32");
  for (const property of [
    { const: 1 },                                   // no type
    { enum: ["input", "output"] },                  // no type
    { type: ["string", "null"] },                   // a list of types
    {},                                             // a value of any type
    { type: "array" },                              // items of no type
    { type: "array", items: { type: "array", items: { type: "number" } } },
    { oneOf: [{ type: "string" }, { type: "null" }] },
  ]) {
    assert.throws(() => lichtblickFields({ type: "object", properties: { a: property } }, "X"),
                  undefined, JSON.stringify(property));
  }
  assert.throws(() => lichtblickFields({ type: "array" }, "X"), /Expected "type": "object"/);
});

for (const [demo, run] of Object.entries(demos)) {
  test(`${demo}: every schema passes Lichtblick's parser`, () => {
    const topics = [...run.channels.values()].map((c) => `${c.topic} ${c.schemaName}`).sort();
    assert.deepEqual(topics, ["/arbiter/header arbiter.Header", "/arbiter/inputs arbiter.Inputs",
                              "/arbiter/log foxglove.Log", "/arbiter/scene foxglove.SceneUpdate",
                              "/arbiter/step arbiter.Step"]);
    for (const channel of run.channels.values()) {
      assert.doesNotThrow(() => lichtblickFields(channel.schema, channel.schemaName), channel.topic);
    }
  });

  test(`${demo}: every message validates against its channel's schema`, () => {
    // strictRequired would refuse a machine's required `state`, which is declared by
    // patternProperties, out of Lichtblick's sight, since it may be null.
    const ajv = new Ajv2020({ strict: true, strictRequired: false, allErrors: true });
    const validators = new Map();
    for (const [id, channel] of run.channels) validators.set(id, ajv.compile(channel.schema));
    const counts = {};
    for (const message of run.messages) {
      const validate = validators.get(message.channelId);
      assert.ok(validate(message.data),
                `${message.topic}: ${ajv.errorsText(validate.errors)} in ${message.text.slice(0, 300)}`);
      counts[message.topic] = (counts[message.topic] ?? 0) + 1;
    }
    // The step schema is closed: a field it forgets to declare fails the record.
    const step = [...run.channels.values()].find((c) => c.topic === "/arbiter/step");
    const extra = { ...run.of("/arbiter/step")[0].data, unknown: 1 };
    assert.equal(ajv.validate(step.schema, extra), false);
    assert.ok(counts["/arbiter/step"] >= 220 && counts["/arbiter/inputs"] >= 220, JSON.stringify(counts));
  });

  test(`${demo}: the step messages are the trace's lines`, () => {
    const lines = readFileSync(path.join(work, `${demo}.jsonl`), "utf8").trim().split("\n").slice(1);
    assert.deepEqual(run.of("/arbiter/step").map((m) => m.text), lines);
  });

  test(`${demo}: log times are the simulated time, publish times the wall clock`, () => {
    const steps = run.of("/arbiter/step").filter((m) => !m.data.safe);
    assert.equal(run.rateHz, 15);
    const start = run.of("/arbiter/header")[0].logTime;
    for (const m of steps) {
      const expected = start + BigInt(Math.floor((m.data.step * 1e9) / run.rateHz));
      assert.ok(m.logTime - expected <= 1n && expected - m.logTime <= 1n,
                `step ${m.data.step}: ${m.logTime - start} ns after the start`);
    }
    const span = Number(steps.at(-1).logTime - steps[0].logTime) / 1e9;
    const simulated = (steps.at(-1).data.step - steps[0].data.step) / run.rateHz;
    assert.ok(Math.abs(span - simulated) < 1e-6, `spans ${span} s, simulated ${simulated} s`);
    // Flat out, the run took a fraction of that: the wall clock says so.
    const wall = Number(steps.at(-1).publishTime - steps[0].publishTime) / 1e9;
    assert.ok(wall < span / 2, `publish times span ${wall} s`);
    console.log(`${demo}: ${steps.length} steps at ${run.rateHz} Hz: log times span ${span.toFixed(3)} s, ` +
                `publish times ${wall.toFixed(4)} s`);
  });

  test(`${demo}: what the run reported is on the log, at its step's time`, () => {
    const reported = [];
    for (const m of run.of("/arbiter/step")) {
      for (const r of m.data.reported ?? []) reported.push({ ...r, time: m.logTime });
    }
    assert.ok(reported.length > 0);
    const logs = run.of("/arbiter/log");
    assert.deepEqual(
      logs.map((m) => ({ by: m.data.name, text: m.data.message, time: m.logTime })), reported);
    for (const m of logs) {
      assert.equal(m.data.level, 2);  // INFO
      assert.equal(BigInt(m.data.timestamp.sec) * 1000000000n + BigInt(m.data.timestamp.nsec), m.logTime);
    }
  });
}

// What a viewer shows of the "field" frame after each scene message, with the step it was drawn
// in: the message's deletions and entities applied to what the messages before it left (the
// still and the moving entity), the field's primitives gathered into one entity-like object.
function fieldScenes(run) {
  const stepAt = new Map(run.of("/arbiter/step").map((m) => [m.logTime, m.data.step]));
  const shown = new Map();
  return run.of("/arbiter/scene").map((m) => {
    for (const d of m.data.deletions) {
      if (d.type === 1) shown.clear();
      else shown.delete(d.id);
    }
    for (const e of m.data.entities) shown.set(e.id, e);
    const field = [...shown.values()].filter((e) => e.frame_id === "field");
    const entity = field.length === 0 ? undefined : { frame_id: "field" };
    for (const kind of ["arrows", "cylinders", "lines", "texts"]) {
      if (entity) entity[kind] = field.flatMap((e) => e[kind]);
    }
    return { step: stepAt.get(m.logTime), entity, data: m.data, logTime: m.logTime };
  });
}

function ballOf(entity) {
  // The ball: the small filled disc.
  const ball = entity.cylinders.find((c) => c.size.x < 0.2 && c.color.g < 0.6);
  return ball.pose.position;
}

for (const [demo, run] of Object.entries(demos)) {
  test(`${demo}: the scene is Foxglove's SceneUpdate, every message valid against @foxglove/schemas`, () => {
    const scene = [...run.channels.values()].find((c) => c.topic === "/arbiter/scene");
    // The channel's schema is Foxglove's own, as the package publishes it.
    assert.deepEqual(scene.schema, foxgloveSchemas.SceneUpdate);
    const ajv = new Ajv2020({ strict: false, allErrors: true });
    const validate = ajv.compile(foxgloveSchemas.SceneUpdate);
    const scenes = fieldScenes(run);
    assert.equal(scenes.length, run.of("/arbiter/step").filter((m) => !m.data.safe).length);
    for (const { data } of scenes) {
      assert.ok(validate(data), `${ajv.errorsText(validate.errors)}`);
    }
  });

  test(`${demo}: a scene message carries what changed, the whole picture at least once a second`, () => {
    const scenes = fieldScenes(run);
    const whole = (s) => s.data.deletions.some((d) => d.type === 1);
    assert.ok(whole(scenes[0]), "the first message is the whole picture");
    // A viewer that seeks shows the last message before the time it seeks to: a whole picture
    // is never more than a second of log time behind.
    let wholeAt = scenes[0].logTime;
    for (const s of scenes) {
      if (whole(s)) wholeAt = s.logTime;
      assert.ok(s.logTime - wholeAt <= 1000000000n, `step ${s.step}: no whole picture for over 1 s`);
      // A frame's entities: what does not move, and what does.
      for (const e of s.data.entities) assert.match(e.id, new RegExp(`^${e.frame_id}/(still|moving)$`));
      // Between whole pictures only what moves is written (nothing, when nothing does).
      if (!whole(s)) assert.ok(s.data.entities.every((e) => e.id === "field/moving"), `step ${s.step}`);
    }
    // The field's outline, which does not move, is written only with the whole pictures.
    const outlined = scenes.filter((s) => s.data.entities.some((e) => e.lines.some((l) => l.points.length === 4 && l.type === 1)));
    assert.deepEqual(outlined.map((s) => s.step), scenes.filter(whole).map((s) => s.step));
    assert.ok(outlined.length < scenes.length / 10, `${outlined.length} of ${scenes.length}`);
  });

  test(`${demo}: the scene draws the field, the goals, the robot and the ball, which moves`, () => {
    const scenes = fieldScenes(run);
    for (const { step, entity } of scenes) {
      assert.ok(entity, `step ${step}: no field`);
      assert.equal(entity.frame_id, "field");
      const outline = entity.lines.find((l) => l.type === 1 && l.points.length === 4);
      assert.deepEqual(outline.points.map((p) => [p.x, p.y]), [[-4.5, -3], [4.5, -3], [4.5, 3], [-4.5, 3]]);
      const goals = entity.lines.filter((l) => l.type === 0 && l.points.length === 4);
      assert.deepEqual(goals.map((g) => g.points[0].x).sort(), [-4.5, 4.5]);
      assert.ok(entity.arrows.length >= 1, `step ${step}: no heading`);
      assert.ok(entity.cylinders.length >= 2, `step ${step}: robot and ball`);
    }
    const balls = scenes.map((s) => ballOf(s.entity));
    const moved = Math.hypot(balls.at(-1).x - balls[0].x, balls.at(-1).y - balls[0].y);
    assert.ok(moved > 0.5, `the ball moved ${moved} m`);
    console.log(`${demo}: ${scenes.length} scene messages, the ball moved ${moved.toFixed(2)} m`);
  });
}

test("soccer: the scene shows the kick in the step the trace reports it", () => {
  const kicked = demos.soccer.of("/arbiter/step")
    .filter((m) => (m.data.reported ?? []).some((r) => r.text === "ball kicked")).map((m) => m.data.step);
  assert.ok(kicked.length > 0);
  const texts = fieldScenes(demos.soccer).filter((s) => s.entity.texts.some((t) => t.text === "kick"));
  assert.deepEqual(texts.map((s) => s.step), kicked);
  // The ball rolls away from the kick: an arrow from the ball along its motion.
  const after = fieldScenes(demos.soccer).find((s) => s.step === kicked[0] + 1);
  assert.ok(after.entity.arrows.length >= 2);
});

test("goalie: the scene shows the shot and the goalie down after its dive", () => {
  const scenes = fieldScenes(demos.goalie);
  const shot = scenes.find((s) => s.entity.texts.some((t) => t.text === "shot"));
  assert.ok(shot, "no shot drawn");
  // The goalie down: its body a thick line from its centre.
  assert.ok(scenes.some((s) => s.step > shot.step && s.entity.lines.some((l) => l.thickness === 0.2)));
  // While it walks to its pose (walk_to_pose), the pose it walks to: a ring of 0.15 m.
  const walking = demos.goalie.of("/arbiter/step")
    .filter((m) => m.data.controllers.goalie.state === "walk_to_pose").map((m) => m.data.step);
  assert.ok(walking.length > 0);
  const ring = (l) => {
    if (l.type !== 1 || l.points.length !== 32) return false;
    const cx = l.points.reduce((a, p) => a + p.x, 0) / 32, cy = l.points.reduce((a, p) => a + p.y, 0) / 32;
    return Math.abs(Math.hypot(l.points[0].x - cx, l.points[0].y - cy) - 0.15) < 1e-5;
  };
  const targeted = scenes.filter((s) => s.entity.lines.some(ring)).map((s) => s.step);
  assert.deepEqual(targeted, walking);
});

test("soccer: the step schema names each behaviour, actuator and their types", () => {
  const step = [...demos.soccer.channels.values()].find((c) => c.topic === "/arbiter/step");
  const fields = lichtblickFields(step.schema, step.schemaName);
  // The documented plot path, /arbiter/step.layers.control.kick_ball.activation, resolves.
  assert.equal(fields.get("layers.control.kick_ball.activation"), "float64");
  assert.equal(fields.get("layers.control.kick_ball.requested"), "float64");
  assert.equal(fields.get("layers.control.kick_ball.active"), "bool");
  assert.equal(fields.get("layers.control.search_for_ball.inhibited_by[]"), "string");
  assert.equal(fields.get("actuators.head_angle.value"), "float64");
  assert.equal(fields.get("actuators.gait_velocity.value[]"), "float64");
  assert.equal(fields.get("actuators.kick.value"), "bool");
  assert.equal(fields.get("reported[].text"), "string");
  const inputs = [...demos.soccer.channels.values()].find((c) => c.topic === "/arbiter/inputs");
  assert.equal(lichtblickFields(inputs.schema, inputs.schemaName).get("inputs.ball_visible.value"), "bool");
});

test("goalie: the step schema names its state machine and its states' params", () => {
  const step = [...demos.goalie.channels.values()].find((c) => c.topic === "/arbiter/step");
  const fields = lichtblickFields(step.schema, step.schemaName);
  assert.equal(fields.get("layers.control.goalie.activation"), "float64");
  assert.equal(fields.get("actuators.dive.value"), "int32");
  assert.equal(fields.get("controllers.goalie.cycle"), "uint32");
  assert.equal(fields.get("controllers.goalie.status"), "string");
  assert.equal(fields.get("controllers.goalie.queue[]"), "string");
  assert.equal(fields.get("controllers.goalie.params.x"), "float64");
  assert.equal(fields.get("controllers.goalie.ended[].cause"), "string");
  // The states' names are the queue's only values.
  const goalie = step.schema.properties.controllers.properties.goalie;
  assert.deepEqual(goalie.properties.queue.items.enum.sort(),
                   ["dive", "monitor_ball", "wait_for_button", "walk_to_pose"]);
});

test("a paced run logs its steps on the wall clock", async () => {
  const run = await record("paced", "soccer/walk_and_kick.yaml", ["--steps", "6", "--realtime"]);
  const steps = run.of("/arbiter/step").filter((m) => !m.data.safe);
  for (const m of steps) assert.equal(m.logTime, m.publishTime);
  const span = Number(steps.at(-1).logTime - steps[0].logTime) / 1e9;
  // Five periods of 1/15 s at least, as the run kept them (more on a busy machine).
  assert.ok(span > 0.3 && span < 5, `spans ${span} s`);
});

test("the config's load warnings are on the log, with their file and line", async () => {
  const run = await record("warned", "../tests/data/invalid/warn_duplicate_inhibition.yaml",
                           ["--steps", "3"]);
  const start = run.of("/arbiter/header")[0].logTime;
  const warnings = run.of("/arbiter/log").filter((m) => m.data.name === "config");
  assert.deepEqual(warnings.map((m) => [m.data.level, path.basename(m.data.file), m.data.line]),
                   [[3, "warn_duplicate_inhibition.yaml", 12], [3, "warn_duplicate_inhibition.yaml", 13],
                    [3, "warn_duplicate_inhibition.yaml", 14]]);
  assert.match(warnings[0].data.message,
               /^warning\[duplicate-inhibition\]: duplicate inhibition kick_ball => go_behind_ball: applied once\nnote: first declared at /);
  for (const m of warnings) assert.equal(m.logTime, start);
  const log = [...run.channels.values()].find((c) => c.topic === "/arbiter/log");
  const validate = new Ajv2020({ strict: true }).compile(log.schema);
  for (const m of warnings) assert.ok(validate(m.data), JSON.stringify(validate.errors));
});

test("a hot reload that adds a behaviour adds a step channel with its schema", async () => {
  const config = path.join(work, "robot.yaml");
  const file = path.join(work, "reloaded.mcap");
  copyFileSync(path.join(process.env.ARBITER_SOURCE, "configs/soccer/walk_and_kick.yaml"), config);
  const run = spawn(process.env.ARBITER, ["run", config, "--watch", "--realtime", "--record", file]);
  let out = "";
  run.stdout.on("data", (data) => { out += data; });
  const exited = new Promise((resolve) => run.on("exit", resolve));
  const waitFor = async (text) => {
    for (let i = 0; i < 300 && !out.includes(text); ++i) await new Promise((r) => setTimeout(r, 50));
    assert.ok(out.includes(text), `no "${text}" in: ${out}`);
  };
  await waitFor("control/head_control activated");
  writeFileSync(config, readFileSync(config, "utf8").replace(
    /^( {6}head_control: .*)$/m, "$1\n      wave: {type: scripted, params: {activation: 1}}"));
  await waitFor("control/wave activated");
  await new Promise((r) => setTimeout(r, 300));  // a few steps of the reloaded config
  run.kill("SIGINT");
  assert.equal(await exited, 0);
  const recorded = await read(file);
  const steps = [...recorded.channels].filter(([, c]) => c.topic === "/arbiter/step");
  assert.equal(steps.length, 2);
  const [[before, old], [after, now]] = steps;
  assert.equal(lichtblickFields(old.schema, old.schemaName).get("layers.control.wave.activation"), undefined);
  assert.equal(lichtblickFields(now.schema, now.schemaName).get("layers.control.wave.activation"), "float64");
  const ajv = new Ajv2020({ strict: true, strictRequired: false });
  const validators = new Map([...recorded.channels].map(([id, c]) => [id, ajv.compile(c.schema)]));
  for (const m of recorded.messages) assert.ok(validators.get(m.channelId)(m.data), m.text.slice(0, 200));
  const on = (id) => recorded.messages.filter((m) => m.channelId === id);
  assert.ok(on(before).length > 0 && on(after).length > 0);
  assert.ok(on(after).every((m) => "wave" in m.data.layers.control));
  assert.ok(on(before).every((m) => !("wave" in m.data.layers.control)));
});

test("the shipped soccer layout's panels name topics, message paths and a frame of a soccer recording", () => {
  const layout = JSON.parse(readFileSync(path.join(process.env.ARBITER_SOURCE, "docs/layouts/soccer.json"), "utf8"));
  const run = demos.soccer;
  const channel = (topic) => [...run.channels.values()].find((c) => c.topic === topic);
  // Every panel the layout places has its config, and every config is placed.
  const placed = [];
  const walk = (node) => (typeof node === "string" ? placed.push(node) : (walk(node.first), walk(node.second)));
  walk(layout.layout);
  assert.deepEqual(placed.sort(), Object.keys(layout.configById).sort());
  const kinds = placed.map((id) => id.split("!")[0]).sort();
  assert.deepEqual(kinds, ["3D", "Plot", "Plot", "RosOut"]);

  let plotted = 0;
  for (const [id, config] of Object.entries(layout.configById)) {
    if (id.startsWith("3D!")) {
      for (const topic of Object.keys(config.topics)) {
        assert.equal(channel(topic)?.schemaName, "foxglove.SceneUpdate", topic);
      }
      // The frame it follows is the one the soccer world draws in.
      const frames = new Set(run.of("/arbiter/scene").flatMap((m) => m.data.entities.map((e) => e.frame_id)));
      assert.ok(frames.has(config.followTf), `no frame ${config.followTf} in ${[...frames]}`);
    } else if (id.startsWith("RosOut!")) {
      assert.equal(channel(config.topicToRender)?.schemaName, "foxglove.Log");
    } else {
      // A panel's own title is read from this key (Lichtblick's util/layout.ts, as Foxglove's).
      assert.ok(config.foxglovePanelTitle, `${id} has no foxglovePanelTitle`);
      for (const { value } of config.paths) {
        const [, topic, field] = value.match(/^(\/[\w/]+)\.(.+)$/);
        const c = channel(topic);
        assert.ok(c, `${value}: no topic ${topic}`);
        const type = lichtblickFields(c.schema, c.schemaName).get(field.replace(/\[\d+\]/g, "[]"));
        assert.equal(type, "float64", `${value}: a ${type}`);
        ++plotted;
      }
    }
  }
  assert.equal(plotted, 7);
  // The activations plotted are the config's behaviours, all of them.
  const step = run.of("/arbiter/step")[0].data;
  const plots = layout.configById["Plot!activations"].paths.map((p) => p.value.split(".")[3]).sort();
  assert.deepEqual(plots, Object.keys(step.layers.control).sort());
});
