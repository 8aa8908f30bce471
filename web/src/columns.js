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
