// The step records both views draw: the trace format (docs/semantics.md, "The trace"), from the
// live stream or from a trace file.

/** Steps the live view's timelines show up to the newest, and the fewest it keeps (RunPage.trim). */
export const HISTORY = 300;

/**
 * A behaviour's levels in `record`, or undefined.
 * @param {object | null} record
 * @param {string} key 'layer/behaviour'
 */
export function levelsOf(record, key) {
  const [layer, name] = key.split('/');
  return record && record.layers && record.layers[layer] ? record.layers[layer][name] : undefined;
}

/**
 * Notes on each record since when each actuator it did not write has held its value, from the
 * records before it (fed in order): `record.held[name] = {writtenAt, knownFrom}`, where writtenAt
 * is the last step that wrote it (null: none seen) and knownFrom the first step seen without a gap.
 */
export class WriteTracker {
  constructor() {
    this.last = null;
    this.knownFrom = 1;
    this.at = new Map();
  }

  track(record) {
    if (this.last === null || record.step !== this.last + 1) {
      // The first record, or the page missed steps (it fell behind, or was away too long):
      // what was written before them is unknown.
      this.knownFrom = record.step;
      this.at.clear();
    }
    this.last = record.step;
    record.held = {};
    for (const [name, value] of Object.entries(record.actuators || {})) {
      if (value.written) this.at.set(name, record.step);
      else record.held[name] = {writtenAt: this.at.has(name) ? this.at.get(name) : null, knownFrom: this.knownFrom};
    }
  }
}
