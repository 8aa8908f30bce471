// The timelines: over the steps in view (time_view.js), an axis of steps and the run's time `t`,
// a row per behaviour (its activation, a green bar where it was active, a red one where it
// requested a level but was inhibited), grouped by layer (a layer folds away), a lane per state
// machine with its states as bands, and a lane of what code reported. The cursor marks the step
// shown; hovering tells the values at a step; a filter keeps the rows whose name matches.
// Comparing two runs (`arbiter view A --compare B`), each row of A has B's under it, and the
// steps where they differ (as `arbiter diff` finds them) are marked on both and on the axis.
import {ACTIVE, INHIBITED, levelFor, lowerBound, most} from './columns.js';
import {colour, html} from './dom.js';
import {Folds} from './folds.js';
import {attachKeys, attachPointer} from './time_view.js';

const ROW_HEIGHT = 22;
const AXIS_HEIGHT = 34;

/** About `count` round numbers (1, 2, 5 × 10^n apart) between `from` and `to`. */
export function ticks(from, to, count) {
  const raw = Math.max(1, (to - from) / count);
  const power = 10 ** Math.floor(Math.log10(raw));
  const gap = [1, 2, 5, 10].map((m) => m * power).find((m) => m >= raw);
  const out = [];
  for (let tick = Math.ceil(from / gap) * gap; tick <= to; tick += gap) out.push(tick);
  return out;
}

/** A state's colour: the same for the same name, in every lane. */
function bandColour(name) {
  let hash = 0;
  for (const c of name) hash = (hash * 31 + c.charCodeAt(0)) >>> 0;
  return `hsl(${hash % 360}, 55%, 82%)`;
}

/** The run's time `t` (seconds) as the axis and the tip write it. */
export function formatTime(t) {
  if (!Number.isFinite(t)) return '';
  if (Math.abs(t) < 1) return `t ${(t * 1000).toFixed(t < 0.01 ? 2 : 1)} ms`;
  return `t ${t.toFixed(t < 100 ? 3 : 1)} s`;
}

export class Timelines {
  /**
   * @param {HTMLElement} section the timelines' section (it takes the keys when focused)
   * @param {import('./columns.js').Columns} columns
   * @param {import('./time_view.js').TimeView} view
   * @param {Folds} [folds] the layers folded away, shared with the graph
   */
  constructor(section, columns, view, folds = new Folds()) {
    this.section = section;
    this.rows = section.querySelector('#timeline-rows');
    this.range = section.querySelector('#timeline-range');
    this.tip = section.querySelector('#timeline-tip');
    this.filter = section.querySelector('#timeline-filter');
    this.columns = columns;
    this.view = view;
    /** @type {{kind: string, key: string, row: HTMLElement, canvas: HTMLCanvasElement, note?: HTMLElement, columns: object, marks?: number[][]}[]} */
    this.strips = [];
    this.folds = folds;
    this.groups = new Map();     // layer -> {group, head}
    /** Comparing: {columns (B's), differ: {what: [[from, to], ...]}, steps: [[from, to], ...]}. */
    this.compare = null;
    // Rows outside a layer's group and the groups themselves on the screen: the rows of a
    // group are told apart by their rectangles as they are drawn. An IntersectionObserver of
    // every row cost the browser some milliseconds every frame at 1000 rows.
    this.visible = new Set();
    this.pointer = null;         // {strip, x, y}: where the pointer is, for the tip
    this.queueAt = () => null;   // the queue of a state machine at the cursor (from the record)
    /** Called with 'layer/name' when a behaviour's label is clicked, 'state_machines/name' a lane's. */
    this.onLabel = (key) => {};
    /** Called with a state machine and its state when a band of its lane is clicked. */
    this.onState = (machine, state) => {};
    /** Called with the filter's text (lower case) as it changes, and when Enter is pressed in it. */
    this.onFilter = (words) => {};
    this.onFind = (words) => {};
    this.observer = new IntersectionObserver((entries) => {
      for (const entry of entries) {
        if (entry.isIntersecting) this.visible.add(entry.target);
        else this.visible.delete(entry.target);
      }
      this.view.changed();
    });
    // Scrolled within a group on the screen: its rows that came into view are drawn.
    document.addEventListener('scroll', () => this.view.changed(), {capture: true, passive: true});
    view.subscribe(() => this.draw());
    folds.subscribe((layer) => this.showFold(layer));
    attachPointer(this.rows, view, () => this.strip(), (step, event) => this.clicked(step, event));
    attachKeys(section, view);
    this.rows.addEventListener('pointermove', (event) => {
      const row = event.target.closest('[data-strip]');
      this.pointer = row ? {strip: this.strips[Number(row.dataset.strip)], x: event.clientX, y: event.clientY} : null;
      this.showTip();
    });
    this.rows.addEventListener('pointerleave', () => {
      this.pointer = null;
      this.showTip();
    });
    this.filter.addEventListener('input', () => this.applyFilter());
    // Enter: the first behaviour that matches (onFind shows it in the graph and explains it).
    this.filter.addEventListener('keydown', (event) => {
      if (event.key === 'Enter') this.onFind(this.filter.value.trim().toLowerCase());
    });
    this.stripWidth = 0;  // CSS pixels, measured when the rows change size, not each frame
    new ResizeObserver(() => {
      const canvas = this.strips.length ? this.strips[0].canvas : null;
      this.stripWidth = canvas ? canvas.getBoundingClientRect().width : 0;
      this.view.changed();
    }).observe(this.rows);
  }

  /** Where the steps are drawn, in client coordinates: the canvases' column. */
  strip() {
    const canvas = this.strips.length ? this.strips[0].canvas : null;
    if (!canvas) return {left: 0, width: 1};
    const box = canvas.getBoundingClientRect();
    return {left: box.left, width: Math.max(1, box.width)};
  }

  add(kind, key, label, parent, height = ROW_HEIGHT, attributes = {}, columns = this.columns) {
    const row = html('div', {class: kind, 'data-strip': this.strips.length, ...attributes}, parent);
    html('span', {class: 'label', title: label}, row).textContent = label;
    const canvas = html('canvas', {height}, row);
    canvas.style.height = `${height}px`;
    const strip = {kind, key, row, canvas, columns, group: parent === this.rows ? null : parent};
    this.strips.push(strip);
    if (!strip.group) this.observer.observe(row);
    return strip;
  }

  /**
   * Compares with run B: `columns` are B's, `differences` the server's /compare. Rebuilt by the
   * next build().
   */
  setCompare(columns, differences) {
    this.compare = {columns, differ: differences.differ, steps: differences.steps};
  }

  /** Under A's row of `key`, B's (comparing), its steps that differ marked on both. */
  addCompared(kind, key, label, parent, attributes, what) {
    const a = this.strips[this.strips.length - 1];
    if (!this.compare) return a;
    a.marks = what === null ? undefined : this.compare.differ[what] || [];
    a.row.dataset.run = 'a';
    a.row.querySelector('.label').textContent = `A ${label}`;
    const b = this.add(kind, key, `B ${label}`, parent, ROW_HEIGHT, {...attributes, 'data-run': 'b'}, this.compare.columns);
    b.marks = a.marks;
    return b;
  }

  /** The rows of `graph` (the JSON dump): behaviours in execution order, then its state machines. */
  build(graph) {
    this.observer.disconnect();
    this.rows.replaceChildren();
    this.strips = [];
    this.groups.clear();
    this.visible.clear();
    this.add('timeline-axis', '', 'step · t', this.rows, AXIS_HEIGHT);
    for (const layer of graph.layers) {
      if (!layer.behaviours.length) continue;
      const group = html('div', {class: 'timeline-group', 'data-layer': layer.name}, this.rows);
      this.observer.observe(group);
      const head = html('button', {type: 'button', class: 'timeline-layer', 'aria-expanded': 'true'}, group);
      head.textContent = `${layer.name} (${layer.behaviours.length})`;
      head.onclick = () => this.folds.set(layer.name);
      this.groups.set(layer.name, {group, head});
      this.showFold(layer.name);
      for (const behaviour of layer.behaviours) {
        const key = `${layer.name}/${behaviour.name}`;
        const strip = this.add('timeline', key, key, group, ROW_HEIGHT, {'data-name': key});
        strip.row.querySelector('.label').onclick = () => this.onLabel(key);
        this.addCompared('timeline', key, key, group, {'data-name': key}, key);
      }
    }
    if (this.compare) {
      // Behaviours only B's config has (A's only have an empty B row).
      const inA = new Set(graph.layers.flatMap((layer) => layer.behaviours.map((b) => `${layer.name}/${b.name}`)));
      const onlyB = [...this.compare.columns.behaviours.keys()].filter((key) => !inA.has(key));
      if (onlyB.length) {
        const group = html('div', {class: 'timeline-group', 'data-layer': ''}, this.rows);
        this.observer.observe(group);
        html('span', {class: 'timeline-layer'}, group).textContent = `only in B (${onlyB.length})`;
        for (const key of onlyB) {
          const strip = this.add('timeline', key, `B ${key}`, group, ROW_HEIGHT, {'data-name': key, 'data-run': 'b'},
                                 this.compare.columns);
          strip.marks = this.compare.differ[key] || [];
        }
      }
    }
    for (const machine of graph.state_machines || []) {
      const strip = this.add('timeline-machine', machine.name, machine.name, this.rows, ROW_HEIGHT,
                             {'data-machine': machine.name});
      strip.row.querySelector('.label').onclick = () => this.onLabel(`state_machines/${machine.name}`);
      this.addCompared('timeline-machine', machine.name, machine.name, this.rows, {'data-machine': machine.name},
                       `machine:${machine.name}`);
      strip.note = html('div', {class: 'timeline-queue', 'data-machine': machine.name}, this.rows);
    }
    this.add('timeline-events', '', 'reported', this.rows, ROW_HEIGHT);
    this.addCompared('timeline-events', '', 'reported', this.rows, {}, null);
    this.applyFilter();
  }

  /** A click that showed `step`: on a state machine's lane, its state there is explained. */
  clicked(step, event) {
    const row = document.elementFromPoint(event.clientX, event.clientY)?.closest('[data-strip]');
    const strip = row ? this.strips[Number(row.dataset.strip)] : null;
    if (!strip || strip.kind !== 'timeline-machine') return;
    const {columns} = strip;
    const index = columns.indexAtOrBefore(step);
    const state = index >= 0 && columns.steps[index] === step ? columns.machines.get(strip.key)?.[index] : null;
    if (state) this.onState(strip.key, state);
  }

  showFold(layer) {
    const shown = this.groups.get(layer);
    if (!shown) return;
    const folded = this.folds.has(layer);
    shown.group.classList.toggle('collapsed', folded);
    shown.head.setAttribute('aria-expanded', String(!folded));
    this.view.changed();
  }

  /** Keeps the behaviour rows and lanes whose name holds the filter's text. */
  applyFilter() {
    const words = this.filter.value.trim().toLowerCase();
    this.onFilter(words);
    for (const strip of this.strips) {
      if (strip.kind !== 'timeline' && strip.kind !== 'timeline-machine') continue;
      strip.row.hidden = !!words && !strip.key.toLowerCase().includes(words);
      if (strip.note) strip.note.hidden = strip.row.hidden;
    }
    this.view.changed();
  }

  /**
   * The rows on the screen: those outside groups as the observer says, and the rows of the groups
   * on the screen by their rectangles, read before anything is drawn (the page is laid out once).
   */
  onScreen() {
    const shown = [];
    const bottom = window.innerHeight;
    for (const strip of this.strips) {
      if (!strip.group) {
        if (this.visible.has(strip.row)) shown.push(strip);
      } else if (this.visible.has(strip.group) && !strip.row.hidden && !strip.group.classList.contains('collapsed')) {
        const box = strip.row.getBoundingClientRect();
        if (box.bottom > 0 && box.top < bottom) shown.push(strip);
      }
    }
    return shown;
  }

  /** Redraws the rows on the screen. */
  draw() {
    const view = this.view;
    const shown = this.strips.length ? this.onScreen() : [];
    this.range.textContent = this.columns.length ? `steps ${view.from} to ${view.to}` : '';
    this.section.dataset.from = String(view.from);
    this.section.dataset.to = String(view.to);
    if (!this.strips.length) return;
    const ratio = window.devicePixelRatio || 1;
    const width = Math.round(this.stripWidth * ratio);
    if (!width) return;
    // Only the rows on the screen: a row filtered out or folded away is not displayed, and so
    // not intersecting.
    for (const strip of shown) {
      const canvas = strip.canvas;
      const height = Math.round(Number(canvas.getAttribute('height')) * ratio);
      if (canvas.width !== width || canvas.height !== height) {
        canvas.width = width;
        canvas.height = height;
      }
      const context = canvas.getContext('2d');
      context.setTransform(ratio, 0, 0, ratio, 0, 0);
      const w = width / ratio;
      const h = height / ratio;
      context.clearRect(0, 0, w, h);
      if (strip.kind === 'timeline') this.drawBehaviour(context, strip.columns, strip.key, w, h);
      else if (strip.kind === 'timeline-axis') this.drawAxis(context, w, h);
      else if (strip.kind === 'timeline-machine') this.drawMachine(context, strip, w, h);
      else if (strip.kind === 'timeline-events') this.drawEvents(context, strip.columns, w, h);
      if (strip.marks) this.drawMarks(context, strip.marks, w, h, strip.row.dataset.run === 'b');
      else if (strip.kind === 'timeline-axis' && this.compare) this.drawMarks(context, this.compare.steps, w, h, false);
      this.drawCursor(context, w, h);
    }
    this.showTip();
  }

  /** The indices of the steps in view in `columns`. */
  indices(columns = this.columns) {
    const steps = columns.steps;
    return [lowerBound(steps, this.view.from), lowerBound(steps, this.view.to + 1)];
  }

  /**
   * The steps where the compared runs differ (`runs`, [[from, to], ...]): an orange bar over
   * them, and on B's row an orange wash. At least a pixel wide, so that one step stays seen.
   */
  drawMarks(context, runs, w, h, wash) {
    const view = this.view;
    let i = lowerBoundBy(runs.length, (index) => runs[index][1], view.from);
    for (; i < runs.length && runs[i][0] <= view.to; ++i) {
      const left = Math.floor(view.x(Math.max(runs[i][0], view.from), w));
      const right = Math.max(left + 1, Math.ceil(view.x(Math.min(runs[i][1], view.to) + 1, w)));
      if (wash) {
        context.fillStyle = 'rgba(247, 144, 9, 0.22)';
        context.fillRect(left, 0, right - left, h);
      }
      context.fillStyle = '#f79009';
      context.fillRect(left, 0, right - left, 3);
      if (!wash && h > ROW_HEIGHT) context.fillRect(left, h - 4, right - left, 4);
    }
  }

  drawBehaviour(context, columns, key, w, h) {
    const series = columns.behaviours.get(key);
    if (!series) return;
    const {steps} = columns;
    const [begin, end] = this.indices(columns);
    const view = this.view;
    // Many steps to a pixel: each pixel column shows the highest activation among the steps that
    // touch it, and a bar if any of them was active (or inhibited), so that no activation is lost
    // to zooming out. Zoomed in, a step covers the pixels from the one its slot starts in to the
    // one the next step's starts in: no seams between steps. Runs of columns alike are drawn as
    // one rectangle: a long recording zoomed out draws a few hundred, not a rectangle and a
    // colour for each of its thousands of columns.
    const runs = {level: [], active: [], inhibited: []};  // [left, right, value] each
    const extend = (list, left, right, value) => {
      const run = list[list.length - 1];
      if (run && run[1] === left && run[2] === value) run[1] = right;
      else list.push([left, right, value]);
    };
    const perPixel = (view.to - view.from + 1) / w;
    const cover = perPixel > 1 ? Math.ceil : Math.floor;
    const count = Math.ceil(w) + 1;
    const tops = new Float32Array(count);
    const states = new Uint8Array(count);
    // Zoomed out to many steps a pixel, blocks of steps reduced beforehand (their highest
    // activation, their states together), a few to a pixel: a frame costs the pixels, not the
    // steps of a 100 000-step recording.
    const level = levelFor(perPixel, 1);
    const size = 2 ** level;
    const activation = level ? columns.pyramid(series.activation, 'most', most).level(level) : series.activation;
    const bits = level ? columns.pyramid(series.state, 'bits', (a, b) => a | b, stateBits).level(level) : null;
    for (let block = Math.floor(begin / size); block * size < end; ++block) {
      const i = block * size;
      const from = Math.max(0, Math.floor(view.x(steps[i], w)));
      const to = Math.min(count, Math.max(from + 1, cover(view.x(steps[Math.min(i + size, steps.length) - 1] + 1, w))));
      const a = Math.min(1, activation[block]);
      const state = bits ? bits[block] : stateBits(series.state[i]);
      for (let p = from; p < to; ++p) {
        if (a > tops[p]) tops[p] = a;
        states[p] |= state;
      }
    }
    for (let p = 0; p < count; ++p) {
      // 64 shades: enough for the eye, and runs of them join.
      if (tops[p] > 0) extend(runs.level, p, p + 1, Math.round(tops[p] * 64) / 64);
      if (states[p] & 1) extend(runs.active, p, p + 1, 1);
      else if (states[p] & 2) extend(runs.inhibited, p, p + 1, 1);
    }
    let style = '';
    for (const [from, to, level] of runs.level) {
      const fill = colour(level);
      if (fill !== style) context.fillStyle = style = fill;
      context.fillRect(from, h - 3 - level * (h - 5), to - from, level * (h - 5));
    }
    context.fillStyle = '#1b7f3b';
    for (const [from, to] of runs.active) context.fillRect(from, h - 3, to - from, 3);
    context.fillStyle = '#c62828';
    for (const [from, to] of runs.inhibited) context.fillRect(from, h - 2, to - from, 2);
  }

  drawAxis(context, w, h) {
    const view = this.view;
    context.fillStyle = '#667085';
    context.strokeStyle = '#d0d5dd';
    context.font = '10.5px "DejaVu Sans", system-ui, sans-serif';
    context.textAlign = 'center';
    context.textBaseline = 'top';
    const perStep = w / (view.to - view.from + 1);
    for (const tick of ticks(view.from, view.to, Math.max(2, Math.floor(w / 90)))) {
      const x = view.x(tick, w) + perStep / 2;
      // The labels at the ends stay inside the strip.
      context.textAlign = x < 30 ? 'left' : x > w - 30 ? 'right' : 'center';
      context.fillRect(x, 0, 1, 4);
      context.fillText(String(tick), x, 5);
      context.fillText(formatTime(this.columns.timeAt(tick)), x, 19);
    }
  }

  drawMachine(context, strip, w, h) {
    const states = strip.columns.machines.get(strip.key);
    if (states) {
      const {steps} = strip.columns;
      const [begin, end] = this.indices(strip.columns);
      context.font = '11px "DejaVu Sans", system-ui, sans-serif';
      context.textBaseline = 'middle';
      context.textAlign = 'left';
      // A band per run of steps in the same state.
      for (let i = begin; i < end;) {
        let j = i + 1;
        while (j < end && states[j] === states[i]) ++j;
        if (states[i] !== null) {
          const left = this.view.x(steps[i], w);
          const right = this.view.x(steps[j - 1] + 1, w);
          context.fillStyle = bandColour(states[i]);
          context.fillRect(left, 2, Math.max(1, right - left - 1), h - 4);
          const label = states[i];
          if (right - left > context.measureText(label).width + 8) {
            context.fillStyle = '#1d2733';
            context.fillText(label, left + 4, h / 2);
          }
        }
        i = j;
      }
    }
    if (!strip.note) return;  // B's lane: the queue shown is A's
    const queue = this.queueAt(strip.key);
    strip.note.textContent = queue ? `queue: ${queue.length ? queue.join(', ') : '(empty)'}` : '';
  }

  drawEvents(context, columns, w, h) {
    const events = columns.events;
    const stepsOf = (index) => events[index].step;
    let i = lowerBoundBy(events.length, stepsOf, this.view.from);
    context.font = '11px "DejaVu Sans", system-ui, sans-serif';
    context.textBaseline = 'middle';
    context.textAlign = 'left';
    let freeFrom = -Infinity;  // a label is written only where the one before it has ended
    for (; i < events.length && events[i].step <= this.view.to; ++i) {
      const x = this.view.x(events[i].step, w);
      // A breakpoint's stop stands out from what code reported.
      const isBreak = events[i].by === 'break';
      context.fillStyle = isBreak ? '#7a0bc0' : '#a63603';
      context.fillRect(x, 2, isBreak ? 3 : 2, h - 4);
      const label = `${events[i].by}: ${events[i].text}`;
      if (x + 4 >= freeFrom) {
        context.fillText(label, x + 5, h / 2);
        freeFrom = x + 5 + context.measureText(label).width + 6;
      }
    }
  }

  drawCursor(context, w, h) {
    const view = this.view;
    const perStep = w / (view.to - view.from + 1);
    if (view.hover !== null) {
      context.fillStyle = 'rgba(21, 112, 239, 0.35)';
      context.fillRect(view.x(view.hover, w) + perStep / 2 - 0.5, 0, 1, h);
    }
    if (view.cursor !== null && view.cursor >= view.from && view.cursor <= view.to) {
      context.fillStyle = '#d92d20';
      context.fillRect(view.x(view.cursor, w) + perStep / 2 - 1, 0, 2, h);
    }
  }

  /** The tip: the step under the pointer, its time, and the row's values there. */
  showTip() {
    const view = this.view;
    const pointer = this.pointer;
    if (!pointer || view.hover === null) {
      this.tip.hidden = true;
      return;
    }
    const step = view.hover;
    const {strip} = pointer;
    const columns = strip.columns;
    const index = columns.indexAtOrBefore(step);
    const lines = [`step ${step}  ${formatTime(columns.timeAt(step))}`];
    if (strip.kind === 'timeline' && index >= 0 && columns.steps[index] === step) {
      const series = columns.behaviours.get(strip.key);
      if (series) {
        const state = series.state[index] === ACTIVE ? 'active' : series.state[index] === INHIBITED ? 'inhibited' : 'inactive';
        lines.push(`${strip.key}: activation ${series.activation[index].toFixed(2)}, ${state}`);
      }
    } else if (strip.kind === 'timeline-machine' && index >= 0) {
      lines.push(`${strip.key}: ${columns.machines.get(strip.key)?.[index] ?? '(no state)'}`);
    } else if (strip.kind === 'timeline-events') {
      for (const event of columns.events) if (event.step === step) lines.push(`${event.by}: ${event.text}`);
    }
    // Comparing: which run the row is, and what differs at the step.
    if (strip.row.dataset.run) lines[1] = `${strip.row.dataset.run.toUpperCase()} ${lines[1] ?? ''}`.trimEnd();
    if (strip.marks && strip.marks.some(([from, to]) => from <= step && step <= to)) lines.push('A and B differ here');
    this.tip.textContent = lines.join('\n');
    this.tip.hidden = false;
    const box = this.section.getBoundingClientRect();
    this.tip.style.left = `${pointer.x - box.left + 12}px`;
    this.tip.style.top = `${pointer.y - box.top + 14}px`;
  }
}

/** A step's state as bits: 1 active, 2 inhibited (a block of steps ORs them). */
const stateBits = (state) => (state === ACTIVE ? 1 : state === INHIBITED ? 2 : 0);

/** The first index below `length` whose value (`valueAt`, ascending) is >= `value`. */
function lowerBoundBy(length, valueAt, value) {
  let low = 0;
  let high = length;
  while (low < high) {
    const middle = (low + high) >>> 1;
    if (valueAt(middle) < value) low = middle + 1;
    else high = middle;
  }
  return low;
}
