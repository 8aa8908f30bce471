// The layers folded away, one set for everything that draws a program's layers: the graph (a
// folded column keeps its title, sensors and actuators and hides its behaviours) and the
// timelines (a folded group hides its rows). Sharing one makes a fold in either show in both.

export class Folds {
  constructor() {
    this.folded = new Set();  // layer names
    this.listeners = new Set();
  }

  has(layer) {
    return this.folded.has(layer);
  }

  /** Folds `layer` (or unfolds it, `fold` false; toggles it by default) and tells the listeners. */
  set(layer, fold = !this.folded.has(layer)) {
    if (fold === this.folded.has(layer)) return;
    if (fold) this.folded.add(layer);
    else this.folded.delete(layer);
    for (const listener of this.listeners) listener(layer, fold);
  }

  /** Calls `listener(layer, folded)` at each change. */
  subscribe(listener) {
    this.listeners.add(listener);
  }
}
