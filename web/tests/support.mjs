// What the web app's node tests share: starting `arbiter` until it prints where it serves, and
// headless Chromium. The environment is web/tests/run.sh's (ARBITER, ARBITER_SOURCE, CHROMIUM,
// NODE_MODULES).
import {spawn} from 'node:child_process';
import {createRequire} from 'node:module';
import path from 'node:path';

export const arbiter = process.env.ARBITER;
export const source = process.env.ARBITER_SOURCE;
export const requireModule = createRequire(path.join(process.env.NODE_MODULES, 'package.json'));

/// Every arbiter started here, for the tests' `after` to stop.
export const children = [];

/// Starts `arbiter ARGS` in the source tree and resolves, once its stdout matches `pattern`, with
/// the match, the child, `output()` (stdout and stderr so far) and `exited` (resolves with the exit
/// code and all it printed). Rejects when it exits first or prints no match within `timeout` ms,
/// by default 30 s (a debug build loading a 1000-behaviour config on a busy machine takes more
/// than 15).
export function startArbiter(args, pattern, timeout = 30000) {
  return new Promise((resolve, reject) => {
    const child = spawn(arbiter, args, {cwd: source, stdio: ['ignore', 'pipe', 'pipe']});
    children.push(child);
    let out = '';
    let err = '';
    const exited = new Promise((done) => child.on('exit', (code) => done({code, out, err})));
    const timer = setTimeout(() => reject(new Error(`no URL from arbiter ${args.join(' ')}:\n${out}${err}`)), timeout);
    child.stdout.on('data', (data) => {
      out += data;
      const found = out.match(pattern);
      if (found) {
        clearTimeout(timer);
        resolve({found, child, exited, output: () => out + err, streams: () => ({out, err})});
      }
    });
    child.stderr.on('data', (data) => { err += data; });
    child.on('exit', (code) => reject(new Error(`arbiter exited with ${code}:\n${out}${err}`)));
  });
}

/// Stops every arbiter started here.
export function stopAll() {
  for (const child of children) child.kill('SIGINT');
}

/// Debian's headless Chromium, through playwright-core.
export function launchChromium() {
  const {chromium} = requireModule('playwright-core');
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
}

/// A config of `layers` × `perLayer` scripted behaviours at `rateHz`, each switching its level
/// every few steps, with an inhibition between neighbours: a large graph that keeps changing.
export function largeConfig(layers, perLayer, rateHz) {
  const lines = ['arbiter: 1', 'name: large', `rate_hz: ${rateHz}`, 'layers:'];
  for (let l = 0; l < layers; ++l) {
    lines.push(`  - name: layer_${l}`, '    actuators:', `      out_${l}: {type: double, aggregate: true}`, '    behaviours:');
    for (let b = 0; b < perLayer; ++b) {
      const period = 7 + ((l * perLayer + b) % 23);
      const items = [];
      for (let k = 0; k < 40; ++k) items.push(`{from: ${1 + k * period}, level: ${[1, 0, 0.5, 0.2][(k + b) % 4]}}`);
      lines.push(`      b_${l}_${b}: {type: scripted, params: {activation: [${items.join(', ')}], writes: {out_${l}: ${b / perLayer}}}}`);
    }
    lines.push('    inhibitions:');
    for (let b = 0; b + 1 < perLayer; b += 2) lines.push(`      - b_${l}_${b} => b_${l}_${b + 1}`);
  }
  return lines.join('\n') + '\n';
}

/// Each frame's work on the main thread of `page` over `milliseconds`: from the frame's first
/// animation callback to the end of its rendering (a message posted then runs after it), so style,
/// layout and paint count as well as the page's own drawing. `action`, the body of a function of
/// the frame's number, runs at the start of each frame (a wheel turn, a pointer move), so that
/// what it changes is drawn in the next. Resolves with {work, intervals} (ms each) and `steps`,
/// the step shown before and after.
export function frameWork(page, milliseconds, action = '') {
  return page.evaluate(({milliseconds, action}) => new Promise((resolve) => {
    // eslint-disable-next-line no-new-func
    const act = new Function('frame', action);
    const work = [];
    const intervals = [];
    const steps = [Number(document.querySelector('#step').textContent)];
    let last = null;
    let count = 0;
    const channel = new MessageChannel();
    let start = 0;
    channel.port1.onmessage = () => work.push(performance.now() - start);
    const end = performance.now() + milliseconds;
    const frame = (now) => {
      start = performance.now();
      if (last !== null) intervals.push(now - last);
      last = now;
      act(count++);
      channel.port2.postMessage(0);
      if (performance.now() < end) requestAnimationFrame(frame);
      else {
        steps.push(Number(document.querySelector('#step').textContent));
        resolve({work, intervals, steps});
      }
    };
    requestAnimationFrame(frame);
  }), {milliseconds, action});
}

/// The `q` quantile (0 to 1) of `values`.
export const quantile = (values, q) => [...values].sort((a, b) => a - b)[Math.min(values.length - 1, Math.floor(q * values.length))];
