// Frame times of the cockpit in headless Chromium, measured by hand (not a test: the figures
// depend on the machine and its load; docs/performance.md reports them):
//
//   node web/bench/cockpit_frames.mjs recording RUN.mcap   # zoom, pan, hover over a long recording
//   node web/bench/cockpit_frames.mjs live                 # 1000 behaviours streamed at 100 Hz
//
// with the environment of web/tests/run.sh: ARBITER (the binary), ARBITER_SOURCE (the source
// tree), NODE_MODULES (where `npm ci` put playwright-core), CHROMIUM. WINDOWS=N repeats each
// measure N times (default 3); ONLY=TEXT measures only the scenarios whose name holds TEXT;
// PLOTS=LIST the values plotted (default gait_velocity[0],head_angle; empty: no plot). A
// measure of a recording is 2 seconds, of the live page 5: the whole script about a minute, half
// of it `arbiter view` reading a 100 000-step recording (Debug build).
//
// A frame's work is measured as the browser tests measure it (frameWork in web/tests/support.mjs):
// from its first animation callback to the end of its rendering. The interactions are events
// dispatched in the page at the start of each frame, as a wheel or a pointer would send them, so
// each frame has one to draw.
import {mkdtempSync, rmSync, writeFileSync} from 'node:fs';
import {tmpdir} from 'node:os';
import path from 'node:path';

import {frameWork, largeConfig, launchChromium, quantile, startArbiter, stopAll} from '../tests/support.mjs';

const [mode, recording] = process.argv.slice(2);
const windows = Number(process.env.WINDOWS || 3);
if (mode !== 'live' && !(mode === 'recording' && recording)) {
  console.error('usage: cockpit_frames.mjs recording RUN.mcap | live');
  process.exit(2);
}

const summary = (figures) => {
  const {work, intervals} = figures;
  return `${work.length} frames: work median ${quantile(work, 0.5).toFixed(1)} ms, p95 ${quantile(work, 0.95).toFixed(1)} ms, ` +
         `max ${Math.max(...work).toFixed(1)} ms; interval median ${quantile(intervals, 0.5).toFixed(1)} ms`;
};

// Events as the pointer sends them, over the timelines' strip of steps (x from 0 to 1 across it).
const OVER = `
  const canvas = document.querySelector('#timeline-rows .timeline canvas');
  const box = canvas.getBoundingClientRect();
  const at = (x) => ({clientX: box.left + x * box.width, clientY: box.top + box.height / 2, bubbles: true, cancelable: true});
  const rows = document.querySelector('#timeline-rows');
`;
const ACTIONS = {
  // The pointer sweeping across the strip: the cursor line, the tip and the plots' legends follow.
  'hover': `${OVER} rows.dispatchEvent(new PointerEvent('pointermove', at(0.05 + 0.9 * ((frame % 60) / 60))));`,
  // The wheel about the middle: 20 frames in (10 % each), 20 out.
  'wheel zoom': `${OVER} rows.dispatchEvent(new WheelEvent('wheel', {...at(0.5), deltaY: frame % 40 < 20 ? -50 : 50}));`,
  // Shift+wheel: a tenth of the steps in view a frame, 30 frames each way.
  'pan': `${OVER} rows.dispatchEvent(new WheelEvent('wheel', {...at(0.5), shiftKey: true, deltaY: (frame % 60 < 30 ? 1 : -1) * box.width / 10}));`,
};

async function measureRecording(browser) {
  const {found} = await startArbiter(['view', '--trace', path.resolve(recording), '--serve', '0'],
                                     /http:\/\/127\.0\.0\.1:\d+\/\?token=[\w.-]+/, 300000);
  const page = await browser.newPage({viewport: {width: 1400, height: 900}});
  page.setDefaultTimeout(120000);
  const opened = Date.now();
  const plots = process.env.PLOTS ?? 'gait_velocity[0],head_angle';
  await page.goto(`${found[0]}&step=50000${plots ? `&plot=${plots}` : ''}`);
  await page.waitForSelector('body[data-ready="true"]');
  if (plots) await page.waitForSelector('.plot');
  console.log(`page ready in ${((Date.now() - opened) / 1000).toFixed(1)} s: ${await page.textContent('#timeline-range')}`);
  await page.locator('#timelines').scrollIntoViewIfNeeded();
  const range = async () => (await page.textContent('#timeline-range'));
  const scenarios = [
    ['hover, the whole run in view', 'hover', null],
    ['wheel zoom from the whole run', 'wheel zoom', null],
    ['pan, 12 500 steps in view', 'pan', 12500],
    ['pan, 781 steps in view', 'pan', 800],
    ['hover, 781 steps in view', 'hover', 800],
  ];
  const only = process.env.ONLY || '';
  for (const [name, action, span] of scenarios.filter(([name]) => name.includes(only))) {
    // The whole run, then zoomed in about the cursor (at step 50 000) with the + key, halving the
    // steps in view each time, to `span` steps or a little under.
    const presses = span ? Math.ceil(Math.log2(100000 / span)) : 0;
    await page.evaluate((presses) => {
      const section = document.querySelector('#timelines');
      const key = (name) => section.dispatchEvent(new KeyboardEvent('keydown', {key: name, bubbles: true}));
      key('0');
      for (let i = 0; i < presses; ++i) key('+');
      return new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve)));
    }, presses);
    const before = await range();
    for (let window = 0; window < windows; ++window) {
      const figures = await frameWork(page, 2000, ACTIONS[action]);
      console.log(`${name} (${before}): ${summary(figures)}`);
    }
  }
  await page.close();
}

async function measureLive(browser) {
  const scratch = mkdtempSync(path.join(tmpdir(), 'arbiter-bench-'));
  try {
    const config = path.join(scratch, 'large.yaml');
    writeFileSync(config, largeConfig(10, 100, 100));
    const {found} = await startArbiter(['run', config, '--serve', '0', '--steps', '100000', '-q'],
                                       /http:\/\/127\.0\.0\.1:\d+\/\?token=[\w.-]+/);
    const page = await browser.newPage({viewport: {width: 1400, height: 900}});
    page.setDefaultTimeout(60000);
    await page.goto(found[0]);
    await page.waitForFunction(() => Number(document.querySelector('#step').textContent) > 100);
    await page.waitForTimeout(2000);  // past the first batch of 300 steps
    for (let window = 0; window < windows; ++window) {
      const figures = await frameWork(page, 5000);
      console.log(`1000 behaviours at 100 Hz: ${summary(figures)}; steps shown ${figures.steps[0]} to ${figures.steps[1]}`);
    }
    await page.close();
  } finally {
    rmSync(scratch, {recursive: true, force: true});
  }
}

const browser = await launchChromium();
try {
  if (mode === 'live') await measureLive(browser);
  else await measureRecording(browser);
} finally {
  await browser.close();
  stopAll();
}
