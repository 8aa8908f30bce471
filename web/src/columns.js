// The run's step records as columns: an array per behaviour, per numeric actuator component and
// per state machine, index for index with the steps. The timelines and plots draw thousands of
// steps per frame from these, without walking the records' nested objects.

/** The first index at which `array` (ascending) holds a value >= `value`. */
export function lowerBound(array, value) {
  let low = 0;
  let high = array.length;
  while (low < high) {
    const middle = (low + high) >>> 1;
    if (array[middle] < value) low = middle + 1;
    else high = middle;
  }
  return low;
}

/**
 * A series reduced by blocks of 2, 4, 8 ... values, built as asked (Columns.pyramid keeps it
 * until the series changes): zoomed out to many steps a pixel, the timelines and plots draw from the level whose
 * blocks are about a pixel wide, so that a frame costs its pixels rather than its steps.
 */
export class Pyramid {
  /**
   * @param {ArrayLike<number|null>} series
   * @param {(a: any, b: any) => any} reduce of two values (or blocks) into one
   * @param {(value: any) => any} [first] a value of the series as a block of one
   */
  constructor(series, reduce, first = (value) => value) {
    this.series = series;
    this.reduce = reduce;
    this.first = first;
    this.levels = [];  // levels[k - 1]: blocks of 2^k values
  }

  /** The blocks of 2^k values (k >= 1), the last one perhaps shorter. */
  level(k) {
    while (this.levels.length < k) {
      const below = this.levels.length ? this.levels[this.levels.length - 1] : null;
      const count = below ? below.length : this.series.length;
      const at = below ? (i) => below[i] : (i) => this.first(this.series[i]);
      const level = new Array(Math.ceil(count / 2));
      for (let i = 0; i + 1 < count; i += 2) level[i >> 1] = this.reduce(at(i), at(i + 1));
      if (count % 2) level[level.length - 1] = at(count - 1);
      this.levels.push(level);
    }
    return this.levels[k - 1];
  }
}

/** The larger of two numbers, a NaN or null being none. */
export const most = (a, b) => (a === null || a !== a ? b : b === null || b !== b ? a : a > b ? a : b);
/** The smaller of two numbers, a NaN or null being none. */
export const least = (a, b) => (a === null || a !== a ? b : b === null || b !== b ? a : a < b ? a : b);

/**
 * The Pyramid level for `perPixel` steps to a pixel, `finer` levels under the one whose blocks
 * are a pixel or two wide; 0 (the steps themselves) when few steps share a pixel.
 */
export function levelFor(perPixel, finer = 0) {
  return perPixel >= 4 ? Math.max(0, Math.floor(Math.log2(perPixel)) - finer) : 0;
}

// A behaviour's state in a step, as the timelines colour it.
export const IDLE = 0;
export const ACTIVE = 1;
export const INHIBITED = 2;  // requested a level but was inhibited

export class Columns {
  constructor() {
    this.steps = [];
    this.t = [];
    /** @type {Map<string, {activation: number[], state: number[]}>} 'layer/behaviour' */
    this.behaviours = new Map();
    this.byLayer = new Map();  // the same series: layer -> behaviour -> series
    /** @type {Map<string, (number|null)[]>} 'actuator' or 'actuator[i]': numbers, null where none (a gap in a plot) */
    this.values = new Map();
    /** @type {Map<string, (string|null)[]>} state machine -> its state in each step */
    this.machines = new Map();
    /** @type {{step: number, by: string, text: string}[]} what code reported, in step order */
    this.events = [];
    this.dropped = 0;  // steps dropped from the front: with the length, tells a Pyramid to rebuild
    this.pyramids = new WeakMap();  // series -> {name: Pyramid}
  }

  /**
   * The Pyramid of `series` (one of these columns' arrays) by `reduce`, under `name`, kept while
   * the columns only grow.
   */
  pyramid(series, name, reduce, first) {
    let mine = this.pyramids.get(series);
    if (!mine) this.pyramids.set(series, (mine = {}));
    let pyramid = mine[name];
    const stamp = `${this.dropped}/${series.length}`;
    if (!pyramid || pyramid.stamp !== stamp) {
      pyramid = mine[name] = new Pyramid(series, reduce, first);
      pyramid.stamp = stamp;
    }
    return pyramid;
  }

  get length() {
    return this.steps.length;
  }

  /** A new series, NaN (or `fill`) up to the steps before this one. */
  series(map, key, fill = NaN) {
    let series = map.get(key);
    if (!series) {
      series = new Array(this.steps.length - 1).fill(fill);
      map.set(key, series);
    }
    return series;
  }

  /** Appends `record` (the trace format), the next step. */
  push(record) {
    const length = this.steps.length + 1;
    this.steps.push(record.step);
    this.t.push(typeof record.t === 'number' ? record.t : NaN);
    for (const layer in record.layers || {}) {
      const behaviours = record.layers[layer];
      // By layer, then name: no 'layer/name' string to build for each behaviour of each step.
      let named = this.byLayer.get(layer);
      if (!named) this.byLayer.set(layer, (named = new Map()));
      for (const name in behaviours) {
        const levels = behaviours[name];
        let series = named.get(name);
        if (!series) {
          series = {activation: new Array(length - 1).fill(NaN), state: new Array(length - 1).fill(IDLE)};
          this.behaviours.set(`${layer}/${name}`, series);
          named.set(name, series);
        }
        series.activation.push(Number(levels.activation) || 0);
        series.state.push(levels.active ? ACTIVE : levels.requested > 0 ? INHIBITED : IDLE);
      }
    }
    for (const [name, actuator] of Object.entries(record.actuators || {})) {
      const value = actuator.value;
      if (Array.isArray(value)) {
        value.forEach((component, i) => this.series(this.values, `${name}[${i}]`, null).push(toNumber(component)));
      } else {
        this.series(this.values, name, null).push(toNumber(value));
      }
    }
    for (const [name, machine] of Object.entries(record.controllers || {})) {
      this.series(this.machines, name, null).push(machine.state || null);
    }
    for (const event of record.reported || []) this.events.push({step: record.step, by: event.by, text: event.text});
    // A series this record did not have (a behaviour removed by a reload) keeps its length.
    for (const series of this.behaviours.values()) {
      if (series.activation.length < length) {
        series.activation.push(NaN);
        series.state.push(IDLE);
      }
    }
    for (const series of this.values.values()) if (series.length < length) series.push(null);
    for (const series of this.machines.values()) if (series.length < length) series.push(null);
  }

  /** Drops the first `count` steps. */
  dropFront(count) {
    if (count <= 0) return;
    this.dropped += count;
    const first = this.steps[Math.min(count, this.steps.length) - 1];
    this.steps.splice(0, count);
    this.t.splice(0, count);
    for (const series of this.behaviours.values()) {
      series.activation.splice(0, count);
      series.state.splice(0, count);
    }
    for (const series of this.values.values()) series.splice(0, count);
    for (const series of this.machines.values()) series.splice(0, count);
    this.events.splice(0, lowerBound(this.events.map((event) => event.step), first + 1));
  }

  /** The index of `step`, or of the last step before it (-1: none). */
  indexAtOrBefore(step) {
    const index = lowerBound(this.steps, step);
    return index < this.steps.length && this.steps[index] === step ? index : index - 1;
  }

  /** The run's time at `step` (seconds), or NaN. */
  timeAt(step) {
    const index = this.indexAtOrBefore(step);
    return index >= 0 ? this.t[index] : NaN;
  }
}

function toNumber(value) {
  if (typeof value === 'number') return value;
  if (typeof value === 'boolean') return value ? 1 : 0;
  return null;
}
