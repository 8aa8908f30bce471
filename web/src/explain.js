// The explain panel: the server's `explain` answer for the hovered behaviour at the step shown
// (the same answer as `arbiter explain`).

export class ExplainPanel {
  /** @param {HTMLElement} output */
  constructor(output) {
    this.output = output;
    this.step = null;     // the step shown
    this.hovered = null;  // 'layer/name'
    this.pending = false;
    this.shown = '';      // 'step key' of the answer shown
  }

  /** The behaviour hovered, or null: asks for its answer. */
  hover(key) {
    this.hovered = key;
    if (key) this.ask();
  }

  /** The step the page shows: the hovered behaviour's answer follows it. */
  setStep(step) {
    this.step = step;
    if (this.hovered) this.ask();
  }

  async ask() {
    if (this.step === null || this.pending) return;
    const asked = `${this.step} ${this.hovered}`;
    if (asked === this.shown) return;
    this.pending = true;
    try {
      const response = await fetch(`explain?step=${this.step}&target=${encodeURIComponent(this.hovered)}`);
      this.output.textContent = await response.text();
      this.shown = asked;
    } catch (error) {
      this.output.textContent = `explain failed: ${error}`;
    } finally {
      this.pending = false;
    }
    // The step or the behaviour changed while the answer was on its way.
    if (this.hovered && `${this.step} ${this.hovered}` !== this.shown) this.ask();
  }
}
