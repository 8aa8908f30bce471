// The explain panel: the server's `explain` answer (the same as `arbiter explain`) for a
// behaviour, an actuator (`actuators/name`), a state machine or a state (`machine/state`) at the
// step shown, laid out to be read: the verdict as a heading, the inhibitors as a table. Clicking
// one (a behaviour or an actuator in the graph, a timeline's label, a state's band, a plotted
// value's name) pins the panel to it; hovering another shows that one until the pointer leaves.
// It follows the step shown: a click in the timelines explains that step.
import {html} from './dom.js';

const SUBJECT = 'Hover over a behaviour or an actuator, or click it (or a state in the timelines) to pin it here.';

/**
 * The text of an answer as HTML in `box`: the first line a heading, each line of three or more
 * columns (two spaces apart) a table row, the others paragraphs indented as they were.
 */
export function renderAnswer(box, text) {
  box.replaceChildren();
  const lines = text.replace(/\n+$/, '').split('\n');
  html('h3', {class: 'explain-head'}, box).textContent = lines[0];
  let table = null;
  for (const line of lines.slice(1)) {
    const indent = line.length - line.trimStart().length;
    const cells = line.trim().split(/\s{2,}/);
    if (cells.length >= 3) {
      if (!table) table = html('table', {class: 'explain-table'}, box);
      const row = html('tr', {}, table);
      // A space after each cell keeps the text readable when copied.
      cells.forEach((cell, i) => {
        html('td', {class: i === cells.length - 1 && cells.length > 3 ? 'explain-source' : ''}, row).textContent = `${cell} `;
      });
      continue;
    }
    table = null;
    const kind = /^activation = /.test(line.trim()) ? 'explain-formula' : indent === 0 ? 'explain-line' : 'explain-detail';
    const p = html('p', {class: kind}, box);
    p.style.paddingLeft = `${Math.max(0, indent - 2) * 0.5}em`;
    p.textContent = line.trim();
  }
}

export class ExplainPanel {
  /**
   * @param {HTMLElement} output where the answer goes
   * @param {HTMLElement} subject the line that names what is explained, and how to unpin it
   */
  constructor(output, subject) {
    this.output = output;
    this.subject = subject;
    this.step = null;     // the step shown
    this.hovered = null;  // 'layer/name', 'actuators/name', 'machine/state', ...: explain's names
    this.pinned = null;
    this.pending = false;
    this.shown = '';      // 'step key' of the answer shown
    /** Comparing two runs: {a, b}, their names; each is explained against its own config. */
    this.compare = null;
    /** Called when the pinned behaviour changes. */
    this.onPin = (key) => {};
  }

  get target() {
    return this.hovered || this.pinned;
  }

  /** What is hovered, or null: asks for its answer. */
  hover(key) {
    this.hovered = key;
    if (this.target) this.ask();
  }

  /** Pins the panel to `key` (null: unpins it). */
  pin(key) {
    this.pinned = key;
    this.onPin(key);
    this.subject.replaceChildren();
    if (key) {
      this.subject.append(`pinned: ${key} `);
      const unpin = html('button', {type: 'button', class: 'unpin', title: 'explain only what is hovered'}, this.subject);
      unpin.textContent = 'unpin';
      unpin.onclick = () => this.pin(null);
    } else {
      this.subject.textContent = SUBJECT;
    }
    this.subject.parentElement.dataset.pinned = key || '';
    if (this.target) this.ask();
  }

  /** The step the page shows: the answer follows it. */
  setStep(step) {
    this.step = step;
    if (this.target) this.ask();
  }

  async ask() {
    if (this.step === null || this.pending) return;
    const target = this.target;
    const asked = `${this.step} ${target}`;
    if (asked === this.shown) return;
    this.pending = true;
    try {
      const ask = (run) => fetch(`explain?step=${this.step}&target=${encodeURIComponent(target)}${run}`)
        .then(async (response) => ({ok: response.ok, text: await response.text()}));
      const answers = await Promise.all(this.compare ? [ask(''), ask('&run=b')] : [ask('')]);
      const show = (box, {ok, text}) => {
        if (ok) renderAnswer(box, text);
        else box.textContent = text;
      };
      if (!this.compare) show(this.output, answers[0]);
      else {
        this.output.replaceChildren();
        ['a', 'b'].forEach((run, i) => {
          html('p', {class: 'explain-run'}, this.output).textContent = `in ${run.toUpperCase()} (${this.compare[run]})`;
          show(html('div', {class: 'explain-answer', 'data-run': run}, this.output), answers[i]);
        });
      }
      this.output.dataset.step = String(this.step);
      this.output.dataset.target = target;
      this.shown = asked;
    } catch (error) {
      this.output.textContent = `explain failed: ${error}`;
    } finally {
      this.pending = false;
    }
    // The step or the behaviour changed while the answer was on its way.
    if (this.target && `${this.step} ${this.target}` !== this.shown) this.ask();
  }
}
