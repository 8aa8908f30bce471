// The web view in a real browser: headless Chromium driven by playwright-core.
// Run through web/tests/run.sh (CTest label `browser`), which sets:
//   ARBITER         the arbiter binary
//   ARBITER_SOURCE  the source tree (for the configs)
//   CHROMIUM        the browser (Debian's /usr/bin/chromium)
//   NODE_MODULES    where `npm ci` put playwright-core
//   ARBITER_SCREENSHOT (optional) where to save the screenshot of the soccer demo
//   ARBITER_FRAME_BUDGET_MS (optional) the median frame work the 1000-behaviour page must stay
//                   within (default 60; the target, 16, on a quiet machine)
import {test as nodeTest, before, after} from 'node:test';
import assert from 'node:assert/strict';
import {execFile, execFileSync} from 'node:child_process';
import {copyFileSync, existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync} from 'node:fs';
import {tmpdir} from 'node:os';
import path from 'node:path';

import {arbiter, frameWork, largeConfig, launchChromium, quantile, source, startArbiter, stopAll} from './support.mjs';

// A minute per test, set here: Debian's node 18 has no --test-timeout.
const test = (name, fn, timeout = 60000) => nodeTest(name, {timeout}, fn);

// Relative to the source tree, where arbiter runs: the explain answers name them so.
const paper = 'configs/paper/walk_and_kick.yaml';
const soccer = 'configs/soccer/walk_and_kick.yaml';
const scratch = mkdtempSync(path.join(tmpdir(), 'arbiter-web-'));
let browser;

before(async () => {
  browser = await launchChromium();
});

after(async () => {
  if (browser) await browser.close();
  stopAll();
  rmSync(scratch, {recursive: true, force: true});
});

/// Starts `arbiter ARGS` and resolves with the URL it prints (with the live view's token, if
/// any), the server's base URL and the token, the process and what it printed so far
/// (`output()`: stdout and stderr).
async function serve(args) {
  const {found, child, output} =
      await startArbiter(args, /(http:\/\/127\.0\.0\.1:\d+\/)(\?token=([\w.-]+))?/);
  return {url: found[0], base: found[1], token: found[3], child, output};
}

// The graph drawn with ELK's layouts, not the provisional drawing a page shows before them.
const ELK_DRAWN = '#graph:not([data-provisional]) .behaviour';

async function open(url, timeout = 10000) {
  const page = await browser.newPage({viewport: {width: 1400, height: 900}});
  page.setDefaultTimeout(timeout);
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
  await page.waitForSelector(ELK_DRAWN);
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

test('a page opened again revalidates its scripts, ELK\'s worker too, instead of fetching them whole', async () => {
  const {url} = await serve(['run', paper, '--serve', '0', '--paused', '--steps', '1000', '-q']);
  const page = await open(url);
  const received = [];  // [the script's name, the bytes of its body received], at the second opening
  page.on('requestfinished', async (request) => {
    const name = new URL(request.url()).pathname;
    if (name.endsWith('.js')) received.push([name, (await request.sizes()).responseBodySize]);
  });
  await page.reload();
  await page.waitForSelector(ELK_DRAWN);
  await page.waitForFunction(() => document.querySelectorAll('#graph .edge').length === 4);
  await page.waitForFunction(() => performance.getEntriesByName('arbiter:layout:warm-up').length > 0);
  // Each request's sizes come a moment after it finished.
  for (let i = 0; i < 100 && !received.some(([name]) => name === '/elk-worker.js'); ++i) await page.waitForTimeout(50);
  // The page starts two of ELK's workers: the browser asks for the script once or for each, and
  // gets no byte of it again.
  assert.deepEqual([...new Set(received.map(([name]) => name))].sort(), ['/app.js', '/elk-worker.js']);
  assert.deepEqual(received.filter(([, bytes]) => bytes !== 0), []);
  await page.close();
});

test('a page opened again on the same graph draws it from the layouts the browser stored, without ELK', async () => {
  const {url} = await serve(['run', soccer, '--serve', '0', '--paused', '--steps', '1000', '-q']);
  const context = await browser.newContext({viewport: {width: 1400, height: 900}});
  const page = await context.newPage();
  const drawn = async () => {
    await page.waitForSelector('body[data-ready="true"]');
    await page.waitForSelector(ELK_DRAWN);
    return page.$eval('#graph', (svg) => [...svg.querySelectorAll('.behaviour rect, .edge path')]
        .map((node) => `${node.closest('[data-name], [data-from]').outerHTML.slice(0, 60)} ${node.getAttribute('x')} ` +
                       `${node.getAttribute('y')} ${node.getAttribute('d')}`));
  };
  await page.goto(url);
  const first = await drawn();
  assert.ok(first.length > 4);
  // ELK's worker cannot load now: what is drawn comes from the browser's storage.
  await page.route('**/elk-worker.js', (route) => route.abort());
  await page.goto(url);
  assert.deepEqual(await drawn(), first);
  await context.close();
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

// Each behaviour box's place in the SVG, 'layer/name x y'.
const boxPlaces = (page) => page.$$eval('#graph .behaviour', (groups) => groups.map((g) =>
  `${g.dataset.name} ${g.querySelector('rect').getAttribute('x')} ${g.querySelector('rect').getAttribute('y')}`));

/**
 * Opens `url` in a new browser (no layouts stored) with ELK's worker script held back until
 * `release()` is called: the page shows its provisional drawing until then.
 */
async function openWithElkHeld(url) {
  const page = await browser.newPage({viewport: {width: 1400, height: 900}});
  page.setDefaultTimeout(10000);
  let release;
  const held = new Promise((resolve) => { release = resolve; });
  await page.route('**/elk-worker.js', async (route) => {
    await held;
    await route.continue();
  });
  await page.goto(url);
  await page.waitForSelector('#graph[data-provisional="true"] .behaviour');
  return {page, release};
}

for (const [config, what] of [[soccer, 'the soccer demo'], [paper, 'the paper\'s config'],
                              ['web/tests/crowded.yaml', 'a crowded config']]) {
  test(`a page opened in a new browser shows the graph before ELK has loaded, laid out apart, then ELK's: ${what}`, async () => {
    const trace = path.join(scratch, `provisional-${path.basename(config)}.jsonl`);
    execFileSync(arbiter, ['run', config, '--steps', '3', '--trace', trace, '-q'], {cwd: source});
    const {url} = await serve(['view', config, '--trace', trace, '--serve', '0']);
    const {page, release} = await openWithElkHeld(url);
    // Drawn without ELK, and as ELK's is: every behaviour and inhibition, no box over another, no
    // inhibition across a box, all in their layers.
    assert.deepEqual(await layoutProblems(page), []);
    assert.equal(await page.locator('body[data-ready="true"]').count(), 0, 'the page is ready with ELK\'s drawing, not before');
    release();
    await page.waitForSelector(ELK_DRAWN);
    assert.deepEqual(await layoutProblems(page), []);
    await page.close();
  });
}

test('the provisional drawing of a layer of inhibited pairs is ELK\'s to the pixel: no box moves', async () => {
  const config = path.join(scratch, 'pairs.yaml');
  writeFileSync(config, largeConfig(2, 30, 10));
  const {url} = await serve(['run', config, '--serve', '0', '--paused', '--steps', '1000', '-q']);
  const {page, release} = await openWithElkHeld(url);
  const provisional = await boxPlaces(page);
  assert.equal(provisional.length, 60);
  release();
  await page.waitForSelector(ELK_DRAWN);
  assert.deepEqual(await boxPlaces(page), provisional);
  await page.close();
});

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

/// Runs `chromium --headless ARGS URL` as a user would from a shell, resolving with its stdout.
function headless(args, url) {
  return new Promise((resolve, reject) => {
    execFile(process.env.CHROMIUM || '/usr/bin/chromium',
             ['--headless', '--no-sandbox', '--disable-gpu', '--no-first-run', '--window-size=1400,900',
              `--user-data-dir=${mkdtempSync(path.join(scratch, 'profile-'))}`, ...args, url],
             {timeout: 40000, maxBuffer: 1 << 24}, (error, stdout, stderr) => {
               if (error) reject(new Error(`chromium ${args.join(' ')}: ${error.message}\n${stderr}`));
               else resolve(stdout);
             });
  });
}

test('chromium --headless --screenshot of the live page with ?snapshot shows the run as it is', async () => {
  const run = await serve(['run', soccer, '--serve', '0', '--steps', '100000', '-q']);
  await new Promise((resolve) => setTimeout(resolve, 1500));  // 15 Hz: some 20 steps
  // The DOM at the moment the screenshot is taken (the load event): the step the run had reached.
  const dom = await headless(['--dump-dom'], `${run.url}&snapshot`);
  const step = Number((dom.match(/<b id="step">(\d+)<\/b>/) || [])[1]);
  assert.ok(step >= 10, `the snapshot shows step ${step}`);
  assert.match(dom, /data-snapshot="true"/);
  assert.match(dom, /<span id="status" class="badge running">snapshot: running<\/span>/);
  assert.match(dom, /class="behaviour[^"]*"[^>]*data-name="control\/go_behind_ball"/);
  // The picture itself: taken, and the browser exits.
  const png = path.join(scratch, 'snapshot.png');
  await headless([`--screenshot=${png}`], `${run.url}&snapshot`);
  assert.ok(existsSync(png));
  assert.equal(readFileSync(png).subarray(1, 4).toString(), 'PNG');
  // The trace view too, at the step and with the plots the address asks for.
  const trace = path.join(scratch, 'soccer-snapshot.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '220', '--trace', trace, '-q'], {cwd: source});
  const view = await serve(['view', soccer, '--trace', trace, '--serve', '0']);
  const viewed = await headless(['--dump-dom'], `${view.url}&step=171&snapshot&plot=gait_velocity[0],head_angle`);
  assert.match(viewed, /<b id="step">171<\/b>/);
  assert.match(viewed, /class="behaviour active"[^>]*data-name="control\/kick_ball"|data-name="control\/kick_ball"[^>]*data-active="true"/);
  assert.match(viewed, /<div class="plot" data-series="gait_velocity\[0\] head_angle">/);
});

// The x (client coordinates) of the middle of `step` in the timelines' strip of steps.
async function xOfStep(page, step) {
  return page.evaluate((n) => {
    const canvas = document.querySelector('#timeline-rows .timeline-axis canvas');
    const box = canvas.getBoundingClientRect();
    const section = document.querySelector('#timelines');
    const from = Number(section.dataset.from);
    const to = Number(section.dataset.to);
    return {x: box.left + ((n - from + 0.5) / (to - from + 1)) * box.width, y: box.top + box.height / 2};
  }, step);
}
const timelineRange = async (page) => {
  const [, from, to] = (await page.textContent('#timeline-range')).match(/^steps (\d+) to (\d+)$/);
  return [Number(from), Number(to)];
};
// Waits for the frame the timelines draw after a change.
const nextFrame = (page) => page.evaluate(() => new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve))));

test('the timelines zoom, pan and jump to the step clicked, with the cursor at the step shown', async () => {
  const trace = path.join(scratch, 'soccer-timelines.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '220', '--trace', trace, '-q'], {cwd: source});
  const {url} = await serve(['view', soccer, '--trace', trace, '--serve', '0']);
  const page = await open(`${url}&step=171`);
  await nextFrame(page);
  assert.deepEqual(await timelineRange(page), [1, 220]);
  // The axis: steps, and the run's time under them.
  assert.equal(await page.locator('.timeline-axis').count(), 1);
  // The wheel zooms in about the step under the pointer.
  let at = await xOfStep(page, 100);
  await page.mouse.move(at.x, at.y);
  await page.mouse.wheel(0, -600);
  await nextFrame(page);
  let [from, to] = await timelineRange(page);
  assert.ok(to - from < 100, `zoomed in: steps ${from} to ${to}`);
  assert.ok(from <= 100 && 100 <= to, `step 100 stays in view: steps ${from} to ${to}`);
  // A drag to the left shows later steps.
  const before = from;
  at = await xOfStep(page, 100);
  await page.mouse.move(at.x, at.y);
  await page.mouse.down();
  await page.mouse.move(at.x - 200, at.y, {steps: 5});
  await page.mouse.up();
  await nextFrame(page);
  [from, to] = await timelineRange(page);
  assert.ok(from > before, `panned: steps ${from} to ${to}, from ${before}`);
  assert.equal(await stepShown(page), 171, 'a drag does not jump');
  // Keys, with the timelines focused: 0 shows the whole run, - and + zoom.
  await page.focus('#timelines');
  await page.keyboard.press('0');
  await nextFrame(page);
  assert.deepEqual(await timelineRange(page), [1, 220]);
  await page.keyboard.press('+');
  await nextFrame(page);
  [from, to] = await timelineRange(page);
  assert.ok(to - from <= 111 && from <= 171 && 171 <= to, `zoomed about the cursor: steps ${from} to ${to}`);
  await page.keyboard.press('Shift+ArrowLeft');
  await nextFrame(page);
  assert.ok((await timelineRange(page))[0] < from, 'Shift+← pans to earlier steps');
  assert.equal(await stepShown(page), 171, 'Shift+← does not step');
  await page.keyboard.press('0');
  await nextFrame(page);
  // Typed into the filter, + - 0 are text, not zoom keys.
  await page.locator('#timeline-filter').pressSequentially('ball');
  assert.deepEqual(await page.locator('.timeline:visible').evaluateAll((rows) => rows.map((row) => row.dataset.name)),
                   ['control/kick_ball', 'control/go_behind_ball', 'control/search_for_ball']);
  await page.locator('#timeline-filter').pressSequentially('+0');
  assert.equal(await page.inputValue('#timeline-filter'), 'ball+0');
  assert.equal(await page.locator('.timeline:visible').count(), 0);
  await nextFrame(page);
  assert.deepEqual(await timelineRange(page), [1, 220]);
  await page.fill('#timeline-filter', '');
  // Hovering tells the step, its time and the row's values there.
  at = {x: (await xOfStep(page, 50)).x, y: await yOfRow(page, '.timeline[data-name="control/kick_ball"]')};
  await page.mouse.move(at.x, at.y);
  await page.waitForSelector('#timeline-tip:not([hidden])');
  const tip = await page.textContent('#timeline-tip');
  assert.match(tip, /^step 50 {2}t [\d.]+ m?s\ncontrol\/kick_ball: activation 0\.00, inactive$/);
  // A click shows that step: the graph, the slider, the address and the cursor follow.
  await page.mouse.click(at.x, at.y);
  await waitForStep(page, 50);
  assert.equal(await page.$eval('#scrub', (node) => Number(node.value)), 49);
  assert.equal(new URL(page.url()).searchParams.get('step'), '50');
  await nextFrame(page);
  const red = await page.evaluate(({x}) => {
    const canvas = document.querySelector('#timeline-rows .timeline canvas');
    const box = canvas.getBoundingClientRect();
    const ratio = canvas.width / box.width;
    const pixel = canvas.getContext('2d').getImageData(Math.round((x - box.left) * ratio), 2, 1, 1).data;
    return [...pixel.slice(0, 3)];
  }, at);
  assert.ok(red[0] > 200 && red[1] < 80 && red[2] < 80, `the cursor is drawn at the step shown: rgb ${red}`);
  // The step of the kick, clicked on the go_behind_ball row: inhibited there.
  at = await xOfStep(page, 171);
  await page.mouse.click(at.x, await yOfRow(page, '.timeline[data-name="control/go_behind_ball"]'));
  await waitForStep(page, 171);
  assert.equal(await behaviour(page, 'kick_ball').getAttribute('data-active'), 'true');
  await page.close();
});

test('a value plot of gait_velocity[0] over a 3000-step recording, on the timelines\' steps and cursor', async () => {
  const recording = path.join(scratch, 'soccer-3000.mcap');
  const trace = path.join(scratch, 'soccer-3000.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '3000', '--record', recording, '--trace', trace, '-q'], {cwd: source});
  const expected = new Map(readFileSync(trace, 'utf8').trim().split('\n').slice(1).map((line) => {
    const record = JSON.parse(line);
    return [record.step, record.actuators.gait_velocity.value[0]];
  }));
  const {url} = await serve(['view', soccer, '--trace', recording, '--serve', '0']);
  const page = await open(`${url}&step=1500`);
  assert.deepEqual(await timelineRange(page), [1, 3000]);
  // Every numeric actuator and vector component can be plotted; booleans too, as 0 and 1.
  const choices = await page.$$eval('#plot-add option', (options) => options.map((option) => option.value).filter(Boolean));
  for (const key of ['gait_velocity[0]', 'gait_velocity[1]', 'gait_velocity[2]', 'head_angle', 'kick', 'robot_pose[2]']) {
    assert.ok(choices.includes(key), `${key} among ${choices}`);
  }
  await page.selectOption('#plot-add', 'gait_velocity[0]');
  const plot = page.locator('.plot[data-series="gait_velocity[0]"]');
  await plot.waitFor();
  const value = () => plot.locator('li[data-series="gait_velocity[0]"] .plot-value').textContent();
  // The legend gives the value at the step shown, as the recording has it.
  assert.equal(await value(), expected.get(1500).toFixed(3));
  // Several in one plot.
  await plot.locator('select').selectOption('head_angle');
  await page.waitForSelector('.plot[data-series="gait_velocity[0] head_angle"]');
  const both = page.locator('.plot[data-series="gait_velocity[0] head_angle"]');
  // The plot's steps lie under the timelines': hovering a step there gives that step's value.
  await both.scrollIntoViewIfNeeded();
  await nextFrame(page);
  const over = await both.locator('.u-over').boundingBox();
  const strip = await page.locator('#timeline-rows .timeline canvas').first().boundingBox();
  assert.ok(Math.abs(over.x - strip.x) <= 2 && Math.abs(over.width - strip.width) <= 2,
            `plot ${JSON.stringify(over)} under timelines ${JSON.stringify(strip)}`);
  const at = await xOfStep(page, 2400);
  await page.mouse.move(at.x, over.y + over.height / 2);
  // (A pixel holds some 3 steps: the one under the pointer is about step 2400.)
  await page.waitForFunction(() => /^step 2\d\d\d /.test(document.querySelector('.plot .plot-step').textContent));
  const hovered = Number((await both.locator('.plot-step').textContent()).match(/^step (\d+)/)[1]);
  assert.ok(Math.abs(hovered - 2400) <= 3, `hovered step ${hovered}`);
  assert.equal(await both.locator('li[data-series="gait_velocity[0]"] .plot-value').textContent(), expected.get(hovered).toFixed(3));
  // A click in the plot shows that step; the wheel there zooms the timelines too.
  await page.mouse.click(at.x, over.y + over.height / 2);
  await waitForStep(page, hovered);
  await page.mouse.wheel(0, -800);
  await nextFrame(page);
  const [from, to] = await timelineRange(page);
  assert.ok(to - from < 1500 && from <= 2400 && 2400 <= to, `zoomed from the plot: steps ${from} to ${to}`);
  if (process.env.ARBITER_SCREENSHOT_PLOT) await page.screenshot({path: process.env.ARBITER_SCREENSHOT_PLOT, fullPage: true});
  // Zoomed out to many steps a pixel (the whole run in a narrow window: blocks of steps reduced
  // beforehand), a one-step activation is still drawn: kick_ball's at each kick.
  const kicks = readFileSync(trace, 'utf8').trim().split('\n').slice(1).map((line) => JSON.parse(line))
    .filter((record) => record.layers.control.kick_ball.active).map((record) => record.step);
  assert.ok(kicks.length > 3, `kicks at ${kicks}`);
  await page.setViewportSize({width: 700, height: 900});
  await page.focus('#timelines');
  await page.keyboard.press('0');
  await nextFrame(page);
  await nextFrame(page);
  assert.deepEqual(await timelineRange(page), [1, 3000]);
  const row = '.timeline[data-name="control/kick_ball"]';
  await yOfRow(page, row);
  for (const kick of kicks) {
    const green = await page.$eval(`${row} canvas`, (canvas, x) => {
      const box = canvas.getBoundingClientRect();
      const ratio = canvas.width / box.width;
      const data = canvas.getContext('2d').getImageData(Math.floor((x - box.left) * ratio), canvas.height - Math.round(2 * ratio), 1, 1).data;
      return data[1] > 100 && data[0] < 80 && data[2] < 100;
    }, (await xOfStep(page, kick)).x);
    assert.ok(green, `kick_ball active at step ${kick}, drawn among ${3000 / 400} steps a pixel`);
  }
  await page.close();
});

/// The y of the middle of `selector`'s canvas (a timeline row or lane), scrolled into view.
async function yOfRow(page, selector) {
  const canvas = page.locator(`${selector} canvas`);
  await canvas.scrollIntoViewIfNeeded();
  const box = await canvas.boundingBox();
  return box.y + box.height / 2;
}
/// The colour of `selector`'s canvas at `x` (client).
const pixelAt = (page, selector, x) => page.$eval(`${selector} canvas`, (canvas, x) => {
  const box = canvas.getBoundingClientRect();
  const ratio = canvas.width / box.width;
  // Near the top: under the text of a band's label.
  return [...canvas.getContext('2d').getImageData(Math.round((x - box.left) * ratio), Math.round(4 * ratio), 1, 1).data.slice(0, 3)].join(',');
}, x);

test('a lane per state machine with its states over time and the queue at the cursor; a lane of reported events', async () => {
  // The goalie: wait_for_button to step 10, walk_to_pose 11-113, monitor_ball 114, walk_to_pose
  // 115-129, monitor_ball 130-200, dive 201-230 (the world reports the shot and the save), then
  // monitor_ball.
  const trace = path.join(scratch, 'goalie.jsonl');
  const goalie = 'configs/soccer/goalie.yaml';
  execFileSync(arbiter, ['run', goalie, '--steps', '300', '--trace', trace, '-q'], {cwd: source});
  const {url} = await serve(['view', goalie, '--trace', trace, '--serve', '0']);
  const page = await open(`${url}&step=205`);
  const lane = '.timeline-machine[data-machine="goalie"]';
  assert.equal(await page.locator(lane).count(), 1);
  assert.equal(await page.textContent('.timeline-queue[data-machine="goalie"]'), 'queue: monitor_ball');
  const y = await yOfRow(page, lane);
  const tipAt = async (step, rowY) => {
    const {x} = await xOfStep(page, step);
    await page.mouse.move(x, rowY);
    await page.waitForFunction((n) => document.querySelector('#timeline-tip').textContent.startsWith(`step ${n} `), step);
    return (await page.textContent('#timeline-tip')).split('\n').slice(1).join('\n');
  };
  // The history, not only the state shown: each step's state under the pointer.
  assert.equal(await tipAt(5, y), 'goalie: wait_for_button');
  assert.equal(await tipAt(60, y), 'goalie: walk_to_pose');
  assert.equal(await tipAt(150, y), 'goalie: monitor_ball');
  assert.equal(await tipAt(215, y), 'goalie: dive');
  // A band per state, the same colour for the same state.
  const colourAt = async (step) => pixelAt(page, lane, (await xOfStep(page, step)).x);
  assert.equal(await colourAt(60), await colourAt(120));
  assert.notEqual(await colourAt(60), await colourAt(150));
  assert.notEqual(await colourAt(150), await colourAt(215));
  // A click on the lane shows that step, with its queue.
  await page.mouse.click((await xOfStep(page, 114)).x, y);
  await waitForStep(page, 114);
  assert.equal(await page.textContent('.timeline-queue[data-machine="goalie"]'), 'queue: walk_to_pose, monitor_ball');
  // The reported events, with their text.
  const events = await yOfRow(page, '.timeline-events');
  assert.equal(await tipAt(201, events), 'world: shot on goal\ngoalie/dive: goalie dives left');
  assert.equal(await tipAt(214, events), 'world: ball saved');
  await page.close();
});

test('the explain panel is pinned to a behaviour, readable, and follows the cursor', async () => {
  const trace = path.join(scratch, 'soccer-explain.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '220', '--trace', trace, '-q'], {cwd: source});
  const {url} = await serve(['view', soccer, '--trace', trace, '--serve', '0']);
  const page = await open(`${url}&step=171`);
  await behaviour(page, 'go_behind_ball').click();
  const answer = (step) => page.waitForSelector(`#explain[data-step="${step}"][data-target="control/go_behind_ball"]`);
  await answer(171);
  // Readable: the verdict a heading, the inhibitors a table.
  assert.equal(await page.textContent('#explain .explain-head'),
               'behaviour go_behind_ball (layer control) at step 171: inactive, activation 0');
  const cells = await page.$$eval('#explain .explain-table tr:first-child td', (tds) => tds.map((td) => td.textContent.trim()));
  assert.deepEqual(cells.slice(0, 3), ['kick_ball', 'activation 1', 'factor 0']);
  assert.match(await page.textContent('#explain .explain-formula'), /^activation = 1 × 0 = 0$/);
  assert.equal(await page.$eval('#explain', (node) => getComputedStyle(node).whiteSpace), 'normal');
  assert.match(await page.textContent('#explain-subject'), /pinned: control\/go_behind_ball/);
  // Pinned: the pointer leaves the graph for the timelines; a click there moves the cursor, and
  // the panel explains the same behaviour at the new step.
  const {x} = await xOfStep(page, 100);
  const y = await yOfRow(page, '.timeline[data-name="control/head_control"]');
  await page.mouse.click(x, y);
  await waitForStep(page, 100);
  await answer(100);
  assert.equal(await page.textContent('#explain .explain-head'),
               'behaviour go_behind_ball (layer control) at step 100: active, activation 1');
  // The panel stays in view while the page is scrolled to the timelines.
  const box = await page.locator('#explain').boundingBox();
  assert.ok(box.y >= 0 && box.y < 900, `the explain panel at y ${box.y}`);
  // A timeline's label pins its behaviour.
  await page.locator('.timeline[data-name="control/search_for_ball"] .label').click();
  await page.waitForSelector('#explain[data-step="100"][data-target="control/search_for_ball"]');
  await page.keyboard.press('ArrowRight');
  await waitForStep(page, 101);
  await page.waitForSelector('#explain[data-step="101"][data-target="control/search_for_ball"]');
  // The filter by name finds behaviours in the graph too: Enter explains the first.
  await page.locator('#timeline-filter').fill('head');
  assert.deepEqual(await page.locator('#graph .behaviour.matched').evaluateAll((nodes) => nodes.map((node) => node.dataset.name)),
                   ['control/head_control']);
  assert.equal(await page.locator('#graph .behaviour.unmatched').count(), 3);
  await page.locator('#timeline-filter').press('Enter');
  await page.waitForSelector('#explain[data-step="101"][data-target="control/head_control"]');
  await page.close();
});

test('an actuator explained: clicked in the graph or a plot\'s legend, it follows the cursor', async () => {
  const trace = path.join(scratch, 'soccer-explain-actuator.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '220', '--trace', trace, '-q'], {cwd: source});
  const {url} = await serve(['view', soccer, '--trace', trace, '--serve', '0']);
  const page = await open(`${url}&step=180&plot=gait_velocity[0]`);
  await page.locator('.port.actuator[data-actuator="kick"]').click();
  const answer = (step, target) => page.waitForSelector(`#explain[data-step="${step}"][data-target="${target}"]`);
  await answer(180, 'actuators/kick');
  assert.match(await page.textContent('#explain-subject'), /pinned: actuators\/kick/);
  // Held since the kick: the step whose value it keeps, from the steps before the one shown.
  assert.equal(await page.textContent('#explain .explain-head'),
               'actuator kick (layer control, the most active writer wins) at step 180: true, held');
  assert.match(await page.textContent('#explain'), /keeps the value written at step 171 \(true\)/);
  // It follows the step clicked in the timelines: at the kick, written by kick_ball.
  const {x} = await xOfStep(page, 171);
  await page.mouse.click(x, await yOfRow(page, '.timeline[data-name="control/head_control"]'));
  await waitForStep(page, 171);
  await answer(171, 'actuators/kick');
  assert.equal(await page.textContent('#explain .explain-head'),
               'actuator kick (layer control, the most active writer wins) at step 171: true, written');
  assert.match(await page.textContent('#explain'), /written by kick_ball \(activation 1\)/);
  // A plotted value's name explains its actuator: the writers and their weights, as a table.
  await page.locator('.plot li[data-series="gait_velocity[0]"] .plot-name').click();
  await answer(171, 'actuators/gait_velocity');
  assert.match(await page.textContent('#explain .explain-head'), /^actuator gait_velocity \(layer control, aggregated\) at step 171: /);
  const rows = await page.$$eval('#explain .explain-table tr', (trs) => trs.map((tr) => tr.cells[0].textContent.trim()));
  assert.ok(rows.includes('kick_ball'), `the writers: ${rows}`);
  await page.close();
});

test('a state explained: a band of its state machine\'s lane clicked, it follows the cursor', async () => {
  const trace = path.join(scratch, 'goalie-explain.jsonl');
  const goalie = 'configs/soccer/goalie.yaml';
  execFileSync(arbiter, ['run', goalie, '--steps', '300', '--trace', trace, '-q'], {cwd: source});
  const {url} = await serve(['view', goalie, '--trace', trace, '--serve', '0']);
  const page = await open(`${url}&step=100`);
  const lane = '.timeline-machine[data-machine="goalie"]';
  const answer = (step, target) => page.waitForSelector(`#explain[data-step="${step}"][data-target="${target}"]`);
  // The band of dive at step 215: that step is shown and the state explained there, from its
  // start (planned and pre-empting monitor_ball) to its end.
  await page.mouse.click((await xOfStep(page, 215)).x, await yOfRow(page, lane));
  await waitForStep(page, 215);
  await answer(215, 'goalie/dive');
  assert.match(await page.textContent('#explain-subject'), /pinned: goalie\/dive/);
  assert.equal(await page.textContent('#explain .explain-head'), 'state goalie/dive at step 215: running (cycle 215)');
  const lines = await page.$$eval('#explain p', (ps) => ps.map((p) => p.textContent));
  assert.deepEqual(lines, ['started at step 201: activated when monitor_ball ended: pre-empted by dive',
                           'planned: in step 201 itself, as the state before it ended',
                           'ended at step 231: proceeded']);
  // Pinned, it follows the cursor: a click on another row explains dive at that step.
  await page.mouse.click((await xOfStep(page, 150)).x, await yOfRow(page, '.timeline-events'));
  await waitForStep(page, 150);
  await answer(150, 'goalie/dive');
  assert.match(await page.textContent('#explain .explain-head'), /^state goalie\/dive at step 150: /);
  // The state in the state machine's panel, and the lane's label (the machine itself).
  await page.locator('.controller[data-controller="goalie"] .state').click();
  await answer(150, 'goalie/monitor_ball');
  await page.locator(`${lane} .label`).click();
  await answer(150, 'state_machines/goalie');
  assert.match(await page.textContent('#explain .explain-head'), /^state machine goalie at step 150: /);
  await page.close();
});

test('two runs compared: the what-if without kick_ball over the run, the steps that differ marked', async () => {
  // The docs' what-if (docs/replay.md): the recorded run replayed without kick_ball.
  const config = path.join(scratch, 'compare.yaml');
  const noKick = path.join(scratch, 'compare_no_kick.yaml');
  copyFileSync(path.join(source, soccer), config);
  writeFileSync(noKick, readFileSync(config, 'utf8').split('\n')
    .filter((line) => !/kick_ball: \{type|kick_ball => go_behind_ball/.test(line)).join('\n'));
  const run = path.join(scratch, 'compare.mcap');
  const whatIf = path.join(scratch, 'compare_no_kick.mcap');
  const env = {...process.env, ARBITER_PLUGIN_PATH: path.join(path.dirname(arbiter), '..', 'plugins')};
  execFileSync(arbiter, ['run', config, '--steps', '220', '--record', run, '-q'], {cwd: source, env});
  execFileSync(arbiter, ['replay', run, '--config', noKick, '--record', whatIf], {cwd: source, env});
  const {url} = await serve(['view', '--trace', run, '--compare', whatIf, '--serve', '0']);
  const page = await open(`${url}&step=100&plot=kick`);
  // Where they first differ, and what: the kick, as `arbiter diff` finds it.
  assert.equal(await page.textContent('#compare-what'),
               'first differ at step 171: control/go_behind_ball, control/kick_ball, actuator:gait_velocity, actuator:kick');
  assert.match(await page.textContent('#compare-runs'), /^A .*compare\.mcap · B .*compare_no_kick\.mcap$/);
  // B's row of each behaviour under A's, named.
  const rowA = '.timeline[data-run="a"][data-name="control/go_behind_ball"]';
  const rowB = '.timeline[data-run="b"][data-name="control/go_behind_ball"]';
  assert.equal(await page.textContent(`${rowA} .label`), 'A control/go_behind_ball');
  assert.equal(await page.textContent(`${rowB} .label`), 'B control/go_behind_ball');
  assert.equal(await page.locator('.timeline-machine, .timeline-events').count(), 2, 'a reported lane for each run');
  // One button to the first difference.
  await page.click('#compare-first');
  await waitForStep(page, 171);
  await nextFrame(page);
  // Marked on the row where they differ, at that step and not before it.
  const orange = (rgb) => { const [r, g, b] = rgb.split(',').map(Number); return r > 200 && g > 100 && g < 200 && b < 80; };
  const top = (selector, x) => page.$eval(`${selector} canvas`, (canvas, x) => {
    const box = canvas.getBoundingClientRect();
    const ratio = canvas.width / box.width;
    return [...canvas.getContext('2d').getImageData(Math.round((x - box.left) * ratio), Math.round(ratio), 1, 1).data.slice(0, 3)].join(',');
  }, x);
  await yOfRow(page, rowB);
  // The timelines redraw in a frame of their own, which a busy machine may put off for a few.
  let marked = false;
  for (let frame = 0; frame < 60 && !marked; ++frame) {
    marked = orange(await top(rowB, (await xOfStep(page, 171)).x + 2));
    if (!marked) await nextFrame(page);
  }
  assert.ok(marked, 'step 171 marked on B\'s row');
  assert.ok(!orange(await top(rowB, (await xOfStep(page, 150)).x)), 'step 150 not marked');
  // The tip tells each run's values: inhibited in A, active in B.
  const {x} = await xOfStep(page, 171);
  await page.mouse.move(x, await yOfRow(page, rowA));
  await page.waitForFunction(() => document.querySelector('#timeline-tip').textContent.startsWith('step 171 '));
  assert.match(await page.textContent('#timeline-tip'), /\nA control\/go_behind_ball: activation 0\.00, inhibited\nA and B differ here$/);
  await page.mouse.move(x, await yOfRow(page, rowB));
  await page.waitForFunction(() => /\nB control/.test(document.querySelector('#timeline-tip').textContent));
  assert.match(await page.textContent('#timeline-tip'), /\nB control\/go_behind_ball: activation 1\.00, active\n/);
  // The plot draws B's value beside A's, named.
  assert.equal(await page.textContent('.plot li[data-series="kick"]:not([data-run]) .plot-value'), '1');
  assert.equal(await page.textContent('.plot li[data-series="kick"][data-run="b"] .plot-name'), 'kick (B)');
  assert.equal(await page.textContent('.plot li[data-series="kick"][data-run="b"] .plot-value'), '0');
  // The explain panel answers for each run against its own config.
  await behaviour(page, 'go_behind_ball').click();
  await page.waitForSelector('#explain[data-step="171"][data-target="control/go_behind_ball"]');
  assert.deepEqual(await page.$$eval('#explain .explain-head', (heads) => heads.map((head) => head.textContent)),
                   ['behaviour go_behind_ball (layer control) at step 171: inactive, activation 0',
                    'behaviour go_behind_ball (layer control) at step 171: active, activation 1']);
  // Next difference: kick differs from 171 to the end (held true in A).
  await page.click('#compare-next');
  await waitForStep(page, 172);
  await page.close();
});

test('1000 behaviours streamed live at 100 Hz: the page stays responsive (median frame work within budget)', async () => {
  const config = path.join(scratch, 'large.yaml');
  writeFileSync(config, largeConfig(10, 100, 100));
  const {url} = await serve(['run', config, '--serve', '0', '--steps', '100000', '-q']);
  // (Laying out 1000 behaviours takes a few seconds on a slow machine.)
  const page = await open(url, 40000);
  page.setDefaultTimeout(10000);
  await page.waitForFunction(() => Number(document.querySelector('#step').textContent) > 100);
  assert.equal(await page.locator('.behaviour').count(), 1000);
  await page.waitForTimeout(2000);  // past the first batch of 300 steps
  // Each frame's work on the main thread over 5 seconds of the stream (frameWork).
  const measure = () => frameWork(page, 5000);
  // The machine the tests run on may be busy with other work: the best of three windows. (The
  // steps shown are reported, not checked: on a busy machine the engine itself falls behind.)
  // The target is 16 ms (docs/performance.md), met on a quiet machine; the test's machine is
  // shared, and asserts a budget that still tells the page from one that redraws everything
  // each frame (390 ms). ARBITER_FRAME_BUDGET_MS=16 checks the target.
  const budget = Number(process.env.ARBITER_FRAME_BUDGET_MS || 60);
  const reports = [];
  let met = false;
  for (let window = 0; window < 3 && !met; ++window) {
    const figures = await measure();
    const median = quantile(figures.work, 0.5);
    met = median <= budget;
    reports.push(`frames ${figures.work.length} in 5 s; frame work median ${median.toFixed(1)} ms, ` +
        `p95 ${quantile(figures.work, 0.95).toFixed(1)} ms; frame interval median ${quantile(figures.intervals, 0.5).toFixed(1)} ms; ` +
        `steps shown ${figures.steps[0]} to ${figures.steps[1]}`);
    console.log(`1000 behaviours at 100 Hz: ${reports[reports.length - 1]}`);
  }
  assert.ok(met, reports.join('\n'));
  // Search and fold: a filter by name leaves the matching rows; a layer folds away.
  await page.fill('#timeline-filter', 'b_3_4');
  assert.equal(await page.locator('.timeline:visible').count(), 11);  // b_3_4, b_3_40 ... b_3_49
  // Enter finds the first in the graph, far off the screen: it is scrolled into view, explained.
  await page.fill('#timeline-filter', 'b_7_93');
  await page.locator('#timeline-filter').press('Enter');
  await page.waitForSelector('#explain[data-target="layer_7/b_7_93"]');
  const found = await page.locator('.behaviour[data-name="layer_7/b_7_93"] rect').boundingBox();
  assert.ok(found.y >= 0 && found.y + found.height <= 900 && found.x >= 0 && found.x + found.width <= 1400,
            `b_7_93 on the screen: ${JSON.stringify(found)}`);
  await page.fill('#timeline-filter', '');
  await page.click('.timeline-group[data-layer="layer_0"] .timeline-layer');
  assert.equal(await page.locator('.timeline:visible').count(), 900);
  // Folded in the graph too (one set of folds); its title there unfolds both.
  await page.waitForSelector('#graph .layer.folded[data-layer="layer_0"]');
  assert.equal(await page.locator('#graph .behaviour').count(), 900);
  await page.click('#graph .layer[data-layer="layer_0"] .layer-head');
  await page.waitForSelector('.timeline-group:not(.collapsed)[data-layer="layer_0"]');
  assert.equal(await page.locator('#graph .behaviour').count(), 1000);
  await page.close();
}, 120000);

test('live: a step clicked in the timelines stays shown while the run goes on, until Follow', async () => {
  const {url} = await serve(['run', soccer, '--serve', '0', '--steps', '100000', '-q']);
  const page = await open(url);
  await page.waitForFunction(() => Number(document.querySelector('#step').textContent) >= 30);
  await nextFrame(page);
  // The timelines' scale grows with the run between measuring and clicking, so the step clicked
  // is step 10 or one after it: 10 × (steps at the click / steps at the measure), which a busy
  // machine can make large, but not past 20 unless the run doubled meanwhile (two seconds at
  // least). The page must show the one it pinned.
  const {x} = await xOfStep(page, 10);
  await page.mouse.click(x, await yOfRow(page, '.timeline[data-name="control/go_behind_ball"]'));
  await page.waitForSelector('body[data-pinned]');
  const pinned = Number(await page.getAttribute('body', 'data-pinned'));
  assert.ok(pinned >= 8 && pinned <= 20, `pinned step ${pinned}, clicked at step 10`);
  await waitForStep(page, pinned);
  assert.equal(await page.isVisible('#follow'), true);
  // The run goes on (the timelines grow), the page stays at the step clicked.
  const [, last] = await timelineRange(page);
  await page.waitForFunction((n) => Number(document.querySelector('#timelines').dataset.to) > n + 5, last);
  assert.equal(await stepShown(page), pinned);
  await page.click('#follow');
  await page.waitForFunction((n) => Number(document.querySelector('#step').textContent) > n + 5, last);
  assert.equal(await page.isVisible('#follow'), false);
  await page.close();
});

/// The first step of a plain run of the soccer demo at which kick_ball is active: the kick.
function kickStep() {
  const trace = path.join(scratch, 'kick.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '400', '--trace', trace, '-q'], {cwd: source});
  for (const line of readFileSync(trace, 'utf8').split('\n').slice(1)) {
    if (!line) continue;
    const record = JSON.parse(line);
    if (!record.safe && record.layers.control.kick_ball.active) return record.step;
  }
  throw new Error('the soccer demo never kicked');
}

test('a breakpoint set on the page pauses the live soccer demo at the kick', async () => {
  const kick = kickStep();
  const run = await serve(['run', soccer, '--serve', '0', '--paused', '--full-speed', '--steps', '100000']);
  const page = await open(run.url);
  // A condition that names nothing is refused with the place and the closest name.
  await page.fill('#break-condition', 'kick_bal activates');
  await page.click('#break-add');
  await page.waitForSelector('#break-message.error:not([hidden])');
  assert.match(await page.textContent('#break-message'), /break:1:1: error\[unknown-name\]: 'kick_bal' names no behaviour[\s\S]*did you mean 'kick_ball'\?/);
  // Clicking the behaviour offers "break when it activates".
  await behaviour(page, 'kick_ball').click();
  assert.equal(await page.inputValue('#break-condition'), 'control/kick_ball activates');
  await page.click('#break-add');
  await page.waitForSelector('.breakpoint[data-condition="control/kick_ball activates"]');
  // The refusal's message goes once the accepted breakpoint is listed (on a busy machine, a frame
  // after it).
  await page.waitForSelector('#break-message', {state: 'hidden'});
  await page.click('#resume');
  await page.waitForSelector('body[data-break]');
  // Paused at the kick's step, named; the last step the engine ran is the kick's.
  assert.equal(await page.getAttribute('body', 'data-break'), String(kick));
  assert.equal(await page.textContent('#status'), `paused at step ${kick}: break control/kick_ball activates`);
  await waitForStep(page, kick);
  await page.waitForTimeout(300);
  assert.equal(await stepShown(page), kick, 'no step after the break ran');
  // Paused as Pause pauses: the safe values are out.
  await page.waitForSelector('body[data-safe="true"]');
  assert.equal(await page.locator('.port.actuator[data-actuator="gait_velocity"] .value').textContent(), '[0, 0, 0]');
  assert.equal(await behaviour(page, 'kick_ball').getAttribute('data-active'), 'true');
  // Reported at that step, as the trace and the recording carry it.
  assert.ok((await page.locator('#reported li.event').allTextContents())
      .includes(`step ${kick}  break: control/kick_ball activates`));
  assert.match(run.output(), new RegExp(`step\\s+${kick}  break: control/kick_ball activates`));
  // Removed, the run goes on past the next kick.
  await page.click('.breakpoint[data-condition="control/kick_ball activates"] .break-remove');
  await page.waitForFunction(() => !document.querySelector('.breakpoint'));
  await page.click('#resume');
  await page.waitForFunction(() => document.body.dataset.break === undefined);
  await page.waitForFunction((n) => Number(document.querySelector('#step').textContent) > n + 250, kick);
  await page.close();
});

test('the recorded view shows the next step where a condition becomes true', async () => {
  const kick = kickStep();
  const trace = path.join(scratch, 'seek.jsonl');
  execFileSync(arbiter, ['run', soccer, '--steps', '400', '--trace', trace, '-q'], {cwd: source});
  const {url} = await serve(['view', soccer, '--trace', trace, '--serve', '0', '--step', '1']);
  const page = await open(url);
  assert.equal(await page.locator('#break-add').isVisible(), false);
  // A value clicked offers "break when it rises above what it shows"; a behaviour, its activation.
  await page.click('.port.actuator[data-actuator="gait_velocity"] .value');
  assert.equal(await page.inputValue('#break-condition'), 'gait_velocity[0] > 0');
  await behaviour(page, 'go_behind_ball').click();
  assert.equal(await page.inputValue('#break-condition'), 'control/go_behind_ball activates');
  await page.fill('#break-condition', 'kick_ball activates');
  await page.click('#break-next');
  await waitForStep(page, kick);
  assert.equal(await page.textContent('#break-message'), `step ${kick}: kick_ball activates`);
  await page.press('#break-condition', 'Enter');
  await page.waitForFunction((n) => Number(document.querySelector('#step').textContent) > n, kick);
  const second = await stepShown(page);
  await page.press('#break-condition', 'Enter');
  await page.waitForSelector('#break-message:not(.error)');
  await page.waitForFunction(() => document.querySelector('#break-message').textContent.startsWith('no step after'));
  assert.equal(await stepShown(page), second, 'no later kick: the step shown stays');
  await page.close();
});
