// The steps the timelines and plots show, shared by all of them: the range in view (zoomed and
// panned with the wheel, a drag or the keys), the cursor at the step the page shows, and the step
// under the pointer. Clicking a step asks the view to show it (onSeek).

const MIN_SPAN = 10;  // steps: zoomed in no further

export class TimeView {
  constructor() {
    this.first = 0;  // the steps the page has
    this.last = 0;
    this.from = 0;  // the steps in view
    this.to = 0;
    this.followSpan = Infinity;  // unzoomed, the view shows this many steps up to the last
    this.zoomed = false;
    this.cursor = null;  // the step the page shows
    this.hover = null;   // the step under the pointer
    /** @type {(step: number) => void} */
    this.onSeek = () => {};
    this.listeners = new Set();
    this.pending = false;
  }

  /** Calls `listener` (once per frame at most) whenever what is in view changes. */
  subscribe(listener) {
    this.listeners.add(listener);
  }

  changed() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => {
      this.pending = false;
      for (const listener of this.listeners) listener(this);
    });
  }

  /** The steps the page has: unzoomed, the view follows them. */
  setExtent(first, last) {
    this.first = first;
    this.last = last;
    if (this.zoomed) this.setRange(this.from, this.to);
    else {
      this.from = Math.max(first, last - this.followSpan + 1);
      this.to = last;
    }
    this.changed();
  }

  /** Shows steps `from` to `to`, kept inside the run. */
  setRange(from, to) {
    const extent = this.last - this.first;
    let span = Math.min(Math.max(to - from, Math.min(MIN_SPAN, extent)), extent);
    from = Math.max(this.first, Math.min(from, this.last - span));
    this.from = from;
    this.to = from + span;
    this.zoomed = this.from !== Math.max(this.first, this.last - this.followSpan + 1) || this.to !== this.last;
    this.changed();
  }

  /** Zooms by `factor` (< 1: in) about `anchor`, which stays where it is. */
  zoom(factor, anchor = (this.from + this.to) / 2) {
    const from = anchor - (anchor - this.from) * factor;
    const to = anchor + (this.to - anchor) * factor;
    this.setRange(Math.round(from), Math.round(to));
  }

  pan(steps) {
    steps = Math.round(steps);
    if (steps) this.setRange(this.from + steps, this.to + steps);
  }

  /** Back to the whole run (live: the last steps, following them). */
  reset() {
    this.zoomed = false;
    this.setExtent(this.first, this.last);
  }

  setCursor(step) {
    if (step === this.cursor) return;
    this.cursor = step;
    this.changed();
  }

  setHover(step) {
    if (step === this.hover) return;
    this.hover = step;
    this.changed();
  }

  /** The x of the left edge of `step` in a strip `width` pixels wide. */
  x(step, width) {
    return ((step - this.from) / (this.to - this.from + 1)) * width;
  }

  /** The step at `x` in a strip `width` pixels wide. */
  stepAt(x, width) {
    const step = Math.floor(this.from + (x / width) * (this.to - this.from + 1));
    return Math.max(this.from, Math.min(this.to, step));
  }
}

/**
 * Lets the pointer drive `view` over `element`, whose strip of steps is `strip()` (client
 * coordinates): the wheel zooms about the pointer (with Shift, or sideways, it pans), a drag pans,
 * a click shows the step, hovering marks it.
 * @param {HTMLElement} element
 * @param {TimeView} view
 * @param {() => {left: number, width: number}} strip
 * @param {(step: number, event: PointerEvent) => void} [clicked] after a click has shown `step`
 */
export function attachPointer(element, view, strip, clicked = () => {}) {
  const at = (event) => {
    const {left, width} = strip();
    return {x: event.clientX - left, width};
  };
  const inside = (event) => {
    const {x, width} = at(event);
    return x >= 0 && x < width;
  };
  element.addEventListener('wheel', (event) => {
    if (!inside(event) || view.last <= view.first) return;
    event.preventDefault();
    const {x, width} = at(event);
    const sideways = Math.abs(event.deltaX) > Math.abs(event.deltaY);
    if (event.shiftKey || sideways) {
      const delta = sideways ? event.deltaX : event.deltaY;
      view.pan((delta / width) * (view.to - view.from + 1));
    } else {
      view.zoom(Math.exp(event.deltaY * 0.002), view.from + (x / width) * (view.to - view.from + 1));
    }
  }, {passive: false});
  let drag = null;
  element.addEventListener('pointerdown', (event) => {
    if (!inside(event) || event.button !== 0) return;
    drag = {x: event.clientX, from: view.from, to: view.to, moved: false};
    element.setPointerCapture(event.pointerId);
  });
  element.addEventListener('pointermove', (event) => {
    const {x, width} = at(event);
    if (drag) {
      const dx = event.clientX - drag.x;
      if (Math.abs(dx) > 3) drag.moved = true;
      if (drag.moved) {
        const steps = Math.round((-dx / width) * (drag.to - drag.from + 1));
        view.setRange(drag.from + steps, drag.to + steps);
      }
    }
    view.setHover(x >= 0 && x < width ? view.stepAt(x, width) : null);
  });
  element.addEventListener('pointerup', (event) => {
    if (!drag) return;
    const moved = drag.moved;
    drag = null;
    if (!moved && inside(event)) {
      const {x, width} = at(event);
      const step = view.stepAt(x, width);
      view.onSeek(step);
      clicked(step, event);
    }
  });
  element.addEventListener('pointerleave', () => {
    if (!drag) view.setHover(null);
  });
}

/**
 * The keys, while `element` has the focus: + and - zoom, 0 shows the whole run, Shift+← and
 * Shift+→ pan (← and → alone step through a trace).
 */
export function attachKeys(element, view) {
  element.addEventListener('keydown', (event) => {
    // Typing in a field (the filter by name) is typing.
    if (event.target.closest('input, select, textarea')) return;
    const span = view.to - view.from + 1;
    if (event.key === '+' || event.key === '=') view.zoom(0.5, view.cursor ?? undefined);
    else if (event.key === '-') view.zoom(2, view.cursor ?? undefined);
    else if (event.key === '0') view.reset();
    else if (event.shiftKey && event.key === 'ArrowLeft') view.pan(-span / 4);
    else if (event.shiftKey && event.key === 'ArrowRight') view.pan(span / 4);
    else return;
    event.preventDefault();
    event.stopPropagation();
  });
}
