// The web view in a real browser: headless Chromium driven by playwright-core.
// Run through web/tests/run.sh (CTest label `browser`), which sets:
//   ARBITER         the arbiter binary
//   ARBITER_SOURCE  the source tree (for the configs)
//   CHROMIUM        the browser (Debian's /usr/bin/chromium)
//   NODE_MODULES    where `npm ci` put playwright-core
//   ARBITER_SCREENSHOT (optional) where to save the screenshot of the soccer demo
import {test as nodeTest, before, after} from 'node:test';
import assert from 'node:assert/strict';
import {spawn, execFileSync} from 'node:child_process';
import {createRequire} from 'node:module';
import {copyFileSync, mkdtempSync, readFileSync, rmSync, writeFileSync} from 'node:fs';
import {tmpdir} from 'node:os';
import path from 'node:path';

// A minute per test, set here: Debian's node 18 has no --test-timeout.
const test = (name, fn) => nodeTest(name, {timeout: 60000}, fn);

const require = createRequire(path.join(process.env.NODE_MODULES, 'package.json'));
const {chromium} = require('playwright-core');

const arbiter = process.env.ARBITER;
const source = process.env.ARBITER_SOURCE;
// Relative to the source tree, where arbiter runs: the explain answers name them so.
const paper = 'configs/paper/walk_and_kick.yaml';
const soccer = 'configs/soccer/walk_and_kick.yaml';
const scratch = mkdtempSync(path.join(tmpdir(), 'arbiter-web-'));
const children = [];
let browser;

before(async () => {
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
});

after(async () => {
  if (browser) await browser.close();
  for (const child of children) child.kill('SIGINT');
  rmSync(scratch, {recursive: true, force: true});
});

/// Starts `arbiter ARGS` and resolves with the URL it prints (with the live view's token, if
/// any), the server's base URL and the token, the process and what it printed so far
/// (`output()`: stdout and stderr).
function serve(args) {
  return new Promise((resolve, reject) => {
    const child = spawn(arbiter, args, {cwd: source, stdio: ['ignore', 'pipe', 'pipe']});
    children.push(child);
    let out = '';
    let err = '';
    const timer = setTimeout(() => reject(new Error(`no URL from arbiter ${args.join(' ')}:\n${out}${err}`)), 15000);
    child.stdout.on('data', (data) => {
      out += data;
      const found = out.match(/(http:\/\/127\.0\.0\.1:\d+\/)(\?token=([\w.-]+))?/);
      if (found) {
        clearTimeout(timer);
        resolve({url: found[0], base: found[1], token: found[3], child, output: () => out + err});
      }
    });
    child.stderr.on('data', (data) => { err += data; });
    child.on('exit', (code) => reject(new Error(`arbiter exited with ${code}:\n${out}${err}`)));
  });
}

async function open(url) {
  const page = await browser.newPage({viewport: {width: 1400, height: 900}});
  page.setDefaultTimeout(10000);
  // Every request the page makes (its favicon too) is answered.
  page.failed = [];
  page.on('response', (response) => {
    if (response.status() >= 400) page.failed.push(`${response.status()} ${response.url()}`);
  });
  await page.goto(url);
  if (await page.locator('#web-app-missing').count()) {
    throw new Error(`this arbiter was built without the web app: ${await page.textContent('body')}`);
  }
  await page.waitForSelector('body[data-ready="true"]');
  await page.waitForSelector('.behaviour');
  return page;
}

const stepShown = (page) => page.$eval('#step', (node) => Number(node.textContent));
const waitForStep = (page, step) =>
  page.waitForFunction((n) => Number(document.querySelector('#step').textContent) === n, step);
const behaviour = (page, name) => page.locator(`.behaviour[data-name="control/${name}"]`);

test('the live page shows every behaviour and inhibition of the config', async () => {
  const {url, base} = await serve(['run', paper, '--serve', '0', '--paused', '--steps', '1000', '-q']);
  const page = await open(url);
  assert.equal(await page.locator('.behaviour').count(), 4);
  assert.equal(await page.locator('#graph .edge').count(), 4);
  assert.equal(await page.locator('#graph .edge[data-kind="chaining"]').count(), 2);
  assert.equal(await page.locator('#graph .edge[data-kind="non-chaining"]').count(), 1);
  const implicit = page.locator('#graph .edge[data-kind="implicit"]');
  assert.equal(await implicit.count(), 1);
  assert.equal(await implicit.getAttribute('data-from'), 'kick_ball');
  assert.equal(await implicit.getAttribute('data-to'), 'search_for_ball');
  assert.equal(await page.locator('.timeline').count(), 4);
  await page.waitForTimeout(300);
  assert.deepEqual(page.failed, [], 'no request of the page fails');
  await page.close();
  // A browser asks for /favicon.ico whatever the page says: answered, with no token needed.
  assert.equal((await fetch(`${base}favicon.ico`)).status, 204);
});

/// Resolves when `child` has exited and closed its output, with all it printed.
const exited = (child, output) => new Promise((resolve) => {
  child.on('close', () => resolve(output()));
});

test('paused, the live page shows the safe values the engine output; single steps print them once', async () => {
  const run = await serve(['run', soccer, '--serve', '0', '--paused', '--steps', '100000']);
  const page = await open(run.url);
  const gait = page.locator('.port.actuator[data-actuator="gait_velocity"] .value');
  await page.click('#resume');
  // Running, the robot walks: the page shows the commands of each step.
  await page.waitForFunction(() => Number(document.querySelector('#step').textContent) >= 20);
  await page.click('#pause');
  await page.waitForSelector('#status.paused');
  // Paused, it shows what the engine output in its safe pass: the robot stands.
  await page.waitForSelector('body[data-safe="true"]');
  assert.equal(await gait.textContent(), '[0, 0, 0]');
  const paused = await stepShown(page);
  for (let step = paused + 1; step <= paused + 3; ++step) {
    await page.click('#single-step');
    await waitForStep(page, step);
    await page.waitForSelector('body[data-safe="true"]');
    assert.equal(await gait.textContent(), '[0, 0, 0]', `the safe values after single step ${step}`);
  }
  // The terminal told the safe values when the run paused, not again after each single step.
  const safeLines = run.output().split('\n').filter((line) => line.includes('safe values output'));
  assert.equal(safeLines.length, 1, safeLines.join('\n'));
  await page.click('#resume');
  await page.waitForFunction(() => document.body.dataset.safe === undefined);
  await page.close();
});

test('after the run, Pause, Step and Resume are gone; the terminal gives the URL with its token', async () => {
  const run = await serve(['run', paper, '--serve', '0', '--steps', '5']);
  const page = await open(run.url);
  await page.waitForSelector('#status.finished');
  assert.equal(await page.isVisible('#live-controls'), false);
  for (const id of ['pause', 'single-step', 'resume']) {
    assert.equal(await page.isDisabled(`#${id}`), true, `#${id} is disabled`);
  }
  await page.waitForFunction(() => Number(document.querySelector('#step').textContent) === 5);
  const over = run.output().match(/the run is over; the live view stays at (\S+) until Ctrl-C/);
  assert.ok(over, run.output());
  assert.equal(over[1], run.url, 'the URL after the run carries the token');
  await page.close();
});

test('Ctrl-C during a served run ends it without promising that the page stays', async () => {
  const run = await serve(['run', paper, '--serve', '0', '--steps', '100000']);
  await new Promise((resolve) => setTimeout(resolve, 500));
  run.child.kill('SIGINT');
  const output = await exited(run.child, run.output);
  assert.match(output, /interrupted: simulated/);
  assert.doesNotMatch(output, /stays at/);
});

test('colours follow the steps; pause, single step and resume drive the engine', async () => {
  const {url} = await serve(['run', paper, '--serve', '0', '--paused', '--steps', '100000', '-q']);
  const page = await open(url);
  const search = behaviour(page, 'search_for_ball');
  const head = behaviour(page, 'head_control');
  // Started paused: nothing has run, and nothing runs until the page says so.
  await page.waitForTimeout(500);
  assert.equal(await stepShown(page), 0);

  await page.click('#single-step');
  await waitForStep(page, 1);
  // Step 1: search_for_ball requests 1 and is not inhibited; it inhibits head_control fully.
  assert.equal(await search.getAttribute('data-activation'), '1');
  assert.equal(await search.getAttribute('data-active'), 'true');
  assert.equal(await head.getAttribute('data-active'), 'false');
  const fullFill = await search.locator('rect').getAttribute('fill');
  const headFill = await head.locator('rect').getAttribute('fill');
  assert.notEqual(fullFill, headFill);

  for (let step = 2; step <= 5; ++step) {
    await page.click('#single-step');
    await waitForStep(page, step);
  }
  // Step 5: go_behind_ball at 0.3 leaves search_for_ball 0.5 × 0.7 = 0.35, head_control 0.65.
  assert.equal(Number(await search.getAttribute('data-activation')).toFixed(2), '0.35');
  assert.equal(Number(await head.getAttribute('data-activation')).toFixed(2), '0.65');
  assert.notEqual(await search.locator('rect').getAttribute('fill'), fullFill);
  await page.waitForTimeout(400);
  assert.equal(await stepShown(page), 5, 'a single step runs one step only');

  // Hovering asks the engine's explain for the step shown.
  await search.hover();
  await page.waitForFunction(() => document.querySelector('#explain').textContent.includes('at step 5'));
  const explanation = await page.textContent('#explain');
  assert.match(explanation, /behaviour search_for_ball \(layer control\) at step 5: active, activation 0\.35/);
  assert.match(explanation, /go_behind_ball\s+activation 0\.3\s+factor 0\.7/);

  await page.click('#resume');
  await page.waitForFunction(() => Number(document.querySelector('#step').textContent) >= 9);
  // Running, the page shows how well the run keeps time.
  await page.waitForSelector('#timing-panel:not([hidden])');
  assert.match(await page.textContent('#timing'), /step duration\s+p50 [\d.]+ µs\s+p99 [\d.]+ µs\s+max [\d.]+ µs/);
  assert.match(await page.textContent('#timing'), /period jitter\s+p50/);
  await page.click('#pause');
  await page.waitForSelector('#status.paused');
  await page.waitForTimeout(300);  // a step already under way may still arrive
  const paused = await stepShown(page);
  await page.waitForTimeout(700);
  assert.equal(await stepShown(page), paused, 'the engine stays paused');
  await page.close();
});

test('a client that reconnects resumes after the last step it saw; many clients at once', async () => {
  const {base, token} = await serve(['run', paper, '--serve', '0', '--steps', '100000', '-q']);
  const firstId = async (headers) => {
    const controller = new AbortController();
    const response = await fetch(`${base}events`,
                                 {headers: {...headers, 'X-Arbiter-Token': token}, signal: controller.signal});
    const reader = response.body.getReader();
    let text = '';
    while (!/\nid: \d+\n/.test(text)) text += new TextDecoder().decode((await reader.read()).value);
    controller.abort();
    return Number(text.match(/\nid: (\d+)\n/)[1]);
  };
  await new Promise((resolve) => setTimeout(resolve, 700));
  const resumed = await firstId({'Last-Event-ID': '3'});
  assert.equal(resumed, 4);
  const ids = await Promise.all(Array.from({length: 12}, () => firstId({})));
  assert.equal(ids.length, 12);
  for (const id of ids) assert.ok(id >= 1);
});

test('an open page redraws the graph when --watch reloads an edited config', async () => {
  const config = path.join(scratch, 'watched.yaml');
  copyFileSync(path.join(source, paper), config);
  const {url} = await serve(['run', config, '--watch', '--serve', '0', '--steps', '100000', '-q']);
  const page = await open(url);
  assert.equal(await page.locator('#graph .behaviour').count(), 4);
  const edited = readFileSync(config, 'utf8').replace(
      '      head_control:\n',
      '      look_around:\n        type: scripted\n        params: {activation: 0.5}\n      head_control:\n');
  writeFileSync(config, edited);
  await page.waitForSelector('.behaviour[data-name="control/look_around"]');
  assert.equal(await page.locator('#graph .behaviour').count(), 5);
  // Steps of the new program arrive: look_around requests 0.5 and nothing inhibits it.
  await page.waitForFunction(() => document.querySelector('.behaviour[data-name="control/look_around"]')
      .getAttribute('data-activation') === '0.5');
  await page.close();
});

test('the trace view scrubs through the recorded steps', async () => {
  const trace = path.join(scratch, 'paper.jsonl');
  execFileSync(arbiter, ['run', paper, '--steps', '20', '--trace', trace, '-q'], {cwd: source});
  const {url} = await serve(['view', paper, '--trace', trace, '--serve', '0']);
  const page = await open(url);
  assert.equal(await page.locator('#trace-controls').isVisible(), true);
  assert.equal(await page.locator('#live-controls').isVisible(), false);
  const kick = behaviour(page, 'kick_ball');
  const scrubTo = (index) => page.$eval('#scrub', (node, value) => {
    node.value = value;
    node.dispatchEvent(new Event('input'));
  }, index);
  await scrubTo(12);  // step 13: kick_ball requests 1
  assert.equal(await stepShown(page), 13);
  assert.equal(await kick.getAttribute('data-active'), 'true');
  assert.equal(await behaviour(page, 'go_behind_ball').getAttribute('data-active'), 'false');
  await scrubTo(3);
  assert.equal(await stepShown(page), 4);
  assert.equal(await kick.getAttribute('data-active'), 'false');
  await page.click('#next');
  assert.equal(await stepShown(page), 5);
  await behaviour(page, 'search_for_ball').hover();
  await page.waitForFunction(() => document.querySelector('#explain').textContent.includes('at step 5'));
  assert.match(await page.textContent('#explain'), /activation = 0\.5 × 1 × 0\.7 = 0\.35/);
  await page.close();
});

test('the trace view lists what behaviour code reported up to the step shown', async () => {
  const trace = path.join(scratch, 'soccer.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '220', '--trace', trace, '-q'], {cwd: source});
  const {url} = await serve(['view', soccer, '--trace', trace, '--serve', '0']);
  const page = await open(url);
  const scrubTo = (index) => page.$eval('#scrub', (node, value) => {
    node.value = value;
    node.dispatchEvent(new Event('input'));
  }, index);
  const reported = () => page.locator('#reported li.event').allTextContents();
  await scrubTo(100);
  assert.deepEqual(await reported(), []);
  await scrubTo(180);
  assert.deepEqual(await reported(), ['step 172  world: ball kicked']);
  await scrubTo(219);
  assert.deepEqual(await reported(), ['step 196  world: goal!', 'step 172  world: ball kicked']);
  await page.close();
});

test('the soccer demo: interface and behaviour layers with their data flow', async () => {
  const {url} = await serve(['run', soccer, '--serve', '0', '--steps', '100000', '-q']);
  const page = await open(url);
  assert.equal(await page.locator('#graph .layer').count(), 2);
  assert.equal(await page.locator('.behaviour').count(), 4);
  // world -> control: ball_visible, ball_position, robot_pose; control -> world: gait_velocity,
  // head_angle, kick.
  assert.equal(await page.locator('#graph .flow').count(), 6);
  await page.waitForFunction(() => Number(document.querySelector('#step').textContent) >= 45);
  assert.equal(await behaviour(page, 'go_behind_ball').getAttribute('data-active'), 'true');
  if (process.env.ARBITER_SCREENSHOT) {
    await behaviour(page, 'go_behind_ball').hover();
    await page.waitForFunction(() => document.querySelector('#explain').textContent.includes('go_behind_ball'));
    await page.screenshot({path: process.env.ARBITER_SCREENSHOT, fullPage: true});
  }
  await page.close();
});

test('the soccer demo: the world beside the graph, the field and the ball moving with the step', async () => {
  const {url} = await serve(['run', soccer, '--serve', '0', '--paused', '--steps', '100000', '-q']);
  const page = await open(url);
  // Nothing has run: no picture yet.
  assert.equal(await page.locator('#scene-panel').isHidden(), true);
  await page.click('#single-step');
  await waitForStep(page, 1);
  await page.waitForSelector('#scene-panel:not([hidden])');
  const picture = () => page.$eval('#scene', (root) => ({
    step: Number(root.dataset.step),
    loops: [...root.querySelectorAll('[data-kind="loop"]')].map((n) => n.getAttribute('points')),
    // The discs, smallest first: the ball (0.075 m), then the robot (0.15 m).
    discs: [...root.querySelectorAll('[data-kind="disc"]')]
      .map((n) => ({r: Number(n.getAttribute('r')), x: Number(n.getAttribute('cx')), y: -Number(n.getAttribute('cy'))}))
      .sort((a, b) => a.r - b.r),
    arrows: root.querySelectorAll('[data-kind="arrow"]').length,
  }));
  const first = await picture();
  assert.equal(first.step, 1);
  // The field's outline (y drawn downwards), the centre circle, the robot's heading.
  assert.ok(first.loops.includes('-4.5,3 4.5,3 4.5,-3 -4.5,-3'), JSON.stringify(first.loops));
  assert.equal(first.discs.length, 2);
  assert.ok(first.arrows >= 1);
  const [ball, robot] = first.discs;
  assert.deepEqual([ball.x, ball.y], [0.5, 1]);  // the config's ball_start
  assert.deepEqual([robot.x, robot.y], [-3, -1]);  // and robot_start
  // Past the kick (step 172 of this config): the ball has gone, the robot walked to it.
  await page.click('#resume');
  await page.waitForFunction(() => Number(document.querySelector('#step').textContent) >= 185, null, {timeout: 40000});
  await page.click('#pause');
  await page.waitForSelector('#status.paused');
  await page.waitForTimeout(300);
  const later = await picture();
  assert.equal(later.step, await stepShown(page), 'the picture is of the step shown');
  const [movedBall, movedRobot] = later.discs;
  assert.ok(Math.hypot(movedBall.x - ball.x, movedBall.y - ball.y) > 1, JSON.stringify(later.discs));
  assert.ok(Math.hypot(movedRobot.x - robot.x, movedRobot.y - robot.y) > 1, JSON.stringify(later.discs));
  await page.close();
});

// Every label of the graph (SVG text) against every inhibition arc and its bar, sampled along
// the path, at each step of the trace; and every arc inside its own layer's box. Returns what
// overlaps, as readable strings.
async function overlapsAtEveryStep(page) {
  return page.evaluate(() => {
    const problems = [];
    const points = [];  // {x, y, r, arc, layer} in page coordinates
    for (const edge of document.querySelectorAll('#graph .edge')) {
      const arc = `${edge.dataset.from} -> ${edge.dataset.to}`;
      for (const shape of edge.querySelectorAll('path, line')) {
        const matrix = shape.getScreenCTM();
        const r = parseFloat(getComputedStyle(shape).strokeWidth) / 2;
        const length = shape.getTotalLength();
        for (let i = 0; i <= 80; ++i) {
          const p = shape.getPointAtLength(length * i / 80);
          const q = new DOMPoint(p.x, p.y).matrixTransform(matrix);
          points.push({x: q.x, y: q.y, r, arc, layer: edge.dataset.layer});
        }
      }
    }
    if (!points.length) problems.push('no arcs drawn');
    for (const point of points) {
      const box = document.querySelector(`#graph .layer[data-layer="${point.layer}"] .layer-box`).getBoundingClientRect();
      if (point.x + point.r > box.right || point.x - point.r < box.left) {
        problems.push(`arc ${point.arc} leaves layer ${point.layer} at x ${point.x.toFixed(1)}`);
        break;
      }
    }
    const scrub = document.querySelector('#scrub');
    for (let index = 0; index <= Number(scrub.max); ++index) {
      scrub.value = index;
      scrub.dispatchEvent(new Event('input'));
      const step = document.querySelector('#step').textContent;
      for (const label of document.querySelectorAll('#graph text')) {
        if (!label.textContent) continue;
        const box = label.getBoundingClientRect();
        for (const p of points) {
          if (p.x + p.r > box.left && p.x - p.r < box.right && p.y + p.r > box.top && p.y - p.r < box.bottom) {
            problems.push(`step ${step}: "${label.textContent}" under the arc ${p.arc}`);
            break;
          }
        }
      }
      // A behaviour's text stays inside its box.
      for (const behaviour of document.querySelectorAll('#graph .behaviour')) {
        const box = behaviour.querySelector('rect').getBoundingClientRect();
        for (const label of behaviour.querySelectorAll('text')) {
          const r = label.getBoundingClientRect();
          if (label.textContent && (r.right > box.right || r.bottom > box.bottom)) {
            problems.push(`step ${step}: "${label.textContent}" runs out of ${behaviour.dataset.name}'s box`);
          }
        }
      }
      if (problems.length > 20) break;
    }
    return problems;
  });
}

for (const [config, what] of [[soccer, 'the soccer demo'], ['tests/data/valid/twin.yaml', 'a config of two behaviour layers'],
                              [paper, 'the paper\'s config'], ['web/tests/crowded.yaml', 'a crowded config of long names and wide arcs']]) {
  test(`no label lies under an inhibition arc: ${what}`, async () => {
    const trace = path.join(scratch, `${path.basename(config)}.jsonl`);
    execFileSync(arbiter, ['run', config, '--steps', '40', '--trace', trace, '-q'], {cwd: source});
    const {url} = await serve(['view', config, '--trace', trace, '--serve', '0']);
    const page = await open(url);
    assert.deepEqual(await overlapsAtEveryStep(page), []);
    await page.close();
  });
}

// ELK's layout, against the graph the page was given: every behaviour and every inhibition of the
// config drawn, with the ends the config gives it; no two behaviour boxes overlapping; no
// inhibition crossing a behaviour box other than its own two; every box inside its layer's.
async function layoutProblems(page) {
  return page.evaluate(async () => {
    const graph = await (await fetch('graph')).json();
    const problems = [];
    const inside = (p, r, margin = 0) =>
      p.x > r.left + margin && p.x < r.right - margin && p.y > r.top + margin && p.y < r.bottom - margin;
    for (const layer of graph.layers) {
      const column = document.querySelector(`#graph .layer[data-layer="${layer.name}"] .layer-box`).getBoundingClientRect();
      const boxes = new Map();
      for (const behaviour of layer.behaviours) {
        const node = document.querySelector(`#graph .behaviour[data-name="${layer.name}/${behaviour.name}"] rect`);
        if (!node) {
          problems.push(`${layer.name}/${behaviour.name} not drawn`);
          continue;
        }
        const r = node.getBoundingClientRect();
        boxes.set(behaviour.name, r);
        if (r.left < column.left || r.right > column.right || r.top < column.top || r.bottom > column.bottom) {
          problems.push(`${layer.name}/${behaviour.name} leaves its layer's box`);
        }
      }
      const names = [...boxes.keys()];
      for (let i = 0; i < names.length; ++i) {
        for (let j = i + 1; j < names.length; ++j) {
          const a = boxes.get(names[i]);
          const b = boxes.get(names[j]);
          if (a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom) {
            problems.push(`${layer.name}: ${names[i]} and ${names[j]} overlap`);
          }
        }
      }
      const drawn = [...document.querySelectorAll(`#graph .edge[data-layer="${layer.name}"]`)];
      if (drawn.length !== layer.inhibitions.length) {
        problems.push(`${layer.name}: ${drawn.length} inhibitions drawn, ${layer.inhibitions.length} in the graph`);
      }
      for (const inhibition of layer.inhibitions) {
        const kind = inhibition.implicit ? 'implicit' : inhibition.chaining ? 'chaining' : 'non-chaining';
        const edge = drawn.find((node) => node.dataset.from === inhibition.inhibitor && node.dataset.to === inhibition.inhibited);
        const arc = `${inhibition.inhibitor} -> ${inhibition.inhibited}`;
        if (!edge) {
          problems.push(`${layer.name}: ${arc} not drawn`);
          continue;
        }
        if (edge.dataset.kind !== kind) problems.push(`${layer.name}: ${arc} drawn ${edge.dataset.kind}, is ${kind}`);
        const path = edge.querySelector('path');
        const length = path.getTotalLength();
        const points = [];
        for (let i = 0; i <= 100; ++i) {
          const p = path.getPointAtLength(length * i / 100);
          points.push(new DOMPoint(p.x, p.y).matrixTransform(path.getScreenCTM()));
        }
        // It starts at its inhibitor and ends at the bar just before its inhibited behaviour.
        const from = boxes.get(inhibition.inhibitor);
        const to = boxes.get(inhibition.inhibited);
        const near = (p, r) => p.x >= r.left - 8 && p.x <= r.right + 8 && p.y >= r.top - 8 && p.y <= r.bottom + 8;
        if (!near(points[0], from)) problems.push(`${layer.name}: ${arc} does not start at ${inhibition.inhibitor}`);
        if (!near(points[points.length - 1], to)) problems.push(`${layer.name}: ${arc} does not end at ${inhibition.inhibited}`);
        for (const [name, box] of boxes) {
          if (points.some((p) => inside(p, box, 1))) problems.push(`${layer.name}: ${arc} crosses ${name}`);
        }
      }
    }
    return problems;
  });
}

for (const [config, what] of [[soccer, 'the soccer demo'], ['tests/data/valid/twin.yaml', 'a config of two behaviour layers'],
                              [paper, 'the paper\'s config'], ['web/tests/crowded.yaml', 'a crowded config']]) {
  test(`ELK lays out every behaviour and inhibition apart: ${what}`, async () => {
    const trace = path.join(scratch, `layout-${path.basename(config)}.jsonl`);
    execFileSync(arbiter, ['run', config, '--steps', '3', '--trace', trace, '-q'], {cwd: source});
    const {url} = await serve(['view', config, '--trace', trace, '--serve', '0']);
    const page = await open(url);
    assert.deepEqual(await layoutProblems(page), []);
    // What the test compares with: the crowded config's 7 declared and implied inhibitions in
    // its first layer, so a page that drew none would not pass.
    if (config.includes('crowded')) {
      assert.ok(await page.locator('#graph .edge[data-layer="planning_with_a_rather_long_layer_name"]').count() >= 7);
    }
    await page.close();
  });
}

test('the trace view opens at the last step, or at --step N, or at ?step=N', async () => {
  const trace = path.join(scratch, 'soccer-open.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '220', '--trace', trace, '-q'], {cwd: source});
  const last = await serve(['view', soccer, '--trace', trace, '--serve', '0']);
  let page = await open(last.url);
  // The end of the run, with the whole run in the timelines.
  assert.equal(await stepShown(page), 220);
  assert.equal(await page.$eval('#scrub', (node) => Number(node.value)), 219);
  assert.equal(await page.textContent('#timeline-range'), 'steps 1 to 220');
  // The address follows the step shown, so that a reload stays there.
  await page.click('#previous');
  assert.equal(await stepShown(page), 219);
  assert.equal(new URL(page.url()).searchParams.get('step'), '219');
  await page.reload();
  await page.waitForSelector('body[data-ready="true"]');
  assert.equal(await stepShown(page), 219);
  await page.goto(`${last.base}?step=5`);
  await page.waitForSelector('body[data-ready="true"]');
  assert.equal(await stepShown(page), 5);
  await page.close();

  const kick = await serve(['view', soccer, '--trace', trace, '--serve', '0', '--step', '171']);
  page = await open(kick.url);
  assert.equal(await stepShown(page), 171);
  assert.equal(await behaviour(page, 'kick_ball').getAttribute('data-active'), 'true');
  await page.close();

  // A step the trace does not have is refused, with the steps it has.
  let failed;
  try {
    execFileSync(arbiter, ['view', soccer, '--trace', trace, '--serve', '0', '--step', '221'],
                 {cwd: source, stdio: 'pipe'});
  } catch (error) {
    failed = error;
  }
  assert.ok(failed, 'arbiter view --step 221 fails');
  assert.equal(failed.status, 2);
  assert.match(failed.stderr.toString(), /--step 221: .*soccer-open\.jsonl has steps 1 to 220/);
});

test('an actuator value nobody wrote is drawn as held, since the step after its last write', async () => {
  const trace = path.join(scratch, 'soccer-held.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '220', '--trace', trace, '-q'], {cwd: source});
  // Opened with the token (and a step): later addresses of this page carry the token's cookie.
  const {url, base} = await serve(['view', soccer, '--trace', trace, '--serve', '0']);
  const page = await open(`${url}&step=200`);
  const kick = page.locator('#graph .actuator[data-actuator="kick"]');
  // kick_ball writes kick = true in step 171 only; the value stays, unwritten.
  assert.equal(await stepShown(page), 200);
  assert.equal(await kick.getAttribute('class'), 'port actuator held');
  assert.equal(await kick.getAttribute('data-held-since'), '172');
  assert.equal(await kick.locator('.value').textContent(), 'trueheld since step 172');
  assert.match(await kick.locator('title').textContent(), /held since step 172: last written in step 171/);
  // Written values are not marked.
  const gait = page.locator('#graph .actuator[data-actuator="gait_velocity"]');
  assert.equal(await gait.getAttribute('class'), 'port actuator written');
  assert.equal(await gait.locator('.held-note').count(), 0);
  // The held value is dimmer than a written one.
  const fill = (locator) => locator.locator('.value').evaluate((node) => getComputedStyle(node).fill);
  assert.notEqual(await fill(kick), await fill(gait));
  await page.goto(`${base}?step=171`);
  await page.waitForSelector('body[data-ready="true"]');
  assert.equal(await kick.getAttribute('class'), 'port actuator written');
  assert.equal(await kick.locator('.value').textContent(), 'true');
  await page.goto(`${base}?step=3`);
  await page.waitForSelector('body[data-ready="true"]');
  assert.equal(await kick.locator('.value').textContent(), 'falsedefault, never written');
  await page.close();
});

test('the live page marks held values, and says when it cannot know since when', async () => {
  // 500 steps at 250 Hz; target_position_... is written in steps 1 and 2 only, kick in step 3.
  const crowded = 'web/tests/crowded.yaml';
  const {url} = await serve(['run', crowded, '--serve', '0', '--steps', '500', '-q']);
  const page = await open(url);
  await page.waitForSelector('#status.finished');
  await waitForStep(page, 500);
  const target = page.locator('#graph .actuator[data-actuator="target_position_in_the_world_frame"]');
  const kick = page.locator('#graph .actuator[data-actuator="kick"]');
  const speed = page.locator('#graph .actuator[data-actuator="speed"]');
  assert.equal(await speed.getAttribute('class'), 'port actuator written');
  // A page that has seen the run from step 1 knows; one that connected later, and was sent the
  // last 300 steps, does not.
  // The first step the page has: its timelines start there.
  const firstStep = async () => Number((await page.textContent('#timeline-range')).match(/^steps (\d+) to/)[1]);
  const first = await firstStep();
  if (first === 1) {
    assert.equal(await target.getAttribute('data-held-since'), '3');
    assert.equal(await kick.getAttribute('data-held-since'), '4');
  }
  await page.reload();
  await page.waitForSelector('body[data-ready="true"]');
  await waitForStep(page, 500);
  assert.equal(await firstStep(), 201);
  assert.equal(await target.getAttribute('class'), 'port actuator held');
  assert.equal(await target.getAttribute('data-held-since'), '<201');
  assert.match(await target.locator('.value').textContent(), /held since before step 201$/);
  assert.equal(await kick.getAttribute('data-held-since'), '<201');
  await page.close();
});

test('a page of another origin cannot pause the run, even in the operator\'s browser', async () => {
  const {url, base} = await serve(['run', paper, '--serve', '0', '--steps', '100000', '-q']);
  // The operator's page, opened with the token: the browser now holds the token's cookie.
  const context = await browser.newContext();
  const operator = await context.newPage();
  operator.setDefaultTimeout(10000);
  await operator.goto(url);
  await operator.waitForSelector('#status.running');
  // Another site, served from another port, tries a form POST and a fetch to pause the run.
  const http = await import('node:http');
  const attack = `<!DOCTYPE html><iframe name="sink"></iframe>
    <form id="f" method="POST" action="${base}control/pause" target="sink"></form>
    <script>
      document.getElementById('f').submit();
      fetch('${base}control/pause', {method: 'POST', mode: 'no-cors', credentials: 'include'})
        .finally(() => { document.body.dataset.done = 'true'; });
    </script>`;
  const site = http.createServer((request, response) => {
    response.writeHead(200, {'Content-Type': 'text/html'});
    response.end(attack);
  });
  await new Promise((resolve) => site.listen(0, '127.0.0.1', resolve));
  try {
    const attacker = await context.newPage();
    await attacker.goto(`http://127.0.0.1:${site.address().port}/`);
    await attacker.waitForSelector('body[data-done="true"]');
    await attacker.waitForTimeout(500);
    // The run goes on: the operator's page still sees it running and stepping.
    const before = await stepShown(operator);
    await operator.waitForFunction((n) => Number(document.querySelector('#step').textContent) > n, before);
    assert.equal(await operator.getAttribute('#status', 'class'), 'badge running');
  } finally {
    site.close();
    await context.close();
  }
});

test('the page opened without the token explains that it needs one', async () => {
  const {base} = await serve(['run', paper, '--serve', '0', '--steps', '100000', '-q']);
  const page = await browser.newPage();
  page.setDefaultTimeout(10000);
  await page.goto(base);
  await page.waitForSelector('#token-needed:not([hidden])');
  assert.match(await page.textContent('#token-needed'), /needs its token/);
  assert.equal(await page.locator('.behaviour').count(), 0);
  // Only the message: no empty graph, legend, timelines, step counter or controls.
  for (const selector of ['main', 'header', '#graph-panel', '#timelines', '#live-controls']) {
    assert.equal(await page.locator(selector).count(), 0, `${selector} is not on the page`);
  }
  await page.close();
});
