// The studio (`arbiter edit`, `arbiter run --serve --edit`) in a real browser: headless Chromium
// driven by playwright-core, run as web/tests/run.sh runs browser_test.mjs (the same variables).
import {test as nodeTest, before, after} from 'node:test';
import assert from 'node:assert/strict';
import {spawnSync} from 'node:child_process';
import {existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync} from 'node:fs';
import {tmpdir} from 'node:os';
import path from 'node:path';

import {arbiter, largeConfig, launchChromium, source, startArbiter, stopAll} from './support.mjs';

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

test('boxes are sized to their texts at every drawing: a behaviour renamed to a long name and back', async () => {
  const file = copyOf('soccer/walk_and_kick.yaml');
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);
  // Every text of every behaviour inside its box.
  const overflowing = () => page.$$eval('.behaviour', (groups) => groups.flatMap((group) => {
    const box = group.querySelector('rect').getBBox();
    return [...group.querySelectorAll('text')].filter((label) => {
      if (!label.textContent) return false;
      const r = label.getBBox();
      return r.x + r.width > box.x + box.width || r.y + r.height > box.y + box.height;
    }).map((label) => `${group.dataset.name}: "${label.textContent}"`);
  }));
  const width = (name) => page.$eval(`.behaviour[data-name="control/${name}"] rect`, (rect) => rect.getBBox().width);
  assert.deepEqual(await overflowing(), []);
  const opened = await width('head_control');
  const long = 'look_around_for_the_ball_and_then_for_both_goal_posts';
  await selectBehaviour(page, 'head_control');
  await page.fill('#rename-input', long);
  await page.click('#rename');
  await page.waitForSelector(`.behaviour[data-name="control/${long}"]`);
  await settled(page);
  assert.ok(await width(long) > opened + 100, `${await width(long)} against ${opened}`);
  assert.deepEqual(await overflowing(), []);
  // Back: the widths the page measured before give the box it had.
  await page.click('#undo');
  await page.waitForSelector('.behaviour[data-name="control/head_control"]');
  await settled(page);
  assert.equal(await width('head_control'), opened);
  assert.deepEqual(await overflowing(), []);
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

test('a 200-behaviour graph: zoomed about the pointer, panned, a layer folded and unfolded, a behaviour found by name', async () => {
  const file = path.join(scratch, 'large.yaml');
  writeFileSync(file, largeConfig(4, 50, 10));
  const original = readFileSync(file, 'utf8');
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);
  await settled(page);
  assert.equal(await page.locator('.behaviour').count(), 200);
  // Laid out by ELK in two web workers (two layers at once), the page's thread left free.
  assert.deepEqual(page.workers().map((worker) => new URL(worker.url()).pathname), ['/elk-worker.js', '/elk-worker.js']);
  const stage = await page.locator('.graph-stage').boundingBox();
  const scale = () => page.evaluate(() => Number(document.querySelector('.graph-stage').dataset.scale));
  const boxOf = (key) => page.locator(`.behaviour[data-name="${key}"] rect`).boundingBox();
  const centre = (b) => ({x: b.x + b.width / 2, y: b.y + b.height / 2});
  const inStage = (b) => b.x >= stage.x && b.y >= stage.y && b.x + b.width <= stage.x + stage.width &&
                         b.y + b.height <= stage.y + stage.height;
  const near = (a, b, what) => assert.ok(Math.abs(a.x - b.x) < 1.5 && Math.abs(a.y - b.y) < 1.5,
                                         `${what}: ${JSON.stringify(a)} against ${JSON.stringify(b)}`);

  // Opened fitted: the whole graph in the stage, smaller than its own size.
  const fitted = await scale();
  assert.ok(fitted < 1, `fitted at ${fitted}`);
  assert.ok(inStage(await page.locator('#graph').boundingBox()), 'the whole graph in view');

  // The wheel zooms in about the pointer: the point under it stays where it is.
  const before = centre(await boxOf('layer_1/b_1_10'));
  await page.mouse.move(before.x, before.y);
  await page.mouse.wheel(0, -300);
  await page.waitForFunction((s) => Number(document.querySelector('.graph-stage').dataset.scale) > s * 1.5, fitted);
  near(centre(await boxOf('layer_1/b_1_10')), before, 'the point under the pointer');
  const zoomed = await scale();
  const wider = await boxOf('layer_1/b_1_10');
  assert.ok(Math.abs(wider.width / (await page.evaluate(() => document.querySelector('.behaviour rect').getBBox().width)) - zoomed) < 0.01);
  // The keys: − zooms out about the middle, 0 fits the graph again.
  await page.focus('.graph-stage');
  await page.keyboard.press('-');
  assert.ok(Math.abs(await scale() - zoomed / 1.25) < 1e-9);
  await page.keyboard.press('0');
  assert.equal(await scale(), fitted);

  // A drag on the background pans: the graph moves with the pointer, nothing is selected or
  // added; the arrow keys pan by a part of the stage.
  const still = await boxOf('layer_0/b_0_0');
  await page.mouse.move(stage.x + 6, stage.y + 6);
  await page.mouse.down();
  for (let i = 1; i <= 8; ++i) await page.mouse.move(stage.x + 6 + 15 * i, stage.y + 6 + 10 * i);
  await page.mouse.up();
  const moved = await boxOf('layer_0/b_0_0');
  near({x: moved.x, y: moved.y}, {x: still.x + 120, y: still.y + 80}, 'panned by the drag');
  assert.match(await page.textContent('#inspector p'), /^Click a behaviour or an inhibition\. Drag from one behaviour to another to add an inhibition;/);
  await page.focus('.graph-stage');
  await page.keyboard.press('ArrowRight');
  const keyed = await boxOf('layer_0/b_0_0');
  near({x: keyed.x, y: keyed.y}, {x: moved.x - 0.15 * (stage.width - 2), y: moved.y}, 'panned by the key');
  await page.keyboard.press('0');

  // A layer folds away by a click on its title: its behaviours are not drawn, the others are;
  // Enter on the title unfolds it.
  await page.click('.layer[data-layer="layer_1"] .layer-head');
  await page.waitForSelector('.layer.folded[data-layer="layer_1"]');
  assert.equal(await page.locator('.behaviour[data-name^="layer_1/"]').count(), 0);
  assert.equal(await page.locator('.behaviour').count(), 150);
  assert.equal(await page.getAttribute('.layer[data-layer="layer_1"] .layer-head', 'aria-expanded'), 'false');
  assert.match(await page.textContent('.layer[data-layer="layer_1"]'), /50 behaviours folded away/);
  await page.focus('.layer[data-layer="layer_1"] .layer-head');
  await page.keyboard.press('Enter');
  await page.waitForSelector('.layer:not(.folded)[data-layer="layer_1"]');
  assert.equal(await page.locator('.behaviour').count(), 200);
  assert.equal(await page.getAttribute('.layer[data-layer="layer_1"] .layer-head', 'aria-expanded'), 'true');

  // Search by name: the matches are marked; Enter brings the first into view at a readable
  // scale and selects it, Enter again the next.
  await page.fill('#graph-search', 'b_3_4');
  assert.equal(await page.locator('.behaviour.matched').count(), 11);  // b_3_4, b_3_40 ... b_3_49
  assert.equal(await page.locator('.behaviour.unmatched').count(), 189);
  assert.equal(await page.textContent('#graph-matches'), '11 found');
  await page.press('#graph-search', 'Enter');
  await page.waitForFunction(() => document.querySelector('#inspector').textContent.includes('layer_3/b_3_4 ('));
  assert.ok(await scale() >= 0.8);
  assert.ok(inStage(await boxOf('layer_3/b_3_4')), 'the first match in view');
  await page.press('#graph-search', 'Enter');
  await page.waitForFunction(() => document.querySelector('#inspector').textContent.includes('layer_3/b_3_40 ('));
  assert.ok(inStage(await boxOf('layer_3/b_3_40')), 'the next match in view');
  assert.equal(await page.textContent('#graph-matches'), '2 of 11');
  // One in a folded layer: the layer unfolds to show it.
  await page.keyboard.press('Escape');
  assert.equal(await page.locator('.behaviour.matched').count(), 0);
  await page.focus('.graph-stage');
  await page.keyboard.press('0');
  await page.click('.layer[data-layer="layer_2"] .layer-head');
  await page.waitForSelector('.layer.folded[data-layer="layer_2"]');
  await page.fill('#graph-search', 'b_2_33');
  assert.equal(await page.getAttribute('.layer[data-layer="layer_2"]', 'data-matches'), '1');
  await page.press('#graph-search', 'Enter');
  await page.waitForSelector('.layer:not(.folded)[data-layer="layer_2"]');
  assert.ok(inStage(await boxOf('layer_2/b_2_33')), 'found in a folded layer, in view');

  // Zoomed in, a drag from one behaviour to another still draws an inhibition, and the view
  // stays where it was when the graph is drawn again.
  const from = await boxOf('layer_2/b_2_33');
  const onto = await boxOf('layer_2/b_2_35');
  assert.ok(inStage(onto), `b_2_35 in view: ${JSON.stringify(onto)}`);
  await page.mouse.move(from.x + from.width / 2, from.y + from.height / 2);
  await page.mouse.down();
  for (let i = 1; i <= 10; ++i) {
    await page.mouse.move(from.x + from.width / 2 + (onto.x - from.x) * i / 10, from.y + from.height / 2 + (onto.y - from.y) * i / 10);
  }
  await page.mouse.up();
  await page.waitForSelector('g.edge[data-from="b_2_33"][data-to="b_2_35"]');
  assert.match(await text(page), /      - b_2_32 => b_2_33\n      - b_2_34 => b_2_35\n[^]*- b_2_33 => b_2_35\n/);
  assert.ok(await scale() >= 0.8);
  assert.equal(readFileSync(file, 'utf8'), original);
  assert.deepEqual(page.errors, []);
  await page.close();
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

test('a state machine\'s queue reordered by dragging its items in the Structure panel; Escape while dragging moves nothing', async () => {
  const file = copyOf('paper/hierarchical.yaml');
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);
  const item = (n) => page.locator(`.queue-op[data-machine="match"] li:nth-child(${n})`).boundingBox();
  // Pressed on an item's name (left of its buttons), moved in steps, released once `check()` is done.
  const dragItem = async (from, to, check = async () => {}) => {
    await settled(page);
    await page.locator('.queue-op[data-machine="match"]').scrollIntoViewIfNeeded();
    const a = await item(from);
    const b = await item(to.n);
    await page.mouse.move(a.x + 8, a.y + a.height / 2);
    await page.mouse.down();
    await page.mouse.move(b.x + 8, to.below ? b.y + b.height - 2 : b.y + 2, {steps: 8});
    await check();
    await page.mouse.up();
  };
  // kick_off below celebrate: the last; the line shows under celebrate while dragging.
  await dragItem(1, {n: 3, below: true}, async () => {
    assert.equal(await page.locator('.queue-op[data-machine="match"] li:nth-child(3).drop-after').count(), 1);
  });
  await page.waitForFunction(() => document.querySelector('#text').value.includes('queue: [attack, celebrate, kick_off]'));
  // celebrate above attack: the first.
  await dragItem(2, {n: 1, below: false});
  await page.waitForFunction(() => document.querySelector('#text').value.includes('queue: [celebrate, attack, kick_off]'));
  // Escape while dragging: nothing moves.
  const before = await text(page);
  await dragItem(1, {n: 3, below: true}, async () => {
    await page.keyboard.press('Escape');
    assert.equal(await page.locator('.queue-op li.drop-after, .queue-op li.drop-before').count(), 0);
  });
  await settled(page);
  assert.equal(await text(page), before);
  // The buttons stay.
  assert.equal(await page.locator('.queue-op[data-machine="match"] li .queue-down').count(), 3);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a graph built from a file that does not exist yet, without typing YAML: a plugin, two layers with actuators and sensors, behaviours from the palette, an inhibition dragged, a port wired, saved and valid', async () => {
  const file = path.join(mkdtempSync(path.join(scratch, 'new-')), 'kicker.yaml');
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await browser.newPage({viewport: {width: 1500, height: 1000}});
  page.setDefaultTimeout(15000);
  page.errors = [];
  page.on('pageerror', (error) => page.errors.push(String(error)));
  await page.goto(url);
  await page.waitForSelector('body[data-ready="true"][data-mode="studio"]');
  assert.equal(await text(page), 'arbiter: 1\nname: kicker\nlayers: []\n');
  assert.equal(existsSync(file), false, 'nothing is written before Save');
  const textHas = (part) => page.waitForFunction((p) => document.querySelector('#text').value.includes(p), part);

  // By keyboard: the soccer plugin, whose classes join the palette.
  await settled(page);
  await page.fill('#new-plugin-name', 'soccer');
  await page.press('#new-plugin-name', 'Enter');
  await page.waitForSelector('#add-class option[value="soccer.KickBall"]', {state: 'attached'});
  // An interface layer fed from inputs, and its actuators, by mouse.
  await settled(page);
  await page.fill('#new-layer-name', 'world');
  await page.fill('#new-layer-interface', 'inputs');
  await page.click('#new-layer button');
  await page.waitForSelector('#add-actuator-world');
  for (const [name, type] of [['ball_visible', 'bool'], ['ball_position', 'vec2'], ['robot_pose', 'vec3']]) {
    await settled(page);
    await page.fill('#add-actuator-world input', name);
    await page.selectOption('#add-actuator-world select', type);
    await page.click('#add-actuator-world button');
    await page.waitForSelector(`.actuator-op[data-actuator="${name}"]`);
  }
  // The control layer (by keyboard), its actuators and what it reads.
  await settled(page);
  await page.fill('#new-layer-name', 'control');
  await page.press('#new-layer-name', 'Enter');
  await page.waitForSelector('#add-actuator-control');
  for (const [name, type] of [['gait_velocity', 'vec3'], ['head_angle', 'double'], ['kick', 'bool'], ['kick_request', 'bool']]) {
    await settled(page);
    await page.fill('#add-actuator-control input', name);
    await page.selectOption('#add-actuator-control select', type);
    await page.press('#add-actuator-control input', 'Enter');
    await page.waitForSelector(`.actuator-op[data-actuator="${name}"]`);
  }
  for (const name of ['ball_visible', 'ball_position', 'robot_pose']) {
    await settled(page);
    await page.fill('#add-sensor-control input', name);
    await page.click('#add-sensor-control button');
    await page.waitForSelector(`.sensors-op[data-layer="control"] .sensor-op[data-sensor="${name}"]`);
  }
  // Behaviours from the palette.
  for (const [name, cls] of [['kick_ball', 'soccer.KickBall'], ['go_behind_ball', 'soccer.GoBehindBall'],
                             ['search_for_ball', 'soccer.SearchForBall'], ['head_control', 'soccer.HeadControl']]) {
    await settled(page);
    await page.selectOption('#add-layer', 'control');
    await page.selectOption('#add-class', cls);
    await page.fill('#add-name', name);
    await page.click('#add-behaviour');
    await page.waitForSelector(`.behaviour[data-name="control/${name}"]`);
  }
  // An inhibition dragged; a port wired in the selected behaviour's form (the graph grew past the
  // view, which was fitted to it again).
  await drag(page, 'kick_ball', 'go_behind_ball');
  await page.waitForSelector('g.edge[data-from="kick_ball"][data-to="go_behind_ball"]');
  await selectBehaviour(page, 'kick_ball');
  await page.fill('#wire-kick input', 'kick_request');
  await page.press('#wire-kick input', 'Enter');
  await textHas('ports: {kick: kick_request}');
  // A state machine added and removed again, by mouse; a layer added and removed.
  await settled(page);
  await page.fill('#new-state-machine-name', 'spare');
  await page.click('#new-state-machine button');
  await page.waitForSelector('.machine-op[data-machine="spare"]');
  await settled(page);
  await page.click('.machine-op[data-machine="spare"] .remove-state-machine');
  await page.waitForFunction(() => !document.querySelector('#text').value.includes('state_machines'));
  await settled(page);
  await page.click('.layer-op[data-layer="world"] .remove-layer');
  await page.waitForFunction(() => /refused: layer 'world' is still used: layer 'control' reads its actuator 'ball_visible'/.test(
      document.querySelector('#studio-message').textContent));

  await settled(page);
  await page.click('#review');
  await page.click('#save');
  await page.waitForSelector('#studio-message[data-kind="saved"]');
  assert.equal(readFileSync(file, 'utf8'), `arbiter: 1
name: kicker
layers:
  - name: world
    interface: inputs
    actuators: {ball_visible: {type: bool}, ball_position: {type: vec2}, robot_pose: {type: vec3}}
  - name: control
    actuators: {gait_velocity: {type: vec3}, head_angle: {type: double}, kick: {type: bool}, kick_request: {type: bool}}
    sensors: [ball_visible, ball_position, robot_pose]
    behaviours:
      kick_ball: {type: soccer.KickBall, ports: {kick: kick_request}}
      go_behind_ball: {type: soccer.GoBehindBall}
      search_for_ball: {type: soccer.SearchForBall}
      head_control: {type: soccer.HeadControl}
    inhibitions: [kick_ball => go_behind_ball]
plugins: [soccer]
`);
  const validate = spawnSync(arbiter, ['validate', file], {cwd: source, encoding: 'utf8'});
  assert.equal(validate.status, 0, validate.stderr);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the plugins on the plugin path that the config does not name are offered in a list; the one chosen is added', async () => {
  const file = copyOf('paper/walk_and_kick.yaml');
  const before = readFileSync(file, 'utf8');
  assert.doesNotMatch(before, /plugins/);
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);
  await settled(page);
  const offered = () => page.$$eval('#new-plugin-choice option', (options) => options.map((o) => o.value));
  assert.ok((await offered()).includes('soccer'), `soccer is offered: ${await offered()}`);
  await page.selectOption('#new-plugin-choice', 'soccer');
  await page.click('#new-plugin button[type="submit"]');
  await page.waitForSelector('#add-class option[value="soccer.KickBall"]', {state: 'attached'});
  assert.equal(await text(page), `${before}plugins: [soccer]\n`);
  // Named now: no longer offered; a name off the path is still typed.
  await settled(page);
  assert.ok(!(await offered()).includes('soccer'));
  assert.equal(await page.isVisible('#new-plugin-name'), true);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a behaviour moved by dragging its grip within its layer and into another, a layer by its title; a refused move says why', async () => {
  const dir = mkdtempSync(path.join(scratch, 'moves-'));
  const file = path.join(dir, 'moves.yaml');
  writeFileSync(file, `arbiter: 1
name: moves
layers:
  - name: low
    actuators: {x: {type: double}}
    behaviours:
      a: scripted
      b: scripted
      c: scripted
    inhibitions:
      - a -> b
  - name: high
    actuators: {y: {type: double}}
    behaviours:
      d: scripted
      e: scripted
`);
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);
  const boxOf = async (key) => {
    await settled(page);
    return page.locator(`.behaviour[data-name="${key}"] rect`).boundingBox();
  };
  const grip = (b) => ({x: b.x + 4, y: b.y + b.height / 2});
  // Pressed at `from`, moved in steps to `to`; released once `check()` (while dragging) is done.
  const dragTo = async (from, to, check = async () => {}) => {
    await page.mouse.move(from.x, from.y);
    await page.mouse.down();
    await page.mouse.move(to.x, to.y, {steps: 10});
    await check();
    await page.mouse.up();
  };
  const indicator = () => page.evaluate(() => {
    const line = document.querySelector('line.drop-indicator');
    return line && line.getAttribute('visibility') !== 'hidden' ? line.getBoundingClientRect().toJSON() : null;
  });
  assert.match(await page.textContent('.behaviour[data-name="low/c"] .grip title'), /drag to move it/);

  // c, by its grip, onto the top edge of a: first in its layer. While dragging, one line shows
  // where it lands, just above a; no inhibition is drawn.
  const a = await boxOf('low/a');
  await dragTo(grip(await boxOf('low/c')), {x: a.x + a.width / 2, y: a.y - 5}, async () => {
    const line = await indicator();
    assert.ok(line, 'the drop indicator is shown');
    assert.ok(line.bottom <= a.y && line.bottom > a.y - 20 && line.left < a.x + a.width / 2 && line.right > a.x + a.width / 2,
              `the indicator above a: ${JSON.stringify(line)} against ${JSON.stringify(a)}`);
    assert.equal(await page.locator('line.drag-line').count(), 0);
  });
  await page.waitForFunction(() => /behaviours:\n      c: scripted\n      a: scripted\n      b: scripted\n/.test(document.querySelector('#text').value));
  assert.equal(await page.locator('line.drop-indicator').count(), 0, 'the indicator is gone once dropped');

  // Escape while dragging: nothing moves, the indicator goes.
  const unmoved = await text(page);
  const e = await boxOf('high/e');
  await dragTo(grip(await boxOf('low/c')), {x: e.x + e.width / 2, y: e.y + e.height + 15}, async () => {
    assert.ok(await indicator(), 'the drop indicator is shown');
    await page.keyboard.press('Escape');
    assert.equal(await page.locator('line.drop-indicator').count(), 0);
  });
  await settled(page);
  assert.equal(await text(page), unmoved);
  assert.equal(await page.locator('.behaviour.moving').count(), 0);

  // c again, into the other layer below e: its last behaviour.
  await dragTo(grip(await boxOf('low/c')), {x: e.x + e.width / 2, y: e.y + e.height + 15});
  await page.waitForSelector('.behaviour[data-name="high/c"]');
  assert.match(await text(page), /behaviours:\n      a: scripted\n      b: scripted\n    inhibitions:/);
  assert.match(await text(page), /behaviours:\n      d: scripted\n      e: scripted\n      c: scripted\n/);

  // b with Alt held, into the other layer: refused, as a -> b cannot follow it; nothing changes.
  const before = await text(page);
  const d = await boxOf('high/d');
  const b = await boxOf('low/b');
  await page.keyboard.down('Alt');
  await dragTo({x: b.x + b.width / 2, y: b.y + b.height / 2}, {x: d.x + d.width / 2, y: d.y - 5});
  await page.keyboard.up('Alt');
  await page.waitForFunction(() => /refused: 'b' is named by the inhibition 'a -> b' of layer 'low', which cannot follow it to another layer: remove it first/
      .test(document.querySelector('#studio-message').textContent));
  assert.equal(await text(page), before);
  assert.equal(await page.locator('g.edge[data-from="b"]').count(), 0, 'no inhibition drawn');

  // The layer high, by its title, before low; a click on the title still folds it.
  await settled(page);
  const title = await page.locator('g.layer[data-layer="high"] .layer-title').boundingBox();
  const low = await page.locator('g.layer[data-layer="low"] rect.layer-box').boundingBox();
  await dragTo({x: title.x + title.width / 2, y: title.y + title.height / 2}, {x: low.x + 10, y: title.y + 40});
  await page.waitForFunction(() => /layers:\n  - name: high\n[^]*\n  - name: low\n/.test(document.querySelector('#text').value));
  await settled(page);
  assert.deepEqual(await page.$$eval('g.layer', (layers) => layers.map((l) => l.dataset.layer)), ['high', 'low']);
  assert.equal(await page.locator('g.layer.folded').count(), 0, 'the drag did not fold it');
  await page.click('g.layer[data-layer="low"] .layer-title');
  await page.waitForSelector('g.layer.folded[data-layer="low"]');

  await page.click('#review');
  await page.click('#save');
  await page.waitForSelector('#studio-message[data-kind="saved"]');
  assert.equal(readFileSync(file, 'utf8'), `arbiter: 1
name: moves
layers:
  - name: high
    actuators: {y: {type: double}}
    behaviours:
      d: scripted
      e: scripted
      c: scripted
  - name: low
    actuators: {x: {type: double}}
    behaviours:
      a: scripted
      b: scripted
    inhibitions:
      - a -> b
`);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a move dragged to the edge of the graph\'s frame pans the view until a layer off-screen is reached, without laying the graph out; the drop lands there', async () => {
  const dir = mkdtempSync(path.join(scratch, 'edge-'));
  const file = path.join(dir, 'edge.yaml');
  writeFileSync(file, `arbiter: 1
name: edge
layers:
  - name: low
    actuators: {x: {type: double}}
    behaviours:
      a: scripted
      b: scripted
  - name: high
    actuators: {y: {type: double}}
    behaviours:
      d: scripted
`);
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);
  await settled(page);
  const stage = await page.locator('.graph-stage').boundingBox();
  const column = () => page.locator('g.layer[data-layer="high"] rect.layer-box').boundingBox();
  const transform = () => page.evaluate(() => document.querySelector('#graph').style.transform);
  // Zoomed in about b's left edge: the layer high is right of the frame.
  let b = await page.locator('.behaviour[data-name="low/b"] rect').boundingBox();
  await page.mouse.move(b.x + 2, b.y + b.height / 2);
  for (let i = 0; i < 2; ++i) await page.mouse.wheel(0, -300);
  await page.waitForFunction((right) => document.querySelector('g.layer[data-layer="high"] rect.layer-box')
      .getBoundingClientRect().left > right, stage.x + stage.width);
  b = await page.locator('.behaviour[data-name="low/b"] rect').boundingBox();
  // Marked, to tell a graph drawn again (which replaces the boxes) from the same one panned.
  await page.evaluate(() => { document.querySelector('g.layer[data-layer="high"]').dataset.seen = 'yes'; });

  // b by its grip, held just inside the frame's right edge: the view pans until high is in it.
  await page.mouse.move(b.x + 4, b.y + b.height / 2);
  await page.mouse.down();
  const edge = {x: stage.x + stage.width - 8, y: stage.y + stage.height / 2};
  await page.mouse.move(edge.x, edge.y, {steps: 10});
  await page.waitForFunction((right) => document.querySelector('g.layer[data-layer="high"] rect.layer-box')
      .getBoundingClientRect().right < right, stage.x + stage.width, {timeout: 10000});
  // Out of the band it stops: the view stays as it is.
  const high = await column();
  const target = {x: high.x + high.width / 2, y: high.y + high.height - 10};
  assert.ok(target.x < edge.x - 40, `high's middle is out of the band: ${JSON.stringify(high)}`);
  await page.mouse.move(target.x, target.y, {steps: 5});
  const still = await transform();
  await page.waitForTimeout(300);
  assert.equal(await transform(), still, 'no panning away from the edge');
  assert.equal(await page.locator('g.layer[data-layer="high"][data-seen="yes"]').count(), 1, 'not drawn again');
  assert.ok(await page.locator('line.drop-indicator[visibility="visible"]').count(), 'the drop is shown');
  await page.mouse.up();
  await page.waitForSelector('.behaviour[data-name="high/b"]');
  assert.match(await text(page), /behaviours:\n      d: scripted\n      b: scripted\n/);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the view follows the graph as it grows: fitted again past the right edge, a new layer brought into a view zoomed by hand, kept when it shows the change', async () => {
  const dir = mkdtempSync(path.join(scratch, 'grows-'));
  const file = path.join(dir, 'grows.yaml');
  writeFileSync(file, `arbiter: 1
name: grows
layers:
  - name: one
    actuators: {x: {type: double}}
    behaviours: {a: scripted}
  - name: two
    actuators: {y: {type: double}}
    behaviours: {b: scripted}
  - name: three
    actuators: {z: {type: double}}
    behaviours: {c: scripted}
`);
  const {url} = await serve(['edit', file, '--serve', '127.0.0.1:0']);
  const page = await open(url);
  await settled(page);
  const stage = await page.locator('.graph-stage').boundingBox();
  const scale = () => page.evaluate(() => Number(document.querySelector('.graph-stage').dataset.scale));
  const transform = () => page.evaluate(() => document.querySelector('#graph').style.transform);
  const column = (layer) => page.locator(`g.layer[data-layer="${layer}"] rect.layer-box`).boundingBox();
  const inStage = (b) => b.x >= stage.x - 1 && b.y >= stage.y - 1 && b.x + b.width <= stage.x + stage.width + 1 &&
                         b.y + b.height <= stage.y + stage.height + 1;
  const addLayer = async (name) => {
    await settled(page);
    await page.fill('#new-layer-name', name);
    await page.press('#new-layer-name', 'Enter');
    await page.waitForSelector(`g.layer[data-layer="${name}"]`);
    await settled(page);
  };
  // Three columns fit at full size; a fourth does not: the view is fitted again, all in view.
  assert.equal(await scale(), 1);
  await addLayer('four');
  assert.ok(await scale() < 1, `fitted again at ${await scale()}`);
  assert.ok(inStage(await page.locator('#graph').boundingBox()), 'the whole graph in view');
  assert.ok(inStage(await column('four')), 'the new layer in view');

  // Zoomed in by hand, the right edge out of view: a fifth layer is brought into the middle, at
  // the scale chosen.
  await page.click('#zoom-in');
  await page.click('#zoom-in');
  const zoomed = await scale();
  await addLayer('five');
  assert.equal(await scale(), zoomed);
  assert.ok(inStage(await column('five')), `the new layer in view: ${JSON.stringify(await column('five'))}`);

  // A behaviour added where the view already shows it: the view does not move.
  const kept = await transform();
  await page.selectOption('#add-layer', 'five');
  await page.fill('#add-name', 'e');
  await page.click('#add-behaviour');
  await page.waitForSelector('.behaviour[data-name="five/e"]');
  await settled(page);
  assert.ok(inStage(await page.locator('.behaviour[data-name="five/e"] rect').boundingBox()));
  assert.equal(await transform(), kept);
  assert.deepEqual(page.errors, []);
  await page.close();
});
