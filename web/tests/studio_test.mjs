// The studio (`arbiter edit`, `arbiter run --serve --edit`) in a real browser: headless Chromium
// driven by playwright-core, run as web/tests/run.sh runs browser_test.mjs (the same variables).
import {test as nodeTest, before, after} from 'node:test';
import assert from 'node:assert/strict';
import {spawnSync} from 'node:child_process';
import {mkdtempSync, readFileSync, rmSync, writeFileSync} from 'node:fs';
import {tmpdir} from 'node:os';
import path from 'node:path';

import {arbiter, launchChromium, source, startArbiter, stopAll} from './support.mjs';

const test = (name, fn, timeout = 90000) => nodeTest(name, {timeout}, fn);

const scratch = mkdtempSync(path.join(tmpdir(), 'arbiter-studio-'));
let browser;

before(async () => {
  browser = await launchChromium();
});

after(async () => {
  if (browser) await browser.close();
  stopAll();
  rmSync(scratch, {recursive: true, force: true});
});

/** A copy of the config `name` (under configs/) in a directory of its own. */
function copyOf(name) {
  const dir = mkdtempSync(path.join(scratch, 'config-'));
  const file = path.join(dir, path.basename(name));
  writeFileSync(file, readFileSync(path.join(source, 'configs', name)));
  return file;
}

/** Starts `arbiter ARGS`; resolves with the URL it prints and what it printed (`output()`). */
async function serve(args) {
  const {found, child, output} =
      await startArbiter(args, /http:\/\/127\.0\.0\.1:\d+\/\?token=[\w.-]+/);
  return {url: found[0], child, output};
}

async function open(url) {
  const page = await browser.newPage({viewport: {width: 1500, height: 1000}});
  page.setDefaultTimeout(15000);
  page.errors = [];
  page.on('pageerror', (error) => page.errors.push(String(error)));
  await page.goto(url);
  await page.waitForSelector('body[data-ready="true"][data-mode="studio"]');
  await page.waitForSelector('.behaviour');
  return page;
}

// Once every request is answered and every graph drawn: a redraw replaces the boxes.
const settled = (page) => page.waitForSelector('body[data-busy="false"]');
async function box(page, name) {
  await settled(page);
  return page.locator(`.behaviour[data-name="control/${name}"] rect`).boundingBox();
}

/** Drags from the middle of one behaviour's box to the middle of another's. */
async function drag(page, from, to) {
  const a = await box(page, from);
  const b = await box(page, to);
  await page.mouse.move(a.x + a.width / 2, a.y + a.height / 2);
  await page.mouse.down();
  for (let i = 1; i <= 10; ++i) {
    await page.mouse.move(a.x + a.width / 2 + (b.x - a.x) * i / 10, a.y + a.height / 2 + (b.y - a.y) * i / 10);
  }
  await page.mouse.up();
}

async function selectBehaviour(page, name) {
  const b = await box(page, name);

  await page.mouse.click(b.x + 20, b.y + b.height / 2);
  await page.waitForFunction((n) => document.querySelector('#inspector')?.textContent.includes(`control/${n} (`), name);
}

const text = (page) => page.inputValue('#text');

/** Resolves once `condition()` holds (bounded: 10 s), else fails with `context()`. */
async function until(condition, context) {
  for (let i = 0; i < 200; ++i) {
    if (condition()) return;
    await new Promise((resolve) => setTimeout(resolve, 50));
  }
  assert.fail(`not within 10 s:\n${context()}`);
}

test('the soccer demo edited by mouse: an inhibition dragged, a param set in the form, a rename undone, saved with only those lines changed', async () => {
  const file = copyOf('soccer/walk_and_kick.yaml');
  const original = readFileSync(file, 'utf8');
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);

  // Drag kick_ball onto search_for_ball: `kick_ball => search_for_ball`, drawn as chaining.
  await drag(page, 'kick_ball', 'search_for_ball');
  await page.waitForSelector('g.edge.chaining[data-from="kick_ball"][data-to="search_for_ball"]');
  assert.match(await text(page), /      - search_for_ball -> head_control\n      - kick_ball => search_for_ball\n/);
  // The lint it gets (chaining implies it already) is drawn on that inhibition and no other.
  await settled(page);
  assert.deepEqual(await page.$$eval('g.edge.has-warning', (edges) => edges.map((e) => `${e.dataset.from} ${e.dataset.to}`)),
                   ['kick_ball search_for_ball']);
  assert.match(await page.textContent('#problems'), /warning\[redundant-inhibition\]: inhibition 'kick_ball => search_for_ball'/);

  // go_behind_ball's max_forward, in the form made from its class's params: a value out of range
  // is refused there with validate's message, and the text is unchanged; then a good one.
  await selectBehaviour(page, 'go_behind_ball');
  const field = page.locator('.param[data-param="max_forward"] input');
  assert.equal(await field.inputValue(), '0.35');
  assert.match(await page.textContent('.param[data-param="max_forward"] .param-about'), /double in \[0, 1\]; default 0\.35/);
  const before = await text(page);
  await field.fill('5');
  await field.press('Enter');
  await page.waitForFunction(() => document.querySelector('.param[data-param="max_forward"] .param-error')?.textContent);
  assert.match(await page.textContent('.param[data-param="max_forward"] .param-error'),
               /param 'max_forward' of behaviour 'go_behind_ball' is 5; it must be a number in \[0, 1\]/);
  assert.equal(await text(page), before);
  await page.locator('.param[data-param="max_forward"] input').fill('0.3');
  await page.locator('.param[data-param="max_forward"] input').press('Enter');
  await page.waitForFunction(() => document.querySelector('#text').value.includes('max_forward: 0.3'));

  // Rename head_control: the declaration and the inhibition follow. Then undo that one step.
  await selectBehaviour(page, 'head_control');
  await page.fill('#rename-input', 'look_around');
  await page.click('#rename');
  await page.waitForSelector('.behaviour[data-name="control/look_around"]');
  assert.match(await text(page), /      - search_for_ball -> look_around\n/);
  await page.click('#undo');
  await page.waitForSelector('.behaviour[data-name="control/head_control"]');
  assert.doesNotMatch(await text(page), /look_around/);
  assert.match(await text(page), /max_forward: 0\.3/);  // only the last step was undone

  // The review: the structural diff the reload prints; then Save.
  await page.click('#review');
  const review = await page.textContent('#review-text');
  assert.match(review, /\+ inhibition control: kick_ball => search_for_ball/);
  assert.match(review, /~ behaviour control\/go_behind_ball: params: max_forward 0\.35 -> 0\.3/);
  assert.equal(readFileSync(file, 'utf8'), original, 'nothing is written before Save');
  await page.click('#save');
  await page.waitForSelector('#studio-message[data-kind="saved"]');

  // Exactly the intended lines changed; every comment is still there; validate passes.
  const saved = readFileSync(file, 'utf8');
  const expected = original
      .replace('      go_behind_ball: {type: soccer.GoBehindBall}\n',
               '      go_behind_ball: {type: soccer.GoBehindBall, params: {max_forward: 0.3}}\n')
      .replace('      - search_for_ball -> head_control\n',
               '      - search_for_ball -> head_control\n      - kick_ball => search_for_ball\n');
  assert.notEqual(expected, original);
  assert.equal(saved, expected);
  writeFileSync(path.join(scratch, 'original.yaml'), original);
  const changed = spawnSync('diff', [path.join(scratch, 'original.yaml'), file], {encoding: 'utf8'}).stdout
      .split('\n').filter((line) => /^[<>] /.test(line));
  assert.deepEqual(changed, [
    '<       go_behind_ball: {type: soccer.GoBehindBall}',
    '>       go_behind_ball: {type: soccer.GoBehindBall, params: {max_forward: 0.3}}',
    '>       - kick_ball => search_for_ball',
  ]);
  for (const comment of original.split('\n').filter((line) => line.includes('#'))) assert.ok(saved.includes(comment), comment);
  const validate = spawnSync(arbiter, ['validate', file], {cwd: source, encoding: 'utf8'});
  assert.equal(validate.status, 0, validate.stderr);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('an edit in the text pane redraws the graph and shows its problems on the behaviour and in the list; an inhibition clicked is flipped and deleted', async () => {
  const file = copyOf('paper/walk_and_kick.yaml');
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);
  const original = await text(page);
  await page.fill('#text', original.replace('          activation: 1\n', '          activation: 3\n'));
  await page.waitForSelector('.behaviour.has-error[data-name="control/head_control"]');
  assert.match(await page.textContent('#problems'),
               /error\[out-of-range\]: param 'activation' of behaviour 'head_control' is 3; it must be a number in \[0, 1\]/);
  // A behaviour added in the text is drawn.
  await page.fill('#text', original.replace('    inhibitions:\n',
                                            '      wave:\n        type: scripted\n    inhibitions:\n'));
  await page.waitForSelector('.behaviour[data-name="control/wave"]');
  await page.waitForFunction(() => !document.querySelector('.behaviour.has-error'));
  // Typing is one undo step; nothing was written.
  await page.click('#undo');
  await page.waitForSelector('.behaviour.has-error[data-name="control/head_control"]');
  assert.equal(readFileSync(file, 'utf8'), original);

  // Back to the text as opened; then an inhibition clicked on its line is selected, made
  // non-chaining, and deleted.
  await page.click('#undo');
  await page.waitForFunction(() => !document.querySelector('.behaviour.has-error') && !document.querySelector('#graph.stale'));
  assert.equal(await text(page), original);
  await settled(page);
  const middle = await page.evaluate(() => {
    const line = document.querySelector('g.edge[data-from="go_behind_ball"][data-to="search_for_ball"] .edge-hit');
    const point = line.getPointAtLength(line.getTotalLength() / 2).matrixTransform(line.getScreenCTM());
    return {x: point.x, y: point.y};
  });
  await page.mouse.click(middle.x, middle.y);
  await page.waitForSelector('#inspector .inhibition-row[data-from="go_behind_ball"][data-to="search_for_ball"]');
  assert.equal(await page.getAttribute('g.edge.selected', 'data-from'), 'go_behind_ball');
  await page.click('#inspector .flip');
  await page.waitForSelector('g.edge.non-chaining[data-from="go_behind_ball"][data-to="search_for_ball"]');
  assert.match(await text(page), /      - go_behind_ball -> search_for_ball\n/);
  await page.click('#inspector .inhibition-row[data-from="go_behind_ball"] .delete');
  await page.waitForFunction(() => !document.querySelector('g.edge[data-from="go_behind_ball"][data-to="search_for_ball"]'));
  assert.doesNotMatch(await text(page), /go_behind_ball -> search_for_ball/);

  // A behaviour from the palette of registered classes; then removed with its inhibitions.
  await page.selectOption('#add-class', 'scripted');
  await page.fill('#add-name', 'blink');
  await page.click('#add-behaviour');
  await page.waitForSelector('.behaviour[data-name="control/blink"]');
  assert.match(await text(page), /      head_control:\n        type: scripted\n        params:\n          activation: 1\n          writes: \{head_angle: -0\.5\}\n      blink: \{type: scripted\}\n/);
  await drag(page, 'blink', 'kick_ball');
  await page.waitForSelector('g.edge[data-from="blink"][data-to="kick_ball"]');
  await selectBehaviour(page, 'blink');
  await page.click('#remove-behaviour');
  await page.waitForFunction(() => !document.querySelector('.behaviour[data-name="control/blink"]'));
  assert.doesNotMatch(await text(page), /blink/);
  assert.equal(readFileSync(file, 'utf8'), original);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('on a running engine (run --serve --edit), Save reloads the graph; a rejected edit leaves the old one running and the page says why', async () => {
  const file = copyOf('paper/walk_and_kick.yaml');
  const run = await serve(['run', file, '--serve', '127.0.0.1:0', '--edit']);
  const page = await open(run.url);
  // Flip an inhibition, by keyboard from the behaviour's inspector.
  await selectBehaviour(page, 'search_for_ball');
  await page.click('.inhibition-row[data-from="search_for_ball"][data-to="head_control"] .flip');
  await page.waitForSelector('g.edge.chaining[data-from="search_for_ball"][data-to="head_control"]');
  await page.click('#review');
  await page.click('#save');
  await page.waitForSelector('#studio-message[data-kind="saved"]');
  assert.match(await page.textContent('#studio-message'), /reload of .*: 1 change, swapped in at the next step/);
  assert.match(await page.textContent('#studio-message'), /~ inhibition control: search_for_ball => head_control/);
  assert.match(run.output(), /reload of .*walk_and_kick\.yaml: 1 change, swapped in at the next step/);
  // The running engine swapped it in at its next step, as the run's report says.
  await until(() => /step +\d+  reloaded walk_and_kick: 1 layers, 4 behaviours/.test(run.output()), run.output);

  // An inhibition of a behaviour that does not exist: saved, refused by the reload.
  const current = await text(page);
  await page.fill('#text', current.replace('      - kick_ball => go_behind_ball\n', '      - kick_ball => nobody\n'));
  await page.waitForSelector('#graph.stale');
  await page.click('#review');
  await page.click('#save');
  await page.waitForFunction(() => /rejected/.test(document.querySelector('#studio-message').textContent));
  assert.match(await page.textContent('#studio-message'), /still running the previous config/);
  assert.match(await page.textContent('#studio-message'), /nobody/);
  assert.match(run.output(), /reload of .* rejected: 1 error\(s\); still running the previous config/);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('two tabs on one studio see each other\'s edits and saves, and a file changed on the disk', async () => {
  const file = copyOf('paper/walk_and_kick.yaml');
  const original = readFileSync(file, 'utf8');
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const first = await open(url);
  const second = await open(url);
  // An inhibition added by keyboard in the first tab's inspector.
  await selectBehaviour(first, 'kick_ball');
  await first.selectOption('#inspector .add-inhibition select', 'head_control');
  await first.click('#inspector .add-inhibition button');
  await first.waitForSelector('g.edge[data-from="kick_ball"][data-to="head_control"]');
  await second.waitForSelector('g.edge[data-from="kick_ball"][data-to="head_control"]');
  await second.waitForSelector('body[data-edited="true"]');
  await first.click('#review');
  await first.click('#save');
  await first.waitForSelector('#studio-message[data-kind="saved"]');
  await second.waitForSelector('body[data-edited="false"]');
  assert.match(readFileSync(file, 'utf8'), /      - kick_ball => head_control\n/);
  // Changed by hand: the file's entry says so, and a save from the page would be refused.
  writeFileSync(file, original);
  await second.waitForFunction(() => /changed on the disk/.test(document.querySelector('#file').textContent));
  await second.fill('#text', (await text(second)).replace('rate_hz: 15', 'rate_hz: 20'));
  await second.waitForSelector('body[data-edited="true"]');
  await settled(second);
  await second.click('#review');
  await second.click('#save');
  await second.waitForSelector('#studio-message[data-kind="error"]');
  assert.match(await second.textContent('#studio-message'), /conflict: .* changed on the disk since it was opened; nothing was written/);
  assert.equal(readFileSync(file, 'utf8'), original);
  // Reloaded from the disk: the hand's change is shown; Undo brings the edits back over it (the
  // first tab's inhibition and this one's rate), and then they save.
  const edited = await text(second);
  assert.match(edited, /rate_hz: 20\n[^]*      - kick_ball => head_control\n/);
  await second.click('#revert');
  await second.waitForSelector('body[data-edited="false"]');
  assert.equal(await text(second), original);
  await second.click('#undo');
  await second.waitForSelector('body[data-edited="true"]');
  await second.click('#review');
  await second.click('#save');
  await second.waitForSelector('#studio-message[data-kind="saved"]');
  assert.equal(readFileSync(file, 'utf8'), edited);
  await first.close();
  await second.close();
});

test('structure edits by mouse and keyboard: a behaviour moved, an actuator added and removed (a used one refused), a queue reordered, a state planned, declared and removed', async () => {
  const file = copyOf('paper/walk_and_kick.yaml');
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);
  const original = await text(page);
  // By keyboard: head_control declared before search_for_ball.
  await selectBehaviour(page, 'head_control');
  await page.focus('#move-behaviour-up');
  await page.keyboard.press('Enter');
  await page.waitForFunction(() => /head_control:[^]*search_for_ball:\n/.test(document.querySelector('#text').value));
  assert.match(await text(page), /      go_behind_ball:\n[^]*\n      head_control:\n        type: scripted\n        params:\n          activation: 1\n          writes: \{head_angle: -0\.5\}\n      search_for_ball:\n/);
  // By mouse: an actuator added, then removed; one a behaviour writes is refused, with the reason.
  await settled(page);
  await page.fill('#add-actuator-control input', 'beep');
  await page.selectOption('#add-actuator-control select', 'bool');
  await page.click('#add-actuator-control button');
  await page.waitForSelector('.actuator-op[data-actuator="beep"]');
  assert.match(await text(page), /      kick: \{type: bool\}\n      beep: \{type: bool\}\n/);
  await page.click('.actuator-op[data-actuator="beep"] .remove-actuator');
  await page.waitForFunction(() => !document.querySelector('.actuator-op[data-actuator="beep"]'));
  await settled(page);
  await page.click('.actuator-op[data-actuator="kick"] .remove-actuator');
  await page.waitForFunction(() => /refused: .*'kick'/.test(document.querySelector('#studio-message').textContent));
  assert.match(await text(page), /      kick: \{type: bool\}\n/);
  assert.equal(readFileSync(file, 'utf8'), original);
  await page.close();

  // A state machine's queue: an item moved later by mouse, a state planned with params by keyboard, one removed.
  const plan = copyOf('paper/hierarchical.yaml');
  const served = await serve(['edit', plan, '--serve', '127.0.0.1:0']);
  const queues = await open(served.url);
  const queueText = () => queues.inputValue('#text');
  await queues.click('.queue-op[data-machine="match"] li:nth-child(1) .queue-down');
  await queues.waitForFunction(() => document.querySelector('#text').value.includes('queue: [attack, kick_off, celebrate]'));
  await settled(queues);
  await queues.selectOption('#plan-match select', 'celebrate');
  await queues.fill('#plan-match input', '{"hold": 1}');
  await queues.press('#plan-match input', 'Enter');
  await queues.waitForFunction(() => document.querySelector('#text').value.includes(
      'queue: [attack, kick_off, celebrate, {celebrate: {hold: 1}}]'));
  await settled(queues);
  await queues.click('.queue-op[data-machine="match"] li:nth-child(1) .queue-remove');
  await queues.waitForFunction(() => document.querySelector('#text').value.includes(
      'queue: [kick_off, celebrate, {celebrate: {hold: 1}}]'));
  assert.match(await queueText(), /    queue: \[dribble, shoot\]\n/);
  // A state declared by keyboard, then removed by mouse; one the queue names is refused.
  await settled(queues);
  await queues.fill('#add-state-attack_plan input >> nth=0', 'pass_ball');
  await queues.press('#add-state-attack_plan input >> nth=0', 'Enter');
  await queues.waitForSelector('.states-op[data-machine="attack_plan"] .state-op[data-state="pass_ball"]');
  assert.match(await queueText(), /      shoot: scripted\n      pass_ball: \{type: scripted\}\n/);
  await settled(queues);
  await queues.click('.states-op[data-machine="attack_plan"] .state-op[data-state="shoot"] .remove-state');
  await queues.waitForFunction(() => /refused: state 'shoot' of state machine 'attack_plan' is still named at/.test(
      document.querySelector('#studio-message').textContent));
  await queues.click('.states-op[data-machine="attack_plan"] .state-op[data-state="pass_ball"] .remove-state');
  await queues.waitForFunction(() => !document.querySelector('#text').value.includes('pass_ball'));
  assert.deepEqual(queues.errors, []);
  await queues.close();
});
