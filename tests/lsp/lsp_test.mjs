// `arbiter lsp` driven by vscode-languageserver-protocol, the client library VS Code uses, on the
// repo's configs (YAML and JSON) and broken copies of them. Expected ranges are computed from the
// text the test sends: 0-based lines, UTF-16 columns.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(path.join(process.env.NODE_MODULES, 'x.js'));
const rpc = require('vscode-languageserver-protocol/node.js');

const arbiter = process.env.ARBITER;
const source = process.env.ARBITER_SOURCE;
const uriOf = (file) => 'file://' + file;

function read(relative) {
  const file = path.join(source, relative);
  return { file, uri: uriOf(file), text: fs.readFileSync(file, 'utf8') };
}

// The range of the `nth` occurrence of `needle` in `text` (plus `skip` characters).
function rangeOf(text, needle, { nth = 0, skip = 0, length = needle.length - skip } = {}) {
  let at = -1;
  for (let i = 0; i <= nth; ++i) {
    at = text.indexOf(needle, at + 1);
    assert.notEqual(at, -1, `'${needle}' not in the text`);
  }
  at += skip;
  const before = text.slice(0, at).split('\n');
  const line = before.length - 1;
  const character = before[line].length;  // JavaScript strings count UTF-16 units
  return { start: { line, character }, end: { line, character: character + length } };
}

function positionOf(text, needle, options = {}) {
  return rangeOf(text, needle, options).start;
}

class Client {
  constructor(args = []) {
    this.process = spawn(arbiter, ['lsp', ...args], { stdio: ['pipe', 'pipe', 'pipe'] });
    this.stderr = '';
    this.process.stderr.on('data', (chunk) => { this.stderr += chunk; });
    this.exited = new Promise((resolve) => this.process.on('exit', (code) => resolve(code)));
    this.connection = rpc.createProtocolConnection(
      new rpc.StreamMessageReader(this.process.stdout),
      new rpc.StreamMessageWriter(this.process.stdin));
    this.diagnostics = new Map();
    this.publications = new Map();  // how many times each URI's diagnostics were published
    this.waiting = new Map();
    this.connection.onNotification('textDocument/publishDiagnostics', (params) => {
      this.diagnostics.set(params.uri, params.diagnostics);
      this.publications.set(params.uri, (this.publications.get(params.uri) ?? 0) + 1);
      const waiter = this.waiting.get(params.uri);
      if (waiter) {
        this.waiting.delete(params.uri);
        waiter(params.diagnostics);
      }
    });
    this.connection.listen();
  }

  async start() {
    const result = await this.connection.sendRequest('initialize',
      { processId: process.pid, rootUri: uriOf(source), capabilities: {} });
    await this.connection.sendNotification('initialized', {});
    return result;
  }

  published(uri) {
    return new Promise((resolve) => this.waiting.set(uri, resolve));
  }

  async open(uri, text) {
    const next = this.published(uri);
    const languageId = uri.endsWith('.json') ? 'json' : 'yaml';
    await this.connection.sendNotification('textDocument/didOpen',
      { textDocument: { uri, languageId, version: 1, text } });
    return next;
  }

  async change(uri, text, waitFor = uri) {
    const next = this.published(waitFor);
    await this.connection.sendNotification('textDocument/didChange',
      { textDocument: { uri, version: 2 }, contentChanges: [{ text }] });
    return next;
  }

  request(method, params) {
    return this.connection.sendRequest(method, params);
  }

  async stop() {
    await this.connection.sendRequest('shutdown');
    await this.connection.sendNotification('exit');
    const code = await this.exited;
    this.connection.dispose();
    return code;
  }
}

async function withClient(body) {
  const client = new Client();
  await client.start();
  try {
    await body(client);
  } finally {
    assert.equal(await client.stop(), 0, client.stderr);
  }
}

const yaml = () => read('configs/soccer/walk_and_kick.yaml');

// `arbiter validate`'s diagnostics of `file` as the server publishes them: code, severity and
// start, in order.
function validated(file, args = []) {
  let output;
  try {
    output = execFileSync(arbiter, [...args, 'validate', '--format', 'json', file], { encoding: 'utf8' });
  } catch (error) {
    output = error.stdout;
  }
  return JSON.parse(output).map((d) => ({
    code: d.code, severity: d.severity === 'error' ? 1 : 2,
    start: { line: d.line - 1, character: d.column - 1 },
  }));
}
const summary = (diagnostics) => diagnostics.map((d) => ({ code: d.code, severity: d.severity, start: d.range.start }));

function tempDir() {
  return fs.mkdtempSync(path.join(os.tmpdir(), 'arbiter-lsp-'));
}
const json = () => read('configs/paper/walk_and_kick.json');

test('a valid config gets an empty list of diagnostics', async () => {
  await withClient(async (client) => {
    for (const config of [yaml(), json()]) {
      assert.deepEqual(await client.open(config.uri, config.text), []);
    }
  });
});

for (const [format, config] of [['YAML', yaml], ['JSON', json]]) {
  test(`a misspelt inhibition endpoint in ${format} is an error at the name, with the suggestion, and fixing it clears it`, async () => {
    await withClient(async (client) => {
      const { uri, text } = config();
      await client.open(uri, text);
      const broken = text.replace('kick_ball => go_behind_ball', 'kick_bal => go_behind_ball');
      const [diagnostic, ...rest] = await client.change(uri, broken);
      assert.deepEqual(rest, []);
      assert.equal(diagnostic.code, 'unknown-behaviour');
      assert.equal(diagnostic.source, 'arbiter');
      assert.equal(diagnostic.severity, 1);
      assert.deepEqual(diagnostic.range, rangeOf(broken, 'kick_bal =>', { length: 8 }));
      assert.match(diagnostic.relatedInformation[0].message, /did you mean 'kick_ball'\?/);

      const [action] = await client.request('textDocument/codeAction',
        { textDocument: { uri }, range: diagnostic.range, context: { diagnostics: [diagnostic] } });
      assert.equal(action.title, "Change to 'kick_ball'");
      assert.deepEqual(action.edit.changes[uri], [{ range: diagnostic.range, newText: 'kick_ball' }]);

      assert.deepEqual(await client.change(uri, text), []);
    });
  });

  test(`an inhibition cycle in ${format} names each edge in related information`, async () => {
    await withClient(async (client) => {
      const { uri, text } = config();
      await client.open(uri, text);
      const broken = text.replace('go_behind_ball => search_for_ball', 'go_behind_ball => kick_ball');
      const diagnostics = await client.change(uri, broken);
      const cycle = diagnostics.find((d) => d.code === 'inhibition-cycle');
      assert.ok(cycle, JSON.stringify(diagnostics));
      assert.ok(cycle.relatedInformation.length >= 1);
      for (const info of cycle.relatedInformation) assert.equal(info.location.uri, uri);
    });
  });

  test(`a redundant inhibition in ${format} is a lint with a quick fix that removes it`, async () => {
    await withClient(async (client) => {
      const { uri, text } = config();
      await client.open(uri, text);
      const added = format === 'YAML'
        ? text.replace('      - search_for_ball -> head_control', '      - search_for_ball -> head_control\n      - kick_ball => search_for_ball')
        : text.replace('"go_behind_ball => search_for_ball"', '"go_behind_ball => search_for_ball", "kick_ball => search_for_ball"');
      assert.notEqual(added, text);
      const diagnostics = await client.change(uri, added);
      const lint = diagnostics.find((d) => d.code === 'redundant-inhibition');
      assert.ok(lint, JSON.stringify(diagnostics));
      assert.equal(lint.severity, 2);
      const needle = format === 'YAML' ? 'kick_ball => search_for_ball' : '"kick_ball => search_for_ball"';
      assert.deepEqual(lint.range.start, positionOf(added, needle));
      const actions = await client.request('textDocument/codeAction',
        { textDocument: { uri }, range: lint.range, context: { diagnostics: [lint] } });
      const remove = actions.find((a) => a.title.startsWith('Remove the inhibition'));
      assert.ok(remove);
      // Applying the edit gives back the original text.
      const [edit] = remove.edit.changes[uri];
      const lines = added.split('\n');
      const offset = (p) => lines.slice(0, p.line).reduce((n, l) => n + l.length + 1, 0) + p.character;
      const fixed = added.slice(0, offset(edit.range.start)) + edit.newText + added.slice(offset(edit.range.end));
      assert.equal(fixed, text);
      assert.deepEqual(await client.change(uri, fixed), []);
    });
  });

  test(`hover on a ${format} behaviour lists its inhibitions, implied ones with their chain`, async () => {
    await withClient(async (client) => {
      const { uri, text } = config();
      await client.open(uri, text);
      const hover = await client.request('textDocument/hover',
        { textDocument: { uri }, position: positionOf(text, 'search_for_ball', { skip: 2 }) });
      assert.deepEqual(hover.range, rangeOf(text, 'search_for_ball'));
      assert.match(hover.contents.value, /\*\*behaviour\*\* `search_for_ball` in layer `control`/);
      assert.match(hover.contents.value, /`go_behind_ball` => `search_for_ball`/);
      assert.match(hover.contents.value, /`kick_ball` inhibits `search_for_ball`, implied by chaining kick_ball => go_behind_ball => search_for_ball/);

      const line = await client.request('textDocument/hover',
        { textDocument: { uri }, position: positionOf(text, ' => go_behind_ball', { skip: 1 }) });
      assert.match(line.contents.value, /Implies through chaining:\n- `kick_ball` inhibits `search_for_ball`/);
    });
  });

  test(`definition and references of a ${format} behaviour`, async () => {
    await withClient(async (client) => {
      const { uri, text } = config();
      await client.open(uri, text);
      const use = positionOf(text, 'kick_ball => go_behind_ball', { skip: 14 });
      const definition = await client.request('textDocument/definition', { textDocument: { uri }, position: use });
      const declared = format === 'YAML' ? 'go_behind_ball: {' : '"go_behind_ball": {';
      assert.deepEqual(definition, { uri, range: rangeOf(text, declared, { skip: format === 'YAML' ? 0 : 1, length: 14 }) });
      const references = await client.request('textDocument/references',
        { textDocument: { uri }, position: use, context: { includeDeclaration: true } });
      assert.equal(references.length, 3);
      assert.deepEqual(references.map((r) => r.range.start.line).sort((a, b) => a - b),
        [definition.range.start.line, positionOf(text, 'kick_ball => go_behind_ball').line,
          positionOf(text, 'go_behind_ball => search_for_ball').line].sort((a, b) => a - b));
    });
  });

  test(`rename of a ${format} behaviour edits every use, and refuses invalid or taken names`, async () => {
    await withClient(async (client) => {
      const { uri, text } = config();
      await client.open(uri, text);
      const position = positionOf(text, 'kick_ball => go_behind_ball');
      const edit = await client.request('textDocument/rename', { textDocument: { uri }, position, newName: 'shoot' });
      const edits = edit.changes[uri];
      assert.equal(edits.length, 2);
      for (const e of edits) assert.equal(e.newText, 'shoot');
      assert.deepEqual(edits[1].range, rangeOf(text, 'kick_ball => go_behind_ball', { length: 9 }));
      await assert.rejects(client.request('textDocument/rename', { textDocument: { uri }, position, newName: 'Shoot!' }),
        /not a valid name/);
      await assert.rejects(client.request('textDocument/rename', { textDocument: { uri }, position, newName: 'head_control' }),
        /already taken/);
    });
  });

  test(`document symbols of ${format}: layers with behaviours and actuators`, async () => {
    await withClient(async (client) => {
      const { uri, text } = config();
      await client.open(uri, text);
      const symbols = await client.request('textDocument/documentSymbol', { textDocument: { uri } });
      const control = symbols.find((s) => s.name === 'control');
      assert.ok(control);
      const behaviours = control.children.filter((c) => c.kind === 5).map((c) => c.name);
      assert.deepEqual(behaviours, ['kick_ball', 'go_behind_ball', 'search_for_ball', 'head_control']);
      assert.ok(control.children.some((c) => c.kind === 8 && c.name === 'gait_velocity'));
    });
  });
}

test('a note that names a place links to that place in related information, however the note words it', async () => {
  const dir = tempDir();
  try {
    await withClient(async (client) => {
      // The note reads "line 6, column 5": no `file:line:column` in its text.
      const unclosed = path.join(dir, 'unclosed.yaml');
      const unclosedText = 'arbiter: 1\nname: t\nlayers:\n  - name: l\n    actuators: {a: {type: bool}\n' +
        '    behaviours:\n      b: {type: scripted}\n';
      fs.writeFileSync(unclosed, unclosedText);
      const [syntax] = await client.open(uriOf(unclosed), unclosedText);
      assert.equal(syntax.code, 'yaml-syntax');
      assert.match(syntax.relatedInformation[0].message, /reached line 6, column 5/);
      assert.deepEqual(syntax.relatedInformation[0].location,
        { uri: uriOf(unclosed), range: rangeOf(unclosedText, 'behaviours') });

      // A folder with a space in its name: the whole path is the place, not what follows the space.
      fs.mkdirSync(path.join(dir, 'two words'));
      const twice = path.join(dir, 'two words', 'twice.yaml');
      const twiceText = 'arbiter: 1\nname: twice\nlayers:\n  - name: control\n  - name: control\n';
      fs.writeFileSync(twice, twiceText);
      const twiceUri = uriOf(twice).replace(/ /g, '%20');
      const [duplicate] = await client.open(twiceUri, twiceText);
      assert.equal(duplicate.code, 'duplicate-name');
      assert.deepEqual(duplicate.range, rangeOf(twiceText, 'control', { nth: 1 }));
      assert.equal(duplicate.relatedInformation[0].message, `first declared at ${twice}:4:11`);
      assert.deepEqual(duplicate.relatedInformation[0].location,
        { uri: twiceUri, range: rangeOf(twiceText, 'control') });
    });
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test("a config's diagnostics equal validate's whatever else is open: another config's plugins stay its own", async () => {
  const dir = tempDir();
  try {
    const { text } = yaml();
    const withPlugin = path.join(dir, 'with_plugin.yaml');
    const without = path.join(dir, 'without.yaml');
    fs.writeFileSync(withPlugin, text);
    fs.writeFileSync(without, text.replace('plugins: [soccer]\n', ''));
    const expected = validated(without);
    assert.equal(expected.filter((d) => d.code === 'unknown-class').length, 5);
    await withClient(async (client) => {
      // The config that names no plugin first, then the one that loads soccer: the first keeps
      // its errors.
      assert.deepEqual(summary(await client.open(uriOf(without), fs.readFileSync(without, 'utf8'))), expected);
      assert.deepEqual(await client.open(uriOf(withPlugin), text), []);
      assert.deepEqual(summary(client.diagnostics.get(uriOf(without))), expected);
      // Nor does completion offer it soccer's classes.
      const withoutText = fs.readFileSync(without, 'utf8');
      const classes = async (uri, edited) => {
        await client.change(uri, edited);
        const result = await client.request('textDocument/completion',
          { textDocument: { uri }, position: positionOf(edited, 'type: soc', { skip: 9 }) });
        return result.items.map((i) => i.label);
      };
      const edit = (t) => t.replace('head_control: {type: soccer.HeadControl}', 'head_control:\n        type: soc');
      assert.ok((await classes(uriOf(withPlugin), edit(text))).includes('soccer.KickBall'));
      assert.ok(!(await classes(uriOf(without), edit(withoutText))).includes('soccer.KickBall'));
    });
    await withClient(async (client) => {
      // The other order: soccer loaded for one config is unknown to the next.
      assert.deepEqual(await client.open(uriOf(withPlugin), text), []);
      assert.deepEqual(summary(await client.open(uriOf(without), fs.readFileSync(without, 'utf8'))), expected);
    });
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('files that are not Arbiter configs get no diagnostics and no completion; a config is known by its keys or its $schema', async () => {
  const dir = tempDir();
  try {
    const others = {
      'package.json': '{\n  "name": "web",\n  "version": "1.0.0",\n  "dependencies": {"arbiter": "^1.0.0", "layers": "2"}\n}\n',
      'CMakePresets.json': '{\n  "version": 6,\n  "configurePresets": [{"name": "dev", "binaryDir": "build"}]\n}\n',
      'ci.yml': 'name: CI\non: [push]\njobs:\n  build:\n    runs-on: ubuntu-latest\n    steps:\n      - run: make\n',
      'docker-compose.yaml': 'services:\n  web:\n    image: nginx\n    layers: 3\n',
    };
    await withClient(async (client) => {
      for (const [name, text] of Object.entries(others)) {
        const uri = uriOf(path.join(dir, name));
        await client.connection.sendNotification('textDocument/didOpen',
          { textDocument: { uri, languageId: name.endsWith('.json') ? 'json' : 'yaml', version: 1, text } });
        const completion = await client.request('textDocument/completion',
          { textDocument: { uri }, position: { line: 1, character: 2 } });
        assert.deepEqual(completion.items ?? completion, [], name);
      }
      // Configs, each recognised by one rule: a top-level `arbiter:`, a `layers:` (an included
      // file), a `$schema` key, the YAML language server's comment. Each gets its diagnostics.
      const configs = {
        'a.yaml': 'arbiter: 1\nname: a\nlayers: 3\n',
        'part.yaml': 'layers:\n  - name: x\n    behaviours: {b: {type: nope}}\n',
        'b.json': '{"$schema": "../schema/arbiter.schema.json", "name": "b"}',
        'c.yaml': '# yaml-language-server: $schema=https://example.org/arbiter.schema.json\nname: c\n',
      };
      for (const [name, text] of Object.entries(configs)) {
        const diagnostics = await client.open(uriOf(path.join(dir, name)), text);
        assert.ok(diagnostics.length > 0, name);
      }
      for (const name of Object.keys(others)) {
        assert.deepEqual(client.diagnostics.get(uriOf(path.join(dir, name))) ?? [], [], name);
      }
    });
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('hover on an actuator lists its writers and readers; on a class, its params; a sensor goes to its actuator', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const actuator = await client.request('textDocument/hover',
      { textDocument: { uri }, position: positionOf(text, 'ball_visible: {', { skip: 1 }) });
    assert.match(actuator.contents.value, /\*\*actuator\*\* `ball_visible` of layer `world`, type `bool`/);
    assert.match(actuator.contents.value, /Written by:\n- interface of layer `world` \(port `ball_visible`\)/);
    assert.match(actuator.contents.value, /Read by:\n- layer `control` \(sensor\)\n- `control\/kick_ball` \(port `ball_visible`\)/);
    const cls = await client.request('textDocument/hover',
      { textDocument: { uri }, position: positionOf(text, 'soccer.SearchForBall', { skip: 3 }) });
    assert.deepEqual(cls.range, rangeOf(text, 'soccer.SearchForBall'));
    assert.match(cls.contents.value, /\*\*soccer.SearchForBall\*\* \(behaviour, plugin soccer/);
    assert.match(cls.contents.value, /- `turn_rate`: double, /);
    const sensor = positionOf(text, 'ball_visible, ball_position, robot_pose', { skip: 2 });
    const definition = await client.request('textDocument/definition', { textDocument: { uri }, position: sensor });
    assert.deepEqual(definition.range, rangeOf(text, 'ball_visible: {', { length: 12 }));
  });
});

test('completion offers keys, classes with descriptions, behaviour names after => and actuators as sensors', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const labels = async (edited, at) => {
      await client.change(uri, edited);
      const result = await client.request('textDocument/completion', { textDocument: { uri }, position: at });
      return result.items.map((i) => i.label);
    };
    // A key at the top level.
    let edited = text.replace('rate_hz: 15', 'rate_hz: 15\nnorm');
    let items = await labels(edited, positionOf(edited, 'norm', { skip: 4 }));
    assert.ok(items.includes('normalise') && items.includes('state_machines') && items.includes('layers'), items.join());
    // A behaviour's keys.
    edited = text.replace('      head_control: {type: soccer.HeadControl}', '      head_control:\n        ty');
    items = await labels(edited, positionOf(edited, '        ty', { skip: 10 }));
    assert.ok(items.includes('type') && items.includes('params') && items.includes('ports'), items.join());
    // Class names after `type:`, with their description.
    edited = text.replace('head_control: {type: soccer.HeadControl}', 'head_control:\n        type: soc');
    await client.change(uri, edited);
    const classes = await client.request('textDocument/completion',
      { textDocument: { uri }, position: positionOf(edited, 'type: soc', { skip: 9 }) });
    const kick = classes.items.find((i) => i.label === 'soccer.KickBall');
    assert.ok(kick, classes.items.map((i) => i.label).join());
    assert.match(kick.documentation.value, /\*\*soccer.KickBall\*\*/);
    // Behaviour names of the layer after `=>`.
    edited = text.replace('search_for_ball -> head_control', 'search_for_ball -> he');
    items = await labels(edited, positionOf(edited, '-> he', { skip: 5 }));
    assert.deepEqual(items.sort(), ['go_behind_ball', 'head_control', 'kick_ball', 'search_for_ball']);
    // Actuators as sensors.
    edited = text.replace('sensors: [ball_visible, ball_position, robot_pose]', 'sensors: [ball_visible, ]');
    items = await labels(edited, positionOf(edited, 'ball_visible, ]', { skip: 14 }));
    assert.ok(items.includes('ball_position') && items.includes('gait_velocity'), items.join());
  });
});

test('completion in JSON offers a layer\'s keys and a params key of the class', async () => {
  await withClient(async (client) => {
    const { uri, text } = json();
    await client.open(uri, text);
    const edited = text.replace('"params": {"activation": 1, "writes": {"head_angle": -0.5}}',
      '"params": {"activation": 1, "writes": {"head_angle": -0.5}, "}');
    await client.change(uri, edited);
    const result = await client.request('textDocument/completion',
      { textDocument: { uri }, position: positionOf(edited, '-0.5}, "}', { skip: 8 }) });
    const labels = result.items.map((i) => i.label);
    assert.ok(labels.includes('activation') && labels.includes('writes'), labels.join());
  });
});

test('state names complete in a queue and go to their declaration', async () => {
  await withClient(async (client) => {
    const { uri, text } = read('configs/paper/goalie_plan.yaml');
    assert.deepEqual(await client.open(uri, text), []);
    const edited = text.replace('      - monitor_ball\n', '      - monitor_ball\n      - wal\n');
    await client.change(uri, edited);
    const result = await client.request('textDocument/completion',
      { textDocument: { uri }, position: positionOf(edited, '      - wal\n', { skip: 11 }) });
    assert.ok(result.items.some((i) => i.label === 'walk_to_pose'), JSON.stringify(result.items));
    await client.change(uri, text);
    const definition = await client.request('textDocument/definition',
      { textDocument: { uri }, position: positionOf(text, '- walk_to_pose', { skip: 2 }) });
    assert.deepEqual(definition.range, rangeOf(text, 'walk_to_pose: {type', { length: 12 }));
  });
});

// Applies a WorkspaceEdit's edits of `uri` to `text` (from the last, so that earlier ranges hold).
function applyEdits(text, edits) {
  const lines = text.split('\n');
  const offset = (p) => lines.slice(0, p.line).reduce((n, l) => n + l.length + 1, 0) + p.character;
  const sorted = [...edits].sort((a, b) => offset(b.range.start) - offset(a.range.start));
  for (const e of sorted) text = text.slice(0, offset(e.range.start)) + e.newText + text.slice(offset(e.range.end));
  return text;
}

test("a state named in a scripted state's append: or prepend: is renamed, and found by references, definition and hover", async () => {
  await withClient(async (client) => {
    const { uri, text } = read('configs/paper/goalie_plan.yaml');
    assert.deepEqual(await client.open(uri, text), []);
    const planned = positionOf(text, 'monitor_ball]');
    const declared = rangeOf(text, '      monitor_ball:', { skip: 6, length: 12 });
    const definition = await client.request('textDocument/definition', { textDocument: { uri }, position: planned });
    assert.deepEqual(definition, { uri, range: declared });
    const references = await client.request('textDocument/references',
      { textDocument: { uri }, position: declared.start, context: { includeDeclaration: true } });
    assert.deepEqual(references.map((r) => r.range).sort((a, b) => a.start.line - b.start.line),
      [declared, rangeOf(text, 'monitor_ball]', { length: 12 }), rangeOf(text, '- monitor_ball\n', { skip: 2, length: 12 })]);
    const walk = await client.request('textDocument/references',
      { textDocument: { uri }, position: positionOf(text, 'walk_to_pose: {type'), context: { includeDeclaration: false } });
    // Three in prepend: and append:, one in the queue.
    assert.equal(walk.length, 4, JSON.stringify(walk));
    const hover = await client.request('textDocument/hover', { textDocument: { uri }, position: planned });
    assert.match(hover.contents.value, /\*\*state\*\* `monitor_ball` of state machine `goalie` \(class `scripted`\)/);

    const edit = await client.request('textDocument/rename',
      { textDocument: { uri }, position: declared.start, newName: 'watch_ball' });
    const renamed = applyEdits(text, edit.changes[uri]);
    // Every other byte, the comments that name it included, is left as it was.
    assert.equal(renamed, text.replace('      monitor_ball:\n', '      watch_ball:\n')
      .replace('monitor_ball]', 'watch_ball]').replace('      - monitor_ball\n', '      - watch_ball\n'));
    const dir = tempDir();
    fs.writeFileSync(path.join(dir, 'goalie_plan.yaml'), renamed);
    assert.deepEqual(validated(path.join(dir, 'goalie_plan.yaml')), []);
    assert.deepEqual(await client.change(uri, renamed), []);
  });
});

test('renaming an actuator that ports bind by name adds ports: entries that keep them bound (YAML)', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const edit = await client.request('textDocument/rename',
      { textDocument: { uri }, position: positionOf(text, 'ball_visible: {'), newName: 'seen' });
    const renamed = applyEdits(text, edit.changes[uri]);
    // The world's interface writes it and every soccer behaviour reads it through a port of its
    // name; a flow mapping gets the entry before its brace, a block mapping a line of its own.
    assert.equal(renamed, text
      .replace('      ball_visible: {type: bool}', '      seen: {type: bool}')
      .replace('    sensors: [gait_velocity, head_angle, kick]\n', '    sensors: [gait_velocity, head_angle, kick]\n    ports: {ball_visible: seen}\n')
      .replace('sensors: [ball_visible,', 'sensors: [seen,')
      .replace('{type: soccer.KickBall}', '{type: soccer.KickBall, ports: {ball_visible: seen}}')
      .replace('{type: soccer.GoBehindBall}', '{type: soccer.GoBehindBall, ports: {ball_visible: seen}}')
      .replace('params: {turn_rate: 0.6}}', 'params: {turn_rate: 0.6}, ports: {ball_visible: seen}}')
      .replace('{type: soccer.HeadControl}', '{type: soccer.HeadControl, ports: {ball_visible: seen}}'));
    assert.deepEqual(await client.change(uri, renamed), []);
  });
});

test('renaming an actuator while a class is unknown is refused with the reason, since its ports are not known', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const broken = text.replace('{type: soccer.KickBall}', '{type: soccer.KickBal}');
    await client.change(uri, broken);
    await assert.rejects(client.request('textDocument/rename',
      { textDocument: { uri }, position: positionOf(broken, 'ball_visible: {'), newName: 'seen' }),
    /the class of 'kick_ball' is not known, so whether a port of it binds to 'ball_visible' by name is not/);
    // A behaviour's rename does not depend on ports.
    const edit = await client.request('textDocument/rename',
      { textDocument: { uri }, position: positionOf(broken, 'go_behind_ball: {'), newName: 'approach' });
    assert.equal(edit.changes[uri].length, 3);
  });
});

test("renaming an actuator a scripted behaviour names in its writes: is refused with the error it would leave", async () => {
  await withClient(async (client) => {
    const { uri, text } = json();
    await client.open(uri, text);
    await assert.rejects(client.request('textDocument/rename',
      { textDocument: { uri }, position: positionOf(text, '"kick": {', { skip: 1 }), newName: 'shoot' }),
    /the edit would leave an error it does not know how to avoid: .*walk_and_kick.json:\d+:\d+: 'kick' is not an actuator of layer 'control'/);
  });
});

test('renaming an actuator that ports bind by name adds ports: entries that keep them bound (JSON)', async () => {
  const dir = tempDir();
  const file = path.join(dir, 'walk_and_kick.json');
  const text = `{
  "arbiter": 1,
  "name": "walk_and_kick",
  "plugins": ["soccer"],
  "layers": [
    {
      "name": "world",
      "interface": "soccer.WorldLink",
      "actuators": {
        "ball_visible": {"type": "bool"},
        "ball_position": {"type": "vec2"},
        "robot_pose": {"type": "vec3"}
      },
      "sensors": ["gait_velocity", "head_angle", "kick"]
    },
    {
      "name": "control",
      "sensors": ["ball_visible", "ball_position", "robot_pose"],
      "actuators": {
        "gait_velocity": {"type": "vec3", "aggregate": true, "safe": [0, 0, 0]},
        "head_angle": {"type": "double", "aggregate": true},
        "kick": {"type": "bool", "safe": false}
      },
      "behaviours": {
        "kick_ball": "soccer.KickBall",
        "go_behind_ball": {
          "type": "soccer.GoBehindBall"
        },
        "search_for_ball": {"type": "soccer.SearchForBall", "ports": {}},
        "head_control": {"type": "soccer.HeadControl", "ports": {"ball_position": "ball_position"}}
      },
      "inhibitions": ["kick_ball => go_behind_ball", "go_behind_ball => search_for_ball", "search_for_ball -> head_control"]
    }
  ]
}
`;
  fs.writeFileSync(file, text);
  await withClient(async (client) => {
    const uri = uriOf(file);
    assert.deepEqual(await client.open(uri, text), []);
    const edit = await client.request('textDocument/rename',
      { textDocument: { uri }, position: positionOf(text, '"ball_visible": {', { skip: 1 }), newName: 'seen' });
    const renamed = applyEdits(text, edit.changes[uri]);
    // A behaviour given as its class alone becomes a mapping; an empty or a multi-line ports:
    // gets the entry; one that binds the port already is left alone.
    assert.equal(renamed, text
      .replace('"ball_visible": {"type": "bool"}', '"seen": {"type": "bool"}')
      .replace('"sensors": ["gait_velocity", "head_angle", "kick"]', '"sensors": ["gait_velocity", "head_angle", "kick"], "ports": {"ball_visible": "seen"}')
      .replace('"sensors": ["ball_visible",', '"sensors": ["seen",')
      .replace('"kick_ball": "soccer.KickBall"', '"kick_ball": {"type": "soccer.KickBall", "ports": {"ball_visible": "seen"}}')
      .replace('"type": "soccer.GoBehindBall"\n', '"type": "soccer.GoBehindBall", "ports": {"ball_visible": "seen"}\n')
      .replace('"ports": {}', '"ports": {"ball_visible": "seen"}')
      .replace('"ball_position": "ball_position"}', '"ball_position": "ball_position", "ball_visible": "seen"}'));
    fs.writeFileSync(file, renamed);
    assert.deepEqual(validated(file), []);
  });
});

for (const [format, config] of [['YAML', yaml], ['JSON', json]]) {
  test(`code actions on a ${format} inhibition flip its chaining and remove it, changing only its text`, async () => {
    await withClient(async (client) => {
      const { uri, text } = config();
      await client.open(uri, text);
      const needle = 'kick_ball => go_behind_ball';
      const at = positionOf(text, needle, { skip: 3 });
      const actions = await client.request('textDocument/codeAction',
        { textDocument: { uri }, range: { start: at, end: at }, context: { diagnostics: [] } });
      const flip = actions.find((a) => a.title === "Make 'kick_ball => go_behind_ball' non-chaining (->)");
      assert.ok(flip, JSON.stringify(actions.map((a) => a.title)));
      const flipped = applyEdits(text, flip.edit.changes[uri]);
      assert.equal(flipped, text.replace(needle, 'kick_ball -> go_behind_ball'));
      const remove = actions.find((a) => a.title === "Remove the inhibition 'kick_ball => go_behind_ball'");
      assert.ok(remove);
      const removed = applyEdits(text, remove.edit.changes[uri]);
      assert.equal(removed, format === 'YAML'
        ? text.replace('      - kick_ball => go_behind_ball\n', '')
        : text.replace('        "kick_ball => go_behind_ball",\n', ''));
      // What the server then reports is what validate reports on the edited file.
      const dir = tempDir();
      for (const edited of [flipped, removed]) {
        const file = path.join(dir, path.basename(uri));
        fs.writeFileSync(file, edited);
        assert.deepEqual(summary(await client.change(uri, edited)), validated(file));
      }
    });
  });
}

test('a code action on a behaviour\'s declaration removes it with the inhibitions that name it, as the studio does', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const at = positionOf(text, 'head_control: {type', { skip: 2 });
    const actions = await client.request('textDocument/codeAction',
      { textDocument: { uri }, range: { start: at, end: at }, context: { diagnostics: [] } });
    const remove = actions.find((a) => a.title === "Remove the behaviour 'head_control' and the inhibitions that name it");
    assert.ok(remove, JSON.stringify(actions.map((a) => a.title)));
    // Offered without its edit, which loads the config again to check it: computed when chosen.
    assert.equal(remove.edit, undefined);
    const removed = applyEdits(text, (await client.request('codeAction/resolve', remove)).edit.changes[uri]);
    assert.equal(removed, text.replace(/      head_control: \{type: soccer\.HeadControl\}\n/, '')
      .replace('      - search_for_ball -> head_control\n', ''));
    const file = path.join(tempDir(), path.basename(uri));
    fs.writeFileSync(file, removed);
    assert.deepEqual(validated(file), []);
  });
});

test('a code action on a selection of behaviours of a layer adds an inhibition between the first and the last, either way the config allows', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const range = { start: positionOf(text, 'kick_ball: {type'), end: positionOf(text, 'search_for_ball: {type', { skip: 15 }) };
    const actions = await client.request('textDocument/codeAction',
      { textDocument: { uri }, range, context: { diagnostics: [] } });
    const titles = actions.map((a) => a.title);
    const add = actions.find((a) => a.title === "Add the inhibition 'kick_ball => search_for_ball'");
    assert.ok(add, JSON.stringify(titles));
    assert.ok(titles.includes("Add the inhibition 'kick_ball -> search_for_ball'"), JSON.stringify(titles));
    // The other way closes a cycle through go_behind_ball: not offered.
    assert.ok(!titles.some((t) => t.startsWith("Add the inhibition 'search_for_ball")), JSON.stringify(titles));
    const added = applyEdits(text, add.edit.changes[uri]);
    assert.equal(added, text.replace('      - search_for_ball -> head_control\n',
      '      - search_for_ball -> head_control\n      - kick_ball => search_for_ball\n'));
    const file = path.join(tempDir(), path.basename(uri));
    fs.writeFileSync(file, added);
    assert.deepEqual(validated(file).filter((d) => d.severity === 1), []);
    // One behaviour alone: no inhibition to offer.
    const one = await client.request('textDocument/codeAction',
      { textDocument: { uri }, range: { start: range.start, end: range.start }, context: { diagnostics: [] } });
    assert.ok(!one.some((a) => a.title.startsWith('Add the inhibition')));
  });
});

test('the inhibition added from a selection in JSON is a JSON string after the last one, as the studio adds it', async () => {
  await withClient(async (client) => {
    const { uri, text } = json();
    await client.open(uri, text);
    const range = { start: positionOf(text, '"kick_ball": {', { skip: 1 }), end: positionOf(text, '"search_for_ball": {', { skip: 16 }) };
    const actions = await client.request('textDocument/codeAction',
      { textDocument: { uri }, range, context: { diagnostics: [] } });
    const add = actions.find((a) => a.title === "Add the inhibition 'kick_ball -> search_for_ball'");
    assert.ok(add, JSON.stringify(actions.map((a) => a.title)));
    const added = applyEdits(text, add.edit.changes[uri]);
    assert.equal(added, text.replace('"search_for_ball -> head_control"\n',
      '"search_for_ball -> head_control", "kick_ball -> search_for_ball"\n'));
    const file = path.join(tempDir(), path.basename(uri));
    fs.writeFileSync(file, added);
    assert.deepEqual(validated(file).filter((d) => d.severity === 1), []);
  });
});

test("a code action on a layer's name adds a behaviour of a registered class, its edit checked when it is chosen", async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const at = positionOf(text, 'name: control', { skip: 7 });
    const actions = await client.request('textDocument/codeAction',
      { textDocument: { uri }, range: { start: at, end: at }, context: { diagnostics: [] } });
    const titles = actions.map((a) => a.title);
    // The config's plugin's classes with the built-ins.
    assert.ok(titles.includes("Add a behaviour of class 'scripted' to layer 'control'"), JSON.stringify(titles));
    const kick = actions.find((a) => a.title === "Add a behaviour of class 'soccer.KickBall' to layer 'control'");
    assert.ok(kick, JSON.stringify(titles));
    assert.equal(kick.edit, undefined);
    const resolved = await client.request('codeAction/resolve', kick);
    const added = applyEdits(text, resolved.edit.changes[uri]);
    // kick_ball is taken: the next free name.
    assert.equal(added, text.replace('      head_control: {type: soccer.HeadControl}\n',
      '      head_control: {type: soccer.HeadControl}\n      kick_ball_2: {type: soccer.KickBall}\n'));
    const file = path.join(tempDir(), path.basename(uri));
    fs.writeFileSync(file, added);
    assert.deepEqual(validated(file).filter((d) => d.severity === 1), []);
    // A class the config cannot take as it is (the goalie's ports bind actuators the config does
    // not have) is refused when it is chosen, with the error it would leave.
    const goalie = actions.find((a) => a.title === "Add a behaviour of class 'soccer.Goalie' to layer 'control'");
    assert.ok(goalie, JSON.stringify(titles));
    await assert.rejects(client.request('codeAction/resolve', goalie), /would leave an error.*goalie/);
  });
});

// The code actions at `needle` (plus `skip` characters) of an open file, by title.
async function actionsAt(client, uri, text, needle, skip = 0) {
  const at = positionOf(text, needle, { skip });
  const actions = await client.request('textDocument/codeAction',
    { textDocument: { uri }, range: { start: at, end: at }, context: { diagnostics: [] } });
  return new Map(actions.map((a) => [a.title, a]));
}

// `text` with the edit of the resolved action `action` applied; the action came without one.
async function resolved(client, uri, text, action) {
  assert.ok(action);
  assert.equal(action.edit, undefined);
  const done = await client.request('codeAction/resolve', action);
  return applyEdits(text, done.edit.changes[uri]);
}

test("code actions on a behaviour's declaration move it up and down its layer, as the studio does", async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const actions = await actionsAt(client, uri, text, 'go_behind_ball: {type', 2);
    const up = await resolved(client, uri, text, actions.get("Move the behaviour 'go_behind_ball' up"));
    assert.equal(up, text.replace('      kick_ball: {type: soccer.KickBall}\n      go_behind_ball: {type: soccer.GoBehindBall}\n',
      '      go_behind_ball: {type: soccer.GoBehindBall}\n      kick_ball: {type: soccer.KickBall}\n'));
    const down = await resolved(client, uri, text, actions.get("Move the behaviour 'go_behind_ball' down"));
    assert.equal(down, text.replace('      go_behind_ball: {type: soccer.GoBehindBall}\n      search_for_ball: {type: soccer.SearchForBall, params: {turn_rate: 0.6}}\n',
      '      search_for_ball: {type: soccer.SearchForBall, params: {turn_rate: 0.6}}\n      go_behind_ball: {type: soccer.GoBehindBall}\n'));
    for (const moved of [up, down]) {
      const file = path.join(tempDir(), path.basename(uri));
      fs.writeFileSync(file, moved);
      assert.deepEqual(validated(file).filter((d) => d.severity === 1), []);
    }
    // The first has no place above it, the last none below.
    const first = await actionsAt(client, uri, text, 'kick_ball: {type', 2);
    assert.ok(!first.has("Move the behaviour 'kick_ball' up"), JSON.stringify([...first.keys()]));
    assert.ok(first.has("Move the behaviour 'kick_ball' down"));
    const last = await actionsAt(client, uri, text, 'head_control: {type', 2);
    assert.ok(!last.has("Move the behaviour 'head_control' down"), JSON.stringify([...last.keys()]));
    assert.ok(last.has("Move the behaviour 'head_control' up"));
  });
});

test('a JSON behaviour moved down takes its lines and keeps the commas right', async () => {
  await withClient(async (client) => {
    const { uri, text } = json();
    await client.open(uri, text);
    const actions = await actionsAt(client, uri, text, '"search_for_ball": {', 1);
    const moved = await resolved(client, uri, text, actions.get("Move the behaviour 'search_for_ball' down"));
    const block = (name, next) => text.slice(text.indexOf(`        "${name}": {`), text.indexOf(next));
    const search = block('search_for_ball', '        "head_control"');
    const head = block('head_control', '      },\n      "inhibitions"');
    assert.equal(moved, text.replace(search + head,
      head.replace(/\n$/, ',\n') + search.replace(/,\n$/, '\n')));
    assert.deepEqual(Object.keys(JSON.parse(moved).layers[0].behaviours),
      ['kick_ball', 'go_behind_ball', 'head_control', 'search_for_ball']);
    const file = path.join(tempDir(), path.basename(uri));
    fs.writeFileSync(file, moved);
    assert.deepEqual(validated(file).filter((d) => d.severity === 1), []);
  });
});

test("code actions on a layer's name move it among its file's layers", async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const control = await actionsAt(client, uri, text, 'name: control', 7);
    assert.ok(!control.has("Move the layer 'control' down"), JSON.stringify([...control.keys()]));
    const moved = await resolved(client, uri, text, control.get("Move the layer 'control' up"));
    const world = text.slice(text.indexOf('  - name: world'), text.indexOf('  - name: control'));
    const rest = text.slice(text.indexOf('  - name: control'));
    assert.equal(moved, text.replace(world + rest, rest + '\n' + world.replace(/\n\n$/, '\n')));
    const top = await actionsAt(client, uri, text, 'name: world', 7);
    assert.ok(top.has("Move the layer 'world' down"), JSON.stringify([...top.keys()]));
    assert.ok(!top.has("Move the layer 'world' up"));
  });
});

test('a code action on an actuator removes it when nothing uses it, and is refused with the error a use it cannot see would leave', async () => {
  await withClient(async (client) => {
    const original = yaml();
    const uri = original.uri;
    const spare = '      spare: {type: bool}   # not read by anything\n';
    const text = original.text.replace('    behaviours:\n', spare + '    behaviours:\n');
    await client.open(uri, text);
    const actions = await actionsAt(client, uri, text, 'spare: {type', 1);
    assert.equal(await resolved(client, uri, text, actions.get("Remove the actuator 'spare'")), original.text);
    // The world layer reads kick: not offered.
    const kick = await actionsAt(client, uri, text, 'kick: {type', 1);
    assert.ok(![...kick.keys()].some((t) => t.startsWith('Remove the actuator')), JSON.stringify([...kick.keys()]));
    // In JSON a scripted behaviour writes it, which only the check by loading finds.
    const config = json();
    await client.open(config.uri, config.text);
    const written = await actionsAt(client, config.uri, config.text, '"kick": {"type"', 1);
    const remove = written.get("Remove the actuator 'kick'");
    assert.ok(remove, JSON.stringify([...written.keys()]));
    await assert.rejects(client.request('codeAction/resolve', remove), /would leave an error.*kick/);
  });
});

test("code actions on a state machine's queue item move it and take it out of the queue", async () => {
  await withClient(async (client) => {
    const { uri, text } = read('configs/paper/goalie_plan.yaml');
    await client.open(uri, text);
    const actions = await actionsAt(client, uri, text, '- obstacle_ahead', 2);
    const walk = "      - walk_to_pose: {hold: 6}   # into the goal: (0.0, -4.2, 1.57)\n";
    const up = await resolved(client, uri, text, actions.get("Move 'obstacle_ahead' up in the queue"));
    assert.equal(up, text.replace(walk + '      - obstacle_ahead\n', '      - obstacle_ahead\n' + walk));
    const down = await resolved(client, uri, text, actions.get("Move 'obstacle_ahead' down in the queue"));
    assert.equal(down, text.replace('      - obstacle_ahead\n      - monitor_ball\n', '      - monitor_ball\n      - obstacle_ahead\n'));
    const removed = await resolved(client, uri, text, actions.get("Remove 'obstacle_ahead' from the queue"));
    assert.equal(removed, text.replace('      - obstacle_ahead\n', ''));
    // Offered, then the queue edited before the choice: the item at its position is another
    // state now, and the action is refused rather than made on it.
    await client.change(uri, up);
    await assert.rejects(client.request('codeAction/resolve', actions.get("Remove 'obstacle_ahead' from the queue")),
                         /queue of state machine 'goalie' changed since the action was offered/);
    await client.change(uri, text);
    for (const edited of [up, down, removed]) {
      const file = path.join(tempDir(), path.basename(uri));
      fs.writeFileSync(file, edited);
      assert.deepEqual(validated(file).filter((d) => d.severity === 1), []);
    }
    // An item with params, found by its state's name; the last has no place below it.
    const last = await actionsAt(client, uri, text, '      - monitor_ball', 8);
    assert.ok(last.has("Move 'monitor_ball' up in the queue"), JSON.stringify([...last.keys()]));
    assert.ok(!last.has("Move 'monitor_ball' down in the queue"));
    const withParams = await actionsAt(client, uri, text, '- walk_to_pose: {hold: 6}', 2);
    assert.ok(withParams.has("Remove 'walk_to_pose' from the queue"), JSON.stringify([...withParams.keys()]));
    // A state named elsewhere than in the queue (a pre-emption) gets no queue action.
    const preempt = await actionsAt(client, uri, text, 'go_to: wait_for_button', 6);
    assert.ok(![...preempt.keys()].some((t) => t.includes('queue')), JSON.stringify([...preempt.keys()]));
  });
});

test("code actions on a layer's name remove it when no other layer reads it and add a layer after it", async () => {
  await withClient(async (client) => {
    const original = yaml();
    const uri = original.uri;
    // The world and control layers read each other's actuators: neither is offered.
    await client.open(uri, original.text);
    const control = await actionsAt(client, uri, original.text, 'name: control', 7);
    assert.ok(!control.has("Remove the layer 'control'"), JSON.stringify([...control.keys()]));
    const added = await resolved(client, uri, original.text, control.get("Add a layer after 'control'"));
    assert.equal(added, original.text + '  - name: layer\n');
    const world = await actionsAt(client, uri, original.text, 'name: world', 7);
    const between = await resolved(client, uri, original.text, world.get("Add a layer after 'world'"));
    assert.equal(between, original.text.replace('\n  - name: control', '\n  - name: layer\n  - name: control'));
    for (const edited of [added, between]) {
      const file = path.join(tempDir(), path.basename(uri));
      fs.writeFileSync(file, edited);
      assert.deepEqual(validated(file).filter((d) => d.severity === 1), []);
    }
    // A layer nothing reads goes with its lines.
    const spare = '  - name: spare\n    actuators: {probe: {type: bool}}\n';
    const text = original.text + spare;
    await client.change(uri, text);
    const actions = await actionsAt(client, uri, text, 'name: spare', 7);
    const remove = actions.get("Remove the layer 'spare'");
    assert.equal(await resolved(client, uri, text, remove), original.text);
    // Chosen after the text changed so that another layer reads it: refused with the readers.
    const read = text.replace('sensors: [ball_visible, ball_position, robot_pose]', 'sensors: [ball_visible, ball_position, robot_pose, probe]');
    await client.change(uri, read);
    await assert.rejects(client.request('codeAction/resolve', remove),
      { message: "layer 'spare' is still used: layer 'control' reads its actuator 'probe'. Remove those sensors first" });
  });
});

test("code actions add another layer's actuator as a sensor on a layer's name and remove a sensor on its name, refused while a port binds it", async () => {
  await withClient(async (client) => {
    const original = yaml();
    const uri = original.uri;
    const text = original.text.replace('      robot_pose: {type: vec3}      # x, y, heading on the field\n',
      '      robot_pose: {type: vec3}      # x, y, heading on the field\n      spare: {type: bool}\n');
    await client.open(uri, text);
    const control = await actionsAt(client, uri, text, 'name: control', 7);
    const sensors = [...control.keys()].filter((t) => t.startsWith('Add the sensor'));
    // The only actuator of another layer that control does not read yet; none of its own.
    assert.deepEqual(sensors, ["Add the sensor 'spare' to layer 'control'"]);
    const reading = text.replace('sensors: [ball_visible, ball_position, robot_pose]', 'sensors: [ball_visible, ball_position, robot_pose, spare]');
    assert.equal(await resolved(client, uri, text, control.get(sensors[0])), reading);
    await client.change(uri, reading);
    const unread = await actionsAt(client, uri, reading, 'robot_pose, spare]', 12);
    assert.equal(await resolved(client, uri, reading, unread.get("Remove the sensor 'spare' from layer 'control'")), text);
    // The control layer's behaviours bind ball_visible by name: refused with the error it would leave.
    const bound = await actionsAt(client, uri, reading, 'sensors: [ball_visible', 10);
    const remove = bound.get("Remove the sensor 'ball_visible' from layer 'control'");
    assert.ok(remove, JSON.stringify([...bound.keys()]));
    await assert.rejects(client.request('codeAction/resolve', remove), /would leave an error.*ball_visible/);
    // In JSON, the sensor goes with its comma.
    const file = path.join(tempDir(), 'pair.json');
    const pair = '{\n  "arbiter": 1,\n  "name": "pair",\n  "layers": [\n' +
      '    {"name": "top", "actuators": {"a": {"type": "bool"}, "b": {"type": "bool"}}},\n' +
      '    {"name": "low", "sensors": ["a", "b"]}\n  ]\n}\n';
    fs.writeFileSync(file, pair);
    await client.open(uriOf(file), pair);
    const low = await actionsAt(client, uriOf(file), pair, '["a", "b"]', 2);
    assert.equal(await resolved(client, uriOf(file), pair, low.get("Remove the sensor 'a' from layer 'low'")),
      pair.replace('["a", "b"]', '["b"]'));
  });
});

test("code actions on a state machine's name remove it when nothing names it and add another", async () => {
  await withClient(async (client) => {
    const { uri, text } = read('configs/paper/goalie_plan.yaml');
    await client.open(uri, text);
    const actions = await actionsAt(client, uri, text, '  goalie:', 2);
    const removed = await resolved(client, uri, text, actions.get("Remove the state machine 'goalie'"));
    assert.equal(removed, text.slice(0, text.indexOf('\nstate_machines:') + 1));
    const added = await resolved(client, uri, text, actions.get('Add a state machine'));
    assert.equal(added, text + '  machine:\n    states: {}\n    queue: []\n');
    for (const edited of [removed, added]) {
      const file = path.join(tempDir(), path.basename(uri));
      fs.writeFileSync(file, edited);
      assert.deepEqual(validated(file).filter((d) => d.severity === 1), []);
    }
    // A machine a behaviour or a state steps is not offered for removal.
    const hierarchical = read('configs/paper/hierarchical.yaml');
    await client.open(hierarchical.uri, hierarchical.text);
    for (const machine of ['match', 'attack_plan']) {
      const named = await actionsAt(client, hierarchical.uri, hierarchical.text, `  ${machine}:\n`, 2);
      assert.ok(named.has('Add a state machine'), JSON.stringify([...named.keys()]));
      assert.ok(!named.has(`Remove the state machine '${machine}'`), JSON.stringify([...named.keys()]));
    }
  });
});

test("code actions on a top-level key add a layer at the end, a state machine, and a plugin the config does not name", async () => {
  await withClient(async (client) => {
    const { uri, text } = read('configs/paper/goalie_plan.yaml');
    await client.open(uri, text);
    const actions = await actionsAt(client, uri, text, 'rate_hz: 10', 2);
    assert.equal(await resolved(client, uri, text, actions.get('Add the plugin \'soccer\'')),
      text + 'plugins: [soccer]\n');
    assert.equal(await resolved(client, uri, text, actions.get('Add a layer at the end')),
      text + 'layers:\n  - name: layer\n');
    assert.ok(actions.has('Add a state machine'), JSON.stringify([...actions.keys()]));
    // Not on a value, and a plugin named already is not offered again.
    assert.ok(!(await actionsAt(client, uri, text, 'rate_hz: 10', 9)).has('Add a state machine'));
    const soccer = yaml();
    await client.open(soccer.uri, soccer.text);
    const named = await actionsAt(client, soccer.uri, soccer.text, 'plugins: [soccer]', 1);
    assert.ok(named.has('Add a layer at the end'), JSON.stringify([...named.keys()]));
    assert.ok(!named.has("Add the plugin 'soccer'"), JSON.stringify([...named.keys()]));
  });
});

test('completion items replace the word typed, a dotted prefix included', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const edited = text.replace('kick_ball: {type: soccer.KickBall}', 'kick_ball: {type: soccer.}');
    await client.change(uri, edited);
    const at = positionOf(edited, 'soccer.}', { skip: 7 });
    const result = await client.request('textDocument/completion', { textDocument: { uri }, position: at });
    const item = result.items.find((i) => i.label === 'soccer.GoBehindBall');
    assert.ok(item, JSON.stringify(result.items));
    assert.deepEqual(item.textEdit, { range: rangeOf(edited, 'soccer.}', { length: 7 }), newText: 'soccer.GoBehindBall' });
    assert.equal(applyEdits(edited, [item.textEdit]), text.replace('soccer.KickBall}', 'soccer.GoBehindBall}'));
    // Every item carries its range, an empty one where nothing is typed yet.
    const keys = await client.request('textDocument/completion',
      { textDocument: { uri }, position: positionOf(text, 'rate_hz: 15\n', { skip: 12 }) });
    assert.ok(keys.items.length > 0);
    for (const i of keys.items) assert.deepEqual(i.textEdit.range.start, i.textEdit.range.end, i.label);
  });
});

test('completion works inside YAML flow mappings and sequences', async () => {
  await withClient(async (client) => {
    const plan = read('configs/paper/goalie_plan.yaml');
    await client.open(plan.uri, plan.text);
    const labels = async (uri, edited, needle, skip) => {
      await client.change(uri, edited);
      const result = await client.request('textDocument/completion',
        { textDocument: { uri }, position: positionOf(edited, needle, { skip }) });
      return result.items.map((i) => i.label).sort();
    };
    const states = ['monitor_ball', 'obstacle_ahead', 'wait_for_button', 'walk_to_pose'];
    // A pre-emption's go_to: in a flow mapping that is a sequence item.
    let edited = plan.text.replace('{cycle: 40, go_to: wait_for_button}', '{cycle: 40, go_to: }');
    assert.deepEqual(await labels(plan.uri, edited, 'go_to: }', 7), states);
    // A state planned by a scripted state's append: (a name, or the key of {name: {params}}).
    edited = plan.text.replace('monitor_ball]', 'mon]');
    assert.deepEqual(await labels(plan.uri, edited, 'mon]', 3), states);
    edited = plan.text.replace('prepend: [{walk_to_pose: {hold: 2}}', 'prepend: [{wal: {hold: 2}}');
    assert.deepEqual(await labels(plan.uri, edited, '[{wal', 5), states);

    // The params of a behaviour's class in `params: {`, for a behaviour the last config that
    // parsed did not have yet.
    const { uri, text } = yaml();
    await client.open(uri, text);
    edited = text.replace('      head_control: {type: soccer.HeadControl}',
      '      head_control: {type: soccer.HeadControl}\n      searching: {type: soccer.SearchForBall, params: {tu');
    const params = await labels(uri, edited, 'params: {tu', 11);
    assert.ok(params.includes('turn_rate') && params.includes('walk_speed'), params.join());
  });
});

test('a file that does not parse gets its syntax error located and keeps completion', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    await client.open(uri, text);
    const broken = text.replace('      kick: {type: bool, safe: false}', '      kick: {type: bool, safe: false\n      x: ]');
    assert.notEqual(broken, text, 'the config changed: the edit no longer applies');
    const diagnostics = await client.change(uri, broken);
    assert.equal(diagnostics.length, 1, JSON.stringify(diagnostics));
    assert.equal(diagnostics[0].source, 'arbiter');
    assert.ok(diagnostics[0].range.start.line >= positionOf(broken, 'kick: {type: bool, safe: false').line);
    const edited = broken.replace('search_for_ball -> head_control', 'search_for_ball -> he');
    await client.change(uri, edited);
    const result = await client.request('textDocument/completion',
      { textDocument: { uri }, position: positionOf(edited, '-> he', { skip: 5 }) });
    assert.ok(result.items.some((i) => i.label === 'head_control'));
  });
});

test("an included file's diagnostics are published on that file, and its open buffer wins over the disk", async () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'arbiter-lsp-'));
  try {
    const main = path.join(dir, 'main.yaml');
    const part = path.join(dir, 'part.yaml');
    const mainText = 'arbiter: 1\nname: m\ninclude: [part.yaml]\nlayers:\n  - name: control\n    actuators:\n      speed: {type: double}\n    behaviours:\n      a: {type: scripted, params: {activation: 1}}\n';
    const partText = 'arbiter: 1\nlayers:\n  - name: other\n    actuators:\n      size: {type: double}\n    behaviours:\n      b: {type: scripted, params: {activation: 1}}\n';
    fs.writeFileSync(main, mainText);
    fs.writeFileSync(part, partText);
    await withClient(async (client) => {
      assert.deepEqual(await client.open(uriOf(main), mainText), []);
      const [definition] = [await client.request('textDocument/definition',
        { textDocument: { uri: uriOf(main) }, position: positionOf(mainText, 'part.yaml', { skip: 1 }) })];
      assert.equal(definition.uri, uriOf(part));
      // The included file opened and broken in the editor (not on disk).
      const partBroken = partText.replace('type: scripted', 'type: scriptd');
      const published = client.published(uriOf(part));
      await client.connection.sendNotification('textDocument/didOpen',
        { textDocument: { uri: uriOf(part), languageId: 'yaml', version: 1, text: partBroken } });
      const diagnostics = await published;
      assert.equal(diagnostics.length, 1, JSON.stringify(diagnostics));
      assert.equal(diagnostics[0].code, 'unknown-class');
      assert.deepEqual(diagnostics[0].range, rangeOf(partBroken, 'scriptd'));
      assert.deepEqual(client.diagnostics.get(uriOf(main)), []);
      assert.deepEqual(await client.change(uriOf(part), partText, uriOf(part)), []);
    });
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

// A config that includes parts/part.yaml, written to a temporary folder.
function includeFixture() {
  const dir = tempDir();
  fs.mkdirSync(path.join(dir, 'parts'));
  const main = path.join(dir, 'main.yaml');
  const part = path.join(dir, 'parts', 'part.yaml');
  const mainText = 'arbiter: 1\nname: m\ninclude: [parts/part.yaml]\nlayers:\n  - name: control\n    actuators:\n      speed: {type: double}\n    behaviours:\n      a: {type: scripted, params: {activation: 1}}\n';
  const partText = 'layers:\n  - name: other\n    actuators:\n      size: {type: double}\n    behaviours:\n      b: {type: scripted, params: {activation: 1}}\n';
  fs.writeFileSync(main, mainText);
  fs.writeFileSync(part, partText);
  return { dir, main, part, mainText, partText, partBroken: partText.replace('type: scripted', 'type: scriptd') };
}

test('an included file opened on its own is checked through the config that includes it on the disk', async () => {
  const { dir, main, part, partText, partBroken } = includeFixture();
  try {
    await withClient(async (client) => {
      assert.deepEqual(await client.open(uriOf(part), partText), []);
      // Its real problem shows.
      const [error, ...rest] = await client.change(uriOf(part), partBroken);
      assert.deepEqual(rest, []);
      assert.equal(error.code, 'unknown-class');
      assert.deepEqual(error.range, rangeOf(partBroken, 'scriptd'));
      fs.writeFileSync(part, partBroken);
      assert.deepEqual(summary([error]), validated(main));
    });
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test("closing the including file keeps the included file's real error", async () => {
  const { dir, main, part, mainText, partBroken } = includeFixture();
  try {
    await withClient(async (client) => {
      assert.deepEqual(await client.open(uriOf(main), mainText), []);
      const [error] = await client.open(uriOf(part), partBroken);
      assert.equal(error.code, 'unknown-class');
      const published = client.published(uriOf(part));
      await client.connection.sendNotification('textDocument/didClose', { textDocument: { uri: uriOf(main) } });
      const [still, ...rest] = await published;
      assert.deepEqual(rest, []);
      assert.deepEqual(still, error);
    });
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('an include cycle is an error on the root file, at the include that leads into it', async () => {
  const dir = tempDir();
  try {
    const root = path.join(dir, 'root.yaml');
    const rootText = 'arbiter: 1\nname: r\ninclude: [a.yaml]\nlayers:\n  - name: top\n';
    fs.writeFileSync(root, rootText);
    fs.writeFileSync(path.join(dir, 'a.yaml'), 'include: [b.yaml]\nlayers:\n  - name: from_a\n');
    fs.writeFileSync(path.join(dir, 'b.yaml'), 'include: [root.yaml]\nlayers:\n  - name: from_b\n');
    assert.deepEqual(validated(root).map((d) => d.code), ['include-cycle']);
    await withClient(async (client) => {
      const [cycle, ...rest] = await client.open(uriOf(root), rootText);
      assert.deepEqual(rest, []);
      assert.equal(cycle.code, 'include-cycle');
      assert.equal(cycle.severity, 1);
      assert.deepEqual(cycle.range, rangeOf(rootText, 'a.yaml'));
      assert.match(cycle.message, /^in included file b\.yaml: include cycle: /);
      assert.equal(cycle.relatedInformation[0].location.uri, uriOf(path.join(dir, 'b.yaml')));
      assert.equal(client.diagnostics.get(uriOf(path.join(dir, 'b.yaml')))[0].code, 'include-cycle');
    });
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('an included file changed on the disk is noticed through workspace/didChangeWatchedFiles, registered when the client can', { timeout: 20000 }, async () => {
  const { dir, main, part, mainText, partBroken } = includeFixture();
  const client = new Client();
  const registered = new Promise((resolve) => client.connection.onRequest('client/registerCapability', (params) => {
    resolve(params);
    return null;
  }));
  try {
    await client.connection.sendRequest('initialize', { processId: process.pid, rootUri: uriOf(dir),
      capabilities: { workspace: { didChangeWatchedFiles: { dynamicRegistration: true } } } });
    await client.connection.sendNotification('initialized', {});
    const { registrations: [registration] } = await registered;
    assert.equal(registration.method, 'workspace/didChangeWatchedFiles');
    assert.ok(registration.registerOptions.watchers.some((w) => w.globPattern.includes('yaml')));
    assert.deepEqual(await client.open(uriOf(main), mainText), []);
    fs.writeFileSync(part, partBroken);
    const published = [client.published(uriOf(main)), client.published(uriOf(part))];
    await client.connection.sendNotification('workspace/didChangeWatchedFiles',
      { changes: [{ uri: uriOf(part), type: 2 }] });
    const [[onInclude], [onPart]] = await Promise.all(published);
    assert.equal(onInclude.code, 'unknown-class');
    assert.deepEqual(onInclude.range, rangeOf(mainText, 'parts/part.yaml'));
    assert.equal(onPart.code, 'unknown-class');
  } finally {
    assert.equal(await client.stop(), 0, client.stderr);
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('an included file opened on its own is checked alone once the config on the disk stops including it', async () => {
  const { dir, main, part, mainText, partText } = includeFixture();
  try {
    await withClient(async (client) => {
      assert.deepEqual(await client.open(uriOf(part), partText), []);
      fs.writeFileSync(main, mainText.replace('include: [parts/part.yaml]\n', ''));
      const published = client.published(uriOf(part));
      await client.connection.sendNotification('workspace/didChangeWatchedFiles',
        { changes: [{ uri: uriOf(main), type: 2 }] });
      // As `arbiter validate` sees it now: a config without its version and name.
      assert.deepEqual(summary(await published), validated(part));
      await client.request('textDocument/documentSymbol', { textDocument: { uri: uriOf(part) } });
      assert.deepEqual(client.diagnostics.get(uriOf(main)) ?? [], []);
    });
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('an included file opened on its own is checked through a config that includes it created on the disk later', async () => {
  const { dir, main, part, mainText, partText } = includeFixture();
  try {
    fs.rmSync(main);
    await withClient(async (client) => {
      // Alone, it is a config without its version and name.
      const alone = await client.open(uriOf(part), partText);
      assert.deepEqual(summary(alone), validated(part));
      assert.notDeepEqual(alone, []);
      fs.writeFileSync(main, mainText);
      await client.connection.sendNotification('workspace/didChangeWatchedFiles',
        { changes: [{ uri: uriOf(main), type: 1 }] });
      // Every notification sent before the reply to a later request has arrived.
      await client.request('textDocument/documentSymbol', { textDocument: { uri: uriOf(part) } });
      assert.deepEqual(client.diagnostics.get(uriOf(part)), []);
      assert.deepEqual(client.diagnostics.get(uriOf(main)) ?? [], []);
    });
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

test('an edit checks again only the configs the edited file belongs to', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    const other = json();
    await client.open(uri, text);
    await client.open(other.uri, other.text);
    const broken = text.replace('kick_ball => go_behind_ball', 'kick_bal => go_behind_ball');
    const before = client.publications.get(other.uri);
    const diagnostics = await client.change(uri, broken);
    // Every notification sent before the reply to a later request has arrived.
    await client.request('textDocument/documentSymbol', { textDocument: { uri } });
    assert.equal(client.publications.get(other.uri), before);
    assert.equal(diagnostics.length, 1);
  });
});

test('a position after a non-ASCII character counts UTF-16 units', async () => {
  await withClient(async (client) => {
    const { uri, text } = yaml();
    const broken = text.replace('      kick_ball: {type: soccer.KickBall}', '      kick_ball: {type: soccer.KickBall}  # 🦶 kick\n      kick_bal2: {type: soccer.KickBal}');
    const diagnostics = await client.open(uri, broken);
    const unknown = diagnostics.find((d) => d.code === 'unknown-class');
    assert.ok(unknown, JSON.stringify(diagnostics));
    assert.deepEqual(unknown.range, rangeOf(broken, 'soccer.KickBal}', { length: 14 }));
  });
});

test('malformed messages get JSON-RPC errors and the server keeps serving', async () => {
  const client = new Client();
  const before = client.request('textDocument/hover', { textDocument: { uri: 'file:///x.yaml' }, position: { line: 0, character: 0 } });
  await assert.rejects(before, (error) => error.code === -32002);
  await client.start();
  await assert.rejects(client.request('arbiter/nonsense', {}), (error) => error.code === -32601);
  // Said in the protocol's words, without the JSON library's own code for the error.
  await assert.rejects(client.request('textDocument/hover', { position: 3 }),
                       (error) => error.code === -32602 && /^invalid params: /.test(error.message) &&
                                  !/json\.exception/.test(error.message));
  // A notification with params it cannot read has no answer: the server says so on stderr.
  const notification = JSON.stringify({ jsonrpc: '2.0', method: 'textDocument/didOpen', params: 5 });
  client.process.stdin.write(`Content-Length: ${notification.length}\r\n\r\n${notification}`);
  // Raw bytes: invalid JSON, valid JSON with a number no double holds, then a frame without
  // Content-Length.
  client.process.stdin.write('Content-Length: 5\r\n\r\n{bad}');
  const huge = '{"id": 1e999999}';
  client.process.stdin.write(`Content-Length: ${huge.length}\r\n\r\n${huge}`);
  client.process.stdin.write('X-Nothing: 1\r\n\r\n');
  const { uri, text } = yaml();
  assert.deepEqual(await client.open(uri, text), []);
  assert.equal(await client.stop(), 0);
  assert.doesNotMatch(client.stderr, /terminate|Segmentation/);
  assert.match(client.stderr, /arbiter lsp: textDocument\/didOpen: invalid params: /);
  assert.doesNotMatch(client.stderr, /json\.exception/);
});

test('after a malformed header or stray bytes between messages the server answers the next well-formed message', { timeout: 20000 }, async () => {
  for (const noise of [
    // a header without its colon, then the message's body
    'Content-Length 59\r\n\r\n{"jsonrpc": "2.0", "id": 90, "method": "textDocument/hover"}',
    // an invalid length, then the body
    'Content-Length: 5x\r\n\r\n{"jsonrpc": "2.0", "id": 91, "method": "shutdown"}',
    // bytes between two messages, with no line end
    'garbage',
    // a body longer than its Content-Length says
    'Content-Length: 2\r\n\r\n{}}}}',
  ]) {
    const client = new Client();
    await client.start();
    client.process.stdin.write(noise);
    const { uri, text } = yaml();
    assert.deepEqual(await client.open(uri, text), [], JSON.stringify(noise));
    assert.equal(await client.stop(), 0, JSON.stringify(noise));
    assert.match(client.stderr, /arbiter lsp: /);
  }
});

test('a --plugin-path that does not exist is a diagnostic on the configs that name plugins, not a failure to start', async () => {
  const client = new Client(['--plugin-path', '/nonexistent/plugins']);
  await client.start();
  try {
    const { uri, text } = yaml();
    const [diagnostic, ...rest] = await client.open(uri, text);
    assert.deepEqual(rest, []);
    assert.equal(diagnostic.code, 'plugin-path-not-found');
    assert.equal(diagnostic.severity, 2);
    assert.match(diagnostic.message, /'\/nonexistent\/plugins'/);
    assert.deepEqual(diagnostic.range.start, positionOf(text, '[soccer]'));
  } finally {
    assert.equal(await client.stop(), 0, client.stderr);
  }
});

test('exit without shutdown ends with status 1', async () => {
  const client = new Client();
  await client.start();
  await client.connection.sendNotification('exit');
  assert.equal(await client.exited, 1);
  client.connection.dispose();
});
