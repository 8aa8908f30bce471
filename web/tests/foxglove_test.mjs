// `arbiter run --foxglove`, seen by Foxglove's own client (@foxglove/ws-protocol, over the `ws`
// socket) as Foxglove and Lichtblick see it. Run through web/tests/foxglove_run.sh (CTest
// `foxglove.live`), which sets:
//   ARBITER         the arbiter binary
//   ARBITER_SOURCE  the source tree (for the configs)
//   NODE_MODULES    where `npm ci` put the packages of web/package.json
import {test as nodeTest, after} from 'node:test';
import assert from 'node:assert/strict';
import {execFileSync, spawn, spawnSync} from 'node:child_process';
import {mkdtempSync, readFileSync, rmSync, writeFileSync} from 'node:fs';
import {tmpdir} from 'node:os';
import path from 'node:path';
import net from 'node:net';

import {arbiter, children, requireModule, source, startArbiter, stopAll} from './support.mjs';

const test = (name, fn) => nodeTest(name, {timeout: 90000}, fn);

const require = requireModule;
const {FoxgloveClient} = require('@foxglove/ws-protocol');
const WebSocket = require('ws');
const Ajv2020 = require('ajv/dist/2020').default;

const soccer = 'configs/soccer/walk_and_kick.yaml';
const scratch = mkdtempSync(path.join(tmpdir(), 'arbiter-foxglove-'));

after(() => {
  stopAll();
  rmSync(scratch, {recursive: true, force: true});
});

/// Starts `arbiter ARGS`; resolves with the ws:// URL it prints, the child, and a function that
/// resolves with all it printed once it exited (after a SIGINT, as the server stays up).
async function serve(args) {
  const {found, child, exited, streams} = await startArbiter(args, /ws:\/\/127\.0\.0\.1:\d+/);
  return {url: found[0], child, exited, output: streams};
}

/// A Foxglove client on `url`: resolves once the server advertised its channels.
function connect(url) {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
    const client = new FoxgloveClient({ws});
    const state = {ws, client, serverInfo: null, channels: new Map(), statuses: []};
    const timer = setTimeout(() => reject(new Error(`no advertise from ${url} in 15 s`)), 15000);
    client.on('error', reject);
    client.on('close', (event) => reject(new Error(`closed before advertise: ${event.code}`)));
    client.on('serverInfo', (info) => { state.serverInfo = info; });
    client.on('status', (status) => state.statuses.push(status));
    client.on('advertise', (channels) => {
      for (const channel of channels) state.channels.set(channel.id, channel);
      clearTimeout(timer);
      resolve(state);
    });
  });
}

const waitFor = (what, predicate, ms = 60000) => new Promise((resolve, reject) => {
  const started = Date.now();
  const timer = setInterval(() => {
    if (predicate()) {
      clearInterval(timer);
      resolve();
    } else if (Date.now() - started > ms) {
      clearInterval(timer);
      reject(new Error(`timed out waiting for ${what}`));
    }
  }, 20);
});

/// The soccer world's whole picture in one scene message: its frame's still and moving entities
/// only, holding together the robot with its heading, the ball and the field lines.
function assertWholeField(scene) {
  const ids = scene.entities.map((e) => e.id);
  assert.ok(ids.includes('field/still') && ids.every((id) => ['field/moving', 'field/still'].includes(id)), `${ids}`);
  const all = (kind) => scene.entities.flatMap((e) => e[kind]);
  assert.ok(all('arrows').length >= 1 && all('cylinders').length >= 2 && all('lines').length >= 4,
            'the robot with its heading, the ball and the field lines');
}

/// The soccer demo at `rate` steps per second, in the scratch folder beside its includes.
function soccerAt(rate) {
  const file = path.join(scratch, `soccer_${rate}.yaml`);
  const text = readFileSync(path.join(source, soccer), 'utf8').replace(/^rate_hz: .*$/m, `rate_hz: ${rate}`);
  // Relative includes and plugin paths keep working from the source's configs/soccer.
  writeFileSync(file, text);
  return file;
}

test('a Foxglove client subscribes to every channel, every message fits its schema, and it sees the kick', async () => {
  const server = await serve(['run', soccer, '--foxglove', '0', '--steps', '100000', '-q']);
  const {client, serverInfo, channels} = await connect(server.url);
  assert.match(serverInfo.name, /^arbiter /);
  // The server publishes its clock, the run's log time: a viewer stamps what it receives with it
  // (Lichtblick's FoxgloveWebSocketPlayer does), not with its own clock.
  assert.deepEqual(serverInfo.capabilities, ['time']);
  let clockTime = null;
  const clockBack = [];
  client.on('time', ({timestamp}) => {
    if (clockTime !== null && timestamp <= clockTime) clockBack.push(`${timestamp} after ${clockTime}`);
    clockTime = timestamp;
  });
  const stepsOffClock = [];
  // Exactly the channels of a recording (arbiter::channels()), in its order, JSON with JSON Schemas.
  const advertised = [...channels.values()].sort((a, b) => a.id - b.id);
  assert.deepEqual(advertised.map((channel) => `${channel.topic} ${channel.schemaName}`),
                   ['/arbiter/header arbiter.Header', '/arbiter/step arbiter.Step',
                    '/arbiter/inputs arbiter.Inputs', '/arbiter/log foxglove.Log',
                    '/arbiter/scene foxglove.SceneUpdate']);
  // The step schema is the config's own: each behaviour a typed field.
  const stepSchema = JSON.parse(advertised[1].schema);
  assert.equal(stepSchema.properties.layers.properties.control.properties.kick_ball
                   .properties.activation.type, 'number');
  const ajv = new Ajv2020({strict: false, allErrors: true});
  const validators = new Map();
  const subscriptions = new Map();
  for (const channel of channels.values()) {
    assert.equal(channel.encoding, 'json');
    assert.equal(channel.schemaEncoding, 'jsonschema');
    validators.set(channel.id, ajv.compile(JSON.parse(channel.schema)));
    subscriptions.set(client.subscribe(channel.id), channel);
  }
  const received = new Map();
  const invalid = [];
  let kickedAt = 0;
  let lastStep = 0;
  let lastTime = 0n;
  const reports = [];  // [{by, text, time}] of the steps received
  const logs = [];
  let firstScene = null;
  client.on('message', ({subscriptionId, timestamp, data}) => {
    const channel = subscriptions.get(subscriptionId);
    assert.ok(channel, `a message for the subscription ${subscriptionId}, which the client made`);
    const message = JSON.parse(new TextDecoder().decode(data));
    const validate = validators.get(channel.id);
    if (!validate(message)) invalid.push(`${channel.topic}: ${ajv.errorsText(validate.errors)}`);
    received.set(channel.topic, (received.get(channel.topic) || 0) + 1);
    if (channel.topic === '/arbiter/step') {
      assert.ok(message.step > lastStep, `steps arrive in order: ${message.step} after ${lastStep}`);
      assert.ok(timestamp >= lastTime, 'log times do not go back');
      if (timestamp !== clockTime) stepsOffClock.push(`step ${message.step} at ${timestamp}, the clock at ${clockTime}`);
      lastStep = message.step;
      lastTime = timestamp;
      if (!kickedAt && message.layers.control.kick_ball.active) kickedAt = message.step;
      for (const {by, text} of message.reported || []) reports.push({by, text, time: timestamp});
    }
    if (channel.topic === '/arbiter/log') logs.push({by: message.name, text: message.message, time: timestamp, message});
    if (channel.topic === '/arbiter/scene' && !firstScene) firstScene = message;
  });
  await waitFor('kick_ball to become active', () => kickedAt > 0);
  await waitFor('a few more steps', () => lastStep > kickedAt + 3, 5000);
  console.log(`kick_ball active at step ${kickedAt}; messages per topic:`,
              Object.fromEntries(received));
  assert.deepEqual(invalid, []);
  assert.deepEqual(clockBack, [], 'the server\'s clock never goes back');
  assert.deepEqual(stepsOffClock, [], 'each step comes after the clock says its time');
  assert.ok(received.get('/arbiter/header') >= 1, 'the header is sent to a client that subscribes late');
  assert.ok(received.get('/arbiter/inputs') > 10);
  // The soccer world draws every step: the picture goes out live as it is recorded.
  assert.ok(received.get('/arbiter/scene') > 10, 'the scene is published live');
  // Scene messages carry what changed; a client that subscribes mid-run gets the whole picture
  // first (everything deleted, then what does not move too), not just what moved.
  assert.ok(firstScene.deletions.some((d) => d.type === 1), 'the first scene message deletes all');
  // Split as the world drew it: what moved since the step before (none, if the client subscribed
  // before the first step) and what did not; together, the field with the robot and the ball.
  assertWholeField(firstScene);
  // What the world reported (the kick) is on /arbiter/log too, at its step's log time: a paced
  // run's, the wall clock.
  await waitFor('the kick reported', () => logs.some((log) => /kick/.test(log.text)), 10000);
  const kick = logs.find((log) => /kick/.test(log.text));
  assert.equal(kick.message.level, 2);  // INFO
  assert.equal(BigInt(kick.message.timestamp.sec) * 1000000000n + BigInt(kick.message.timestamp.nsec),
               kick.time);
  assert.ok(reports.some((report) => report.by === kick.by && report.text === kick.text &&
                                     report.time === kick.time),
            `the step that reported ${kick.by}: ${kick.text} at ${kick.time} has it in "reported"`);
  const late = Math.abs(Number(kick.time / 1000000n) - Date.now());
  assert.ok(late < 30000, `logged on the wall clock: ${late} ms from now`);
  assert.deepEqual(invalid, []);
  client.close();
  server.child.kill('SIGINT');
  assert.equal((await server.exited).code, 0);
});

test('a client that subscribes to the steps, then to the scene, gets the whole picture first, then one each step', async () => {
  // Without a scene subscriber the server leaves the picture out of what it copies each step; a
  // subscriber that comes later must still get a whole picture, then every step's (scene rate 0).
  const server = await serve(['run', soccerAt(60), '--foxglove', '0', '--foxglove-scene-rate', '0',
    '--steps', '100000', '-q']);
  const {client, channels} = await connect(server.url);
  const byTopic = new Map([...channels.values()].map((channel) => [channel.topic, channel]));
  const topics = new Map();
  const steps = [];   // log times of the steps received
  const scenes = [];  // [{time, message}]
  client.on('message', ({subscriptionId, timestamp, data}) => {
    const message = JSON.parse(new TextDecoder().decode(data));
    if (topics.get(subscriptionId) === '/arbiter/step') steps.push(timestamp);
    if (topics.get(subscriptionId) === '/arbiter/scene') scenes.push({time: timestamp, message});
  });
  topics.set(client.subscribe(byTopic.get('/arbiter/step').id), '/arbiter/step');
  await waitFor('steps without the scene', () => steps.length >= 10, 10000);
  assert.equal(scenes.length, 0);
  topics.set(client.subscribe(byTopic.get('/arbiter/scene').id), '/arbiter/scene');
  await waitFor('ten scene messages', () => scenes.length >= 10, 10000);
  const first = scenes[0].message;
  assert.ok(first.deletions.some((d) => d.type === 1), 'the first scene message deletes all');
  assertWholeField(first);
  // The soccer world draws every step: from the first picture on, each step has its scene message.
  const from = steps.indexOf(scenes[0].time);
  assert.ok(from >= 0, 'the first scene message is a step\'s');
  const stepsSince = steps.slice(from, from + 9);
  assert.deepEqual(scenes.slice(0, stepsSince.length).map((scene) => scene.time), stepsSince);
  client.close();
  server.child.kill('SIGINT');
  assert.equal((await server.exited).code, 0);
});

test('at its scene rate the server sends one step\'s picture a period, and every step\'s record', async () => {
  const server = await serve(['run', soccerAt(120), '--foxglove', '0', '--foxglove-scene-rate', '20',
    '--steps', '100000', '-q']);
  const {client, channels} = await connect(server.url);
  const byTopic = new Map([...channels.values()].map((channel) => [channel.topic, channel]));
  const topics = new Map();
  const steps = [];   // log times of the steps received
  const scenes = [];  // log times of the scene messages
  client.on('message', ({subscriptionId, timestamp}) => {
    if (topics.get(subscriptionId) === '/arbiter/step') steps.push(timestamp);
    if (topics.get(subscriptionId) === '/arbiter/scene') scenes.push(timestamp);
  });
  topics.set(client.subscribe(byTopic.get('/arbiter/scene').id), '/arbiter/scene');
  topics.set(client.subscribe(byTopic.get('/arbiter/step').id), '/arbiter/step');
  await waitFor('two seconds of steps', () => steps.length >= 240, 20000);
  client.close();
  server.child.kill('SIGINT');
  assert.equal((await server.exited).code, 0);
  const last = steps.at(-1);
  const shown = scenes.filter((time) => time <= last);
  const seconds = Number(last - steps[0]) / 1e9;
  console.log(`${steps.length} steps and ${shown.length} pictures in ${seconds.toFixed(2)} s of log time`);
  for (const time of shown) assert.ok(steps.includes(time), `a scene message at ${time} is a step's`);
  // 20 a second, the server asking for one when it looks at the steps (every 5 ms).
  assert.ok(shown.length >= 20 * seconds / 2, `${shown.length} pictures in ${seconds} s`);
  assert.ok(shown.length <= 20 * seconds + 3, `${shown.length} pictures in ${seconds} s`);
});

test('replay --foxglove serves a recording at its pace, its messages as a run sends them', async () => {
  const recording = path.join(scratch, 'run.mcap');
  execFileSync(arbiter, ['run', soccer, '--steps', '30', '--record', recording, '-q'], {cwd: source});
  const server = await serve(['replay', recording, '--foxglove', '0']);
  const {client, channels} = await connect(server.url);
  const ajv = new Ajv2020({strict: false});
  const step = [...channels.values()].find((channel) => channel.topic === '/arbiter/step');
  const scene = [...channels.values()].find((channel) => channel.topic === '/arbiter/scene');
  const validate = ajv.compile(JSON.parse(step.schema));
  const validateScene = ajv.compile(JSON.parse(scene.schema));
  const steps = [];
  const times = [];
  const scenes = [];  // [{message, time}]
  const subscriptions = new Map();
  client.on('message', ({subscriptionId, data, timestamp}) => {
    const message = JSON.parse(new TextDecoder().decode(data));
    if (subscriptions.get(subscriptionId) === '/arbiter/scene') {
      assert.ok(validateScene(message), ajv.errorsText(validateScene.errors));
      scenes.push({message, time: timestamp});
      return;
    }
    assert.ok(validate(message), ajv.errorsText(validate.errors));
    steps.push(message.step);
    times.push(timestamp);
  });
  // The scene first: a step the server captures before it has the scene subscription carries no
  // picture (the server copies pictures only for a scene subscriber), and this test compares the
  // pictures with the steps.
  subscriptions.set(client.subscribe(scene.id), '/arbiter/scene');
  subscriptions.set(client.subscribe(step.id), '/arbiter/step');
  await waitFor('the end of the replay', () => /the replay is over/.test(server.output().out), 20000);
  server.child.kill('SIGINT');
  const {code, out} = await server.exited;
  assert.equal(code, 0);
  assert.match(out, /replayed 30 steps of .*: identical to the recording/);
  // Paced at 15 Hz, the replay was still stepping when the client subscribed.
  assert.ok(steps.length > 5, `steps received: ${steps}`);
  assert.equal(steps.at(-1), 30);
  assert.deepEqual(steps, [...steps].sort((a, b) => a - b));
  // Logged on the simulated clock, as a recording of a replay is: step / rate_hz (15 Hz).
  for (let i = 1; i < steps.length; ++i) {
    const expected = (steps[i] - steps[i - 1]) * 1e9 / 15;
    assert.ok(Math.abs(Number(times[i] - times[i - 1]) - expected) <= 2,
              `steps ${steps[i - 1]} and ${steps[i]} are ${times[i] - times[i - 1]} ns apart`);
  }
  // The recorded world's picture, as the run sent it: one message a step, at the step's time,
  // the whole picture first (everything deleted, then the field that does not move and the
  // robot and the ball that do), then what moved.
  assert.ok(scenes.length >= steps.length - 1, `${scenes.length} scene messages for ${steps.length} steps`);
  assert.ok(scenes.every(({time}) => times.includes(time)), 'each at a step\'s log time');
  const first = scenes[0].message;
  assert.ok(first.deletions.some((d) => d.type === 1), 'the first scene message deletes all');
  assertWholeField(first);
  assert.ok(scenes.slice(1).some(({message}) => message.deletions.length === 0 &&
                                                message.entities.map((e) => e.id).join() === 'field/moving'),
            'between whole pictures, only what moves');
});

test('a hot reload (--watch) sends the reloaded program\'s header, and the steps go on', async () => {
  const config = soccerAt(30);
  const server = await serve(['run', config, '--watch', '--foxglove', '0', '-q']);
  const {client, channels} = await connect(server.url);
  const headers = [];
  let lastStep = 0;
  const subscriptions = new Map();
  for (const channel of channels.values()) subscriptions.set(client.subscribe(channel.id), channel.topic);
  client.on('message', ({subscriptionId, data}) => {
    const message = JSON.parse(new TextDecoder().decode(data));
    const topic = subscriptions.get(subscriptionId);
    if (topic === '/arbiter/header') headers.push(message);
    if (topic === '/arbiter/step') lastStep = message.step;
  });
  await waitFor('a few steps', () => lastStep >= 5, 10000);
  writeFileSync(config, readFileSync(config, 'utf8').replace('noise: 0.02', 'noise: 0.03'));
  await waitFor('the reloaded header', () => headers.some((header) => header.reload >= 1), 20000);
  const reloaded = headers.find((header) => header.reload >= 1);
  await waitFor('steps after the reload', () => lastStep > reloaded.after_step + 5, 10000);
  assert.equal(headers[0].arbiter_trace, 1);
  client.close();
  server.child.kill('SIGINT');
  assert.equal((await server.exited).code, 0);
});

test('a client that stops reading does not slow the steps: its messages are dropped, and counted', async () => {
  // Paced fast, so that an unread client's backlog fills within the run.
  const rate = 2000;
  const steps = 10000;
  const config = soccerAt(rate);
  const timed = async (withClient) => {
    const args = ['run', config, '--foxglove', '0', '--steps', String(steps)];
    const server = await serve(args);
    let stalled = null;
    if (withClient) {
      stalled = await connect(server.url);
      for (const channel of stalled.channels.values()) stalled.client.subscribe(channel.id);
      // Reads nothing more: the server's sends pile up in the socket and then in its queue.
      stalled.client.on('message', () => stalled.ws._socket.pause());
    }
    await waitFor('the end of the run', () => /the run is over/.test(server.output().out), 60000);
    server.child.kill('SIGINT');
    const {code, out, err} = await server.exited;
    assert.equal(code, 0, err);
    if (stalled) stalled.ws.terminate();
    const wall = Number(out.match(/in ([\d.]+) s of wall time/)[1]);
    const timing = out.split('\n').filter((line) => /step|period|overrun/i.test(line)).join('\n  ');
    return {wall, timing, err};
  };
  const alone = await timed(false);
  const slow = await timed(true);
  console.log(`${steps} steps paced at ${rate} Hz (${steps / rate} s), on this machine:\n` +
              `without a client: ${alone.wall} s of wall time\n  ${alone.timing}\n` +
              `with a client that stopped reading: ${slow.wall} s of wall time\n  ${slow.timing}\n` +
              `server: ${slow.err.trim()}`);
  assert.match(slow.err, /(\d+) messages were dropped for clients that read too slowly/);
  assert.ok(Number(slow.err.match(/(\d+) messages were dropped/)[1]) > 0);
  assert.match(slow.err, /reads too slowly: its messages are dropped/);
  // The run kept its pace: a client that blocked it would have held it until the end of the
  // test, one that slowed each step by a millisecond would have taken 10 s longer. A paced run's
  // wall time also grows with each period a loaded machine makes it miss: that noise is allowed.
  assert.ok(slow.wall < alone.wall * 1.5 + 1,
            `${slow.wall} s with the client against ${alone.wall} s without`);
});

test('garbage frames, unknown channels and 100 connections are survived with a log line each', async () => {
  const server = await serve(['run', soccer, '--foxglove', '0', '--steps', '100000', '-q',
                              '--log-level', 'info']);
  const {client, ws, channels, statuses} = await connect(server.url);
  const send = (data) => ws.send(data);
  send('not json at all');
  send('{"op": 7}');
  send('[1, 2, 3]');
  send(JSON.stringify({op: 'subscribe', subscriptions: [{id: 1, channelId: 9999}]}));
  send(JSON.stringify({op: 'subscribe', subscriptions: [{id: -1, channelId: 'x'}]}));
  send(JSON.stringify({op: 'subscribe'}));
  send(JSON.stringify({op: 'unsubscribe', subscriptionIds: [12345]}));
  send(JSON.stringify({op: 'publish', data: 1}));
  send(Buffer.from([0x01, 0xff, 0xff, 0xff, 0xff, 0x00]));
  // Nested 30 000 deep, under the size limit: printing it for a status message once overflowed
  // the server thread's stack and ended the run.
  send(`{"op":"subscribe","subscriptions":[${'['.repeat(30000)}${']'.repeat(30000)}]}`);
  await waitFor('a status message for each', () => statuses.length >= 10, 5000);
  console.log('statuses:', statuses.map((status) => status.message));
  // Raw garbage over TCP, not even a WebSocket handshake, 25 times (a scanner, a client retrying
  // in a loop: the log tells the first 20); and a frame too big to take.
  for (let i = 0; i < 25; ++i) {
    await new Promise((resolve) => {
      const socket = net.connect(Number(server.url.split(':')[2]), '127.0.0.1', () => {
        socket.end('\x00\xff garbage\r\n\r\n');
      });
      socket.resume();  // reads the server's answer, to see it close the connection
      socket.on('close', resolve);
      socket.setTimeout(5000, () => {
        socket.destroy();
        resolve();
      });
      socket.on('error', resolve);
    });
  }
  ws.send('x'.repeat(200000));
  // 100 clients connect, subscribe and leave.
  const many = await Promise.all(Array.from({length: 100}, () => connect(server.url)));
  for (const other of many) {
    for (const id of other.channels.keys()) other.client.subscribe(id);
  }
  await new Promise((resolve) => setTimeout(resolve, 300));
  for (const other of many) other.ws.terminate();
  // The server still serves: a new client gets the steps.
  const last = await connect(server.url);
  const step = [...last.channels.values()].find((channel) => channel.topic === '/arbiter/step');
  let got = 0;
  last.client.on('message', () => { got += 1; });
  last.client.subscribe(step.id);
  await waitFor('steps for a client after all that', () => got >= 3, 10000);
  last.client.close();
  client.close();
  server.child.kill('SIGINT');
  const {err} = await server.exited;
  console.log(err.split('\n').filter((line) => !/connected|left|End of File/.test(line)).join('\n'));
  assert.match(err, /malformed message/);
  assert.match(err, /a message nested deeper than 200 levels \(at byte \d+\): ignored/);
  assert.match(err, /no channel has the id 9999/);
  assert.match(err, /a connection from .* failed: .*/);
  assert.equal(err.match(/a connection from .* failed: /g).length, 20, 'the first 20 failed connections logged');
  assert.match(err, /20 connections have failed; further failures are not logged/);
  assert.match(err, /closed the connection of client .*: A message was too large/);
  assert.match(err, /client .* connected \(\d+ connected\)/);
  assert.doesNotMatch(err, /terminate|Segmentation|Aborted/);
  assert.equal(channels.size >= 3, true);
});

test('a client that sends and never reads does not make the server hold its answers without end', async () => {
  // Measured by the server's resident memory: under AddressSanitizer, freed memory is held back
  // (its quarantine) and would count as grown.
  const asan = process.env.ASAN_OPTIONS;
  process.env.ASAN_OPTIONS = `${asan ? `${asan}:` : ''}quarantine_size_mb=0`;
  const server = await serve(['run', soccer, '--foxglove', '0', '--steps', '1000000', '-q']);
  if (asan === undefined) delete process.env.ASAN_OPTIONS;
  else process.env.ASAN_OPTIONS = asan;
  const {client, ws} = await connect(server.url);
  const megabytes = () =>
    Number(/VmRSS:\s+(\d+)/.exec(readFileSync(`/proc/${server.child.pid}/status`, 'utf8'))[1]) / 1024;
  ws._socket.pause();  // reads nothing from here on
  const before = megabytes();
  // Each id it does not know gets a status message: 2 000 000 of them, some 200 MB unread.
  const unknown = JSON.stringify({op: 'unsubscribe', subscriptionIds: Array(20000).fill(7)});
  for (let i = 0; i < 100; ++i) ws.send(unknown);
  // Until the server has read them all: its memory no longer changes (within 20 s).
  let last = before;
  for (let steady = 0, i = 0; steady < 3 && i < 40; ++i) {
    await new Promise((resolve) => setTimeout(resolve, 500));
    const now = megabytes();
    steady = Math.abs(now - last) < 1 ? steady + 1 : 0;
    last = now;
  }
  const grown = megabytes() - before;
  console.log(`the server's memory grew by ${grown.toFixed(1)} MB`);
  assert.ok(grown < 50, `the server's memory grew by ${grown.toFixed(1)} MB`);
  client.close();
  server.child.kill('SIGINT');
  await server.exited;
});

test('loopback unless another address is asked for, with a warning; a bad address is a usage error', async () => {
  const bad = spawnSync(arbiter, ['run', soccer, '--foxglove', '127.0.0.1:99999'], {cwd: source, encoding: 'utf8'});
  assert.equal(bad.status, 2);
  assert.match(bad.stderr, /--foxglove: .*the port must be a number from 0 to 65535/);
  const local = await serve(['run', soccer, '--foxglove', '0', '-q']);
  const all = await new Promise((resolve, reject) => {
    const child = spawn(arbiter, ['run', soccer, '--foxglove', '0.0.0.0:0', '-q'], {cwd: source});
    children.push(child);
    let out = '';
    let err = '';
    child.stdout.on('data', (data) => { out += data; });
    child.stderr.on('data', (data) => { err += data; });
    // stdout and stderr are separate pipes: the warning may arrive after the address.
    const started = Date.now();
    const timer = setInterval(() => {
      const warned = /not only to this machine/.test(err) || Date.now() - started > 10000;
      if (/ws:\/\//.test(out) && warned) {
        clearInterval(timer);
        resolve({child, out, err});
      }
    }, 20);
    child.on('exit', (code) => reject(new Error(`arbiter exited with ${code}: ${err}`)));
  });
  assert.match(all.out, /ws:\/\/0\.0\.0\.0:\d+/);
  assert.match(all.err, /serving on 0\.0\.0\.0, not only to this machine: .*no authentication/);
  assert.doesNotMatch(local.output().err, /not only to this machine/);
  all.child.kill('SIGINT');
  local.child.kill('SIGINT');
  await local.exited;
});
