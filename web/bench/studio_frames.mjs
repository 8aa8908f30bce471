// The studio's speed in headless Chromium (docs/performance.md, "Studio"): the layout of a
// generated graph (the page's `arbiter:layout` measures: text measured, ELK's layout, the SVG
// built) as the page opens for the first time in a browser (a context of its own each run), as
// every layer is reloaded from the disk (ELK loaded and warm), after an edit, and as the page is
// opened again on the graph it showed (its layouts stored by the browser), in wall time and in
// CPU time of the page's main thread and of ELK's web workers (from a Chrome trace); and the
// frames while the pointer drags on it, drawing an inhibition from a behaviour, moving a
// behaviour (Alt+drag: the drop indicator following) and panning the background, at the scale
// the page opens at and at the scale a search shows a behaviour at. A benchmark, run by hand
// (under a minute with the defaults); it prints medians and 95th percentiles and checks nothing.
// CTest's `bench.studio_frames` runs it briefly, to keep it working.
//
//   node web/bench/studio_frames.mjs [--behaviours 200] [--layers 4] [--runs 3] [--seconds 1]
//
// The environment is web/tests/run.sh's; ARBITER and NODE_MODULES default to the dev build's
// (build/dev/cli/arbiter, build/dev/web/node_modules), CHROMIUM to /usr/bin/chromium.
import {mkdtempSync, rmSync, writeFileSync} from 'node:fs';
import {loadavg, tmpdir} from 'node:os';
import path from 'node:path';
import {fileURLToPath} from 'node:url';
import {parseArgs} from 'node:util';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
process.env.ARBITER ??= path.join(root, 'build/dev/cli/arbiter');
process.env.ARBITER_SOURCE ??= root;
process.env.NODE_MODULES ??= path.join(root, 'build/dev/web/node_modules');
// support.mjs reads the environment as it is imported.
const {largeConfig, launchChromium, startArbiter, stopAll} = await import('../tests/support.mjs');

const {values: options} = parseArgs({options: {
  behaviours: {type: 'string', default: '200'},
  layers: {type: 'string', default: '4'},
  runs: {type: 'string', default: '3'},
  seconds: {type: 'string', default: '1'},
}});
const layers = Number(options.layers);
const perLayer = Math.round(Number(options.behaviours) / layers);
const runs = Number(options.runs);
const seconds = Number(options.seconds);
// Each run's reload adds `b_L_1 => b_L_(4 + 2 * run)` to every layer (below).
if (4 + 2 * (runs - 1) >= perLayer) throw new Error(`--runs ${runs} needs more than ${4 + 2 * (runs - 1)} behaviours a layer`);

const quantile = (values, q) => [...values].sort((a, b) => a - b)[Math.min(values.length - 1, Math.floor(q * values.length))];
const figures = (values) => `median ${quantile(values, 0.5).toFixed(1)} ms, p95 ${quantile(values, 0.95).toFixed(1)} ms, ` +
                            `max ${Math.max(...values).toFixed(1)} ms (${values.length})`;

// Each frame, while `act()` runs: the interval since the last one, and its work on the main thread
// (from its first animation callback to the end of its rendering: a message posted then runs after
// it), as web/tests/browser_test.mjs measures the live page.
async function framesDuring(page, act) {
  await page.evaluate(() => {
    const frames = window.frames_ = {work: [], intervals: [], running: true};
    const channel = new MessageChannel();
    let start = 0;
    let last = null;
    channel.port1.onmessage = () => frames.work.push(performance.now() - start);
    const frame = (now) => {
      start = performance.now();
      if (last !== null) frames.intervals.push(now - last);
      last = now;
      channel.port2.postMessage(0);
      if (frames.running) requestAnimationFrame(frame);
    };
    requestAnimationFrame(frame);
  });
  await act();
  return page.evaluate(() => {
    window.frames_.running = false;
    return window.frames_;
  });
}

/**
 * The CPU time of the page's threads named `thread` (its main thread, or its web workers: ELK's)
 * within each `name` measure of the trace `events` (in ms): the thread time of their tasks in that
 * span, a task that overlaps the span in part counted in proportion. On a shared machine the wall
 * time of a measure includes the time the thread waited for a core; its CPU time does not.
 */
function cpuWithin(events, name, thread = 'CrRendererMain') {
  const page = events.find((e) => e.name === 'thread_name' && e.args?.name === 'CrRendererMain').pid;
  const threads = new Set(events.filter((e) => e.name === 'thread_name' && e.pid === page && e.args?.name === thread)
                              .map((e) => e.tid));
  const tasks = events.filter((e) => e.ph === 'X' && e.pid === page && threads.has(e.tid) &&
                                     e.cat.includes('toplevel') && e.tdur !== undefined);
  const spans = [];
  const open = new Map();
  for (const e of events.filter((x) => x.name === name && x.cat.includes('blink.user_timing'))) {
    if (e.ph === 'b') open.set(e.id2?.local ?? e.id, e.ts);
    else if (e.ph === 'e') spans.push([open.get(e.id2?.local ?? e.id), e.ts]);
  }
  return spans.map(([from, to]) => {
    let cpu = 0;
    for (const task of tasks) {
      const overlap = Math.min(to, task.ts + task.dur) - Math.max(from, task.ts);
      if (overlap > 0) cpu += task.tdur * (task.dur ? overlap / task.dur : 1);
    }
    return cpu / 1000;
  });
}

/**
 * Moves the pressed pointer from (x, y) round a circle of `radius` and back, for `seconds`;
 * `during()` is awaited once on the way.
 */
async function dragAbout(page, x, y, radius, during = async () => {}) {
  await page.mouse.move(x, y);
  await page.mouse.down();
  const end = Date.now() + seconds * 1000;
  for (let i = 0; Date.now() < end || i <= 10; ++i) {
    const angle = i / 20;
    await page.mouse.move(x + radius * Math.sin(angle), y + radius * (1 - Math.cos(angle)) / 2);
    if (i === 10) await during();
    await new Promise((resolve) => setTimeout(resolve, 4));
  }
  await page.mouse.move(x, y);
  await page.mouse.up();
}

const scratch = mkdtempSync(path.join(tmpdir(), 'arbiter-studio-bench-'));
const browser = await launchChromium();
try {
  const config = path.join(scratch, 'graph.yaml');
  writeFileSync(config, largeConfig(layers, perLayer, 10));
  const {found} = await startArbiter(['edit', config, '--serve', '127.0.0.1:0'], /http:\/\/127\.0\.0\.1:\d+\/\?token=[\w.-]+/);
  let page;  // each run's, in a browser context of its own: the page opened for the first time
  // ':provisional' only as the page opens on a graph ELK has not laid out in this browser: the
  // graph drawn before ELK's layouts come (web/src/quick_layout.js); '' is up to ELK's drawing.
  const PARTS = [[':provisional', 'first drawing shown (provisional, before ELK\'s layouts)'],
                 ['', 'layout (ELK\'s drawing)'], [':text', '  of which text measured'], [':elk', '  of which ELK'],
                 [':svg', '  of which SVG built']];
  // 'open' (the page opened for the first time), 'reload' (every layer changed), 'edit' (an
  // inhibition added) and 'reopen' (the page opened again on the same graph) -> part -> ms, per run
  const CASES = [['open', 'the page opened for the first time in this browser'],
                 ['reload', 'every layer changed on the disk, reloaded'],
                 ['edit', 'an inhibition added in one layer'],
                 ['reopen', 'the page opened again on the graph it showed']];
  const wall = Object.fromEntries(CASES.map(([when]) => [when, {}]));
  const cpu = Object.fromEntries(CASES.map(([when]) => [when, {}]));
  const workerCpu = Object.fromEntries(CASES.map(([when]) => [when, []]));  // ELK's workers' CPU time in the layout
  const warmUp = [];
  const keptWarm = [];
  const drags = {inhibition: {work: [], intervals: []}, move: {work: [], intervals: []}, pan: {work: [], intervals: []}};
  // The page's last layout while `act()` runs: its wall time (the page's measures) and its CPU time.
  const layoutDuring = async (when, act) => {
    // Only a measure taken after this mark is this layout's (a page opened anew has neither).
    if (page.url().startsWith('http')) await page.evaluate(() => performance.mark('bench:act'));
    await browser.startTracing(page, {categories: ['toplevel', 'blink.user_timing', '__metadata']});
    await act();
    await page.waitForSelector('body[data-busy="false"]');
    const {traceEvents} = JSON.parse(String(await browser.stopTracing()));
    for (const [part] of PARTS) {
      const duration = await page.evaluate((name) => {
        const since = performance.getEntriesByName('bench:act').at(-1)?.startTime ?? 0;
        return performance.getEntriesByName(name).filter((m) => m.startTime >= since).at(-1)?.duration;
      }, `arbiter:layout${part}`);
      if (duration === undefined) continue;  // no provisional drawing
      (cpu[when][part] ??= []).push(cpuWithin(traceEvents, `arbiter:layout${part}`).at(-1));
      if (!part) workerCpu[when].push(cpuWithin(traceEvents, 'arbiter:layout', 'DedicatedWorker thread').at(-1));
      (wall[when][part] ??= []).push(duration);
    }
  };
  const middle = Math.floor(perLayer / 2);
  const original = largeConfig(layers, perLayer, 10);
  for (let run = 0; run < runs; ++run) {
    const context = await browser.newContext({viewport: {width: 1500, height: 1000}});
    page = await context.newPage();
    await layoutDuring('open', async () => {
      await page.goto(found[0]);
      await page.waitForSelector('body[data-ready="true"]');
    });
    warmUp.push(await page.evaluate(() => performance.getEntriesByName('arbiter:layout:warm-up')[0]?.duration ?? 0));
    const count = await page.locator('.behaviour').count();
    if (count !== layers * perLayer) throw new Error(`${count} behaviours drawn, not ${layers * perLayer}`);
    // The workers go on laying out the graph's largest layers until ELK's code is optimised
    // (web/src/graph.js, keepWarm()), as they would while the user looks at the page.
    await page.waitForFunction(() => performance.getEntriesByName('arbiter:layout:kept-warm').length > 0,
                               null, {timeout: 120000});
    keptWarm.push(await page.evaluate(() => performance.getEntriesByName('arbiter:layout:kept-warm')[0].duration));
    // The file changed on the disk in every layer (a checkout while the studio is open) and
    // Reload from disk: the whole graph laid out again, by workers whose ELK is loaded and warm.
    // Each run adds another inhibition to each layer, so that no layer keeps its last layout.
    let layer = 0;
    const target = 4 + 2 * run;
    writeFileSync(config, original.replace(/^ {4}inhibitions:\n/gm,
                                           (line) => `${line}      - b_${layer}_1 => b_${layer++}_${target}\n`));
    await layoutDuring('reload', async () => {
      await page.click('#revert');
      await page.waitForSelector(`g.edge[data-from="b_${layers - 1}_1"][data-to="b_${layers - 1}_${target}"]`);
    });
    // At the scale the studio opens it (the whole graph fitted), then at the scale a search shows
    // a behaviour at (0.8).
    for (const zoom of ['fit', 'search']) {
      if (zoom === 'search') {
        await page.fill('#graph-search', `b_1_${middle}`);
        await page.press('#graph-search', 'Enter');
      }
      const stage = await page.locator('.graph-stage').boundingBox();
      const target = await page.locator(`.behaviour[data-name="layer_1/b_1_${middle}"] rect`).boundingBox();
      const from = {x: target.x + target.width / 2, y: target.y + target.height / 2};
      const inhibition = await framesDuring(page, () => dragAbout(page, from.x, from.y, 200));
      // With Alt (its grip is a few pixels wide at the fitted scale), over its own and the next
      // layers' columns, and back where it was: no edit.
      await page.keyboard.down('Alt');
      const move = await framesDuring(page, () => dragAbout(page, from.x, from.y, 200, async () => {
        if (!await page.locator('line.drop-indicator').count()) throw new Error('no drop indicator while moving');
      }));
      await page.keyboard.up('Alt');
      const pan = await framesDuring(page, () => dragAbout(page, stage.x + 4, stage.y + 4, 200));
      for (const [name, frames] of [['inhibition', inhibition], ['move', move], ['pan', pan]]) {
        drags[name].work.push(...frames.work.slice(1));
        drags[name].intervals.push(...frames.intervals.slice(1));
      }
    }
    // An edit: an inhibition added in one layer (by the selected behaviour's form), another each run.
    const inhibited = `b_1_${middle + 2 + 2 * run}`;
    await layoutDuring('edit', async () => {
      await page.selectOption('#inspector .add-inhibition select', inhibited);
      await page.click('#inspector .add-inhibition button');
      await page.waitForSelector(`g.edge[data-from="b_1_${middle}"][data-to="${inhibited}"]`);
    });
    // Opened again (the cookie holds the token now): its layouts are the browser's stored ones.
    await layoutDuring('reopen', async () => {
      await page.goto(found[0].replace(/\?token=.*/, ''));
      await page.waitForSelector('body[data-ready="true"]');
    });
    await context.close();
  }
  const [one, five, fifteen] = loadavg();
  console.log(`studio, ${layers} layers of ${perLayer} behaviours (${layers * perLayer}), ${runs} runs; ` +
              `load average ${one.toFixed(2)} ${five.toFixed(2)} ${fifteen.toFixed(2)}`);
  console.log(`ELK's warm-up while the page waits for its graph: wall ${figures(warmUp)}`);
  console.log(`ELK's workers kept warm after the first drawing, until optimised: wall ${figures(keptWarm)}`);
  for (const [when, title] of CASES) {
    console.log(`${title}:`);
    for (const [part, label] of PARTS) {
      if (!wall[when][part]) continue;
      console.log(`  ${label}: CPU time of the page's main thread ${figures(cpu[when][part])}; wall ${figures(wall[when][part])}`);
    }
    console.log(`  CPU time of ELK's web workers in the layout (both together): ${figures(workerCpu[when])}`);
  }
  for (const [name, label] of [['inhibition', 'drawing an inhibition'], ['move', 'moving a behaviour'], ['pan', 'panning']]) {
    console.log(`dragging, ${label}: frame interval ${figures(drags[name].intervals)}; frame work ${figures(drags[name].work)}`);
  }
} finally {
  await browser.close();
  stopAll();
  rmSync(scratch, {recursive: true, force: true});
}
