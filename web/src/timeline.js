// A timeline per behaviour: its activation over the last HISTORY steps up to the one shown, a
// green bar where it was active and a red one where it requested a level but was inhibited.
import {colour, html} from './dom.js';
import {HISTORY, levelsOf} from './records.js';

export class Timelines {
  /**
   * @param {HTMLElement} rows where the rows go
   * @param {HTMLElement} range the label of the steps shown
   */
  constructor(rows, range) {
    this.rows = rows;
    this.range = range;
    this.canvases = new Map();  // 'layer/name' -> canvas
  }

  /** A row per behaviour of `graph` (the JSON dump), in execution order. */
  build(graph) {
    this.rows.replaceChildren();
    this.canvases.clear();
    for (const layer of graph.layers) {
      for (const behaviour of layer.behaviours) {
        const key = `${layer.name}/${behaviour.name}`;
        const row = html('div', {class: 'timeline', 'data-name': key}, this.rows);
        html('span', {class: 'label', title: key}, row).textContent = key;
        this.canvases.set(key, html('canvas', {width: 3 * HISTORY, height: 26}, row));
      }
    }
  }

  /** Draws the HISTORY records of `records` up to `current` (the last one if null). */
  draw(records, current) {
    const end = current ? records.indexOf(current) + 1 : records.length;
    const begin = Math.max(0, end - HISTORY);
    this.range.textContent = end > begin ? `steps ${records[begin].step} to ${records[end - 1].step}` : '';
    for (const [key, canvas] of this.canvases) {
      const context = canvas.getContext('2d');
      const w = canvas.width / HISTORY;
      const h = canvas.height;
      context.clearRect(0, 0, canvas.width, h);
      for (let i = begin; i < end; ++i) {
        const levels = levelsOf(records[i], key);
        if (!levels) continue;
        const x = (i - begin) * w;
        const a = Math.max(0, Math.min(1, Number(levels.activation) || 0));
        context.fillStyle = colour(a);
        context.fillRect(x, h - 3 - a * (h - 5), Math.ceil(w), a * (h - 5));
        if (levels.active) {
          context.fillStyle = '#1b7f3b';
          context.fillRect(x, h - 3, Math.ceil(w), 3);
        } else if (levels.requested > 0) {
          context.fillStyle = '#c62828';
          context.fillRect(x, h - 2, Math.ceil(w), 2);
        }
      }
    }
  }
}
