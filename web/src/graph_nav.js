// Finding one's way in a large graph (graph.js): zoom (the wheel about the pointer, + and -, a
// button), pan (a drag on empty space, the arrow keys, Shift+wheel), fit the whole graph (0, a
// button), and a search by name that marks the matches and brings each into view in turn (Enter,
// Shift+Enter). The graph is moved by a CSS transform of its SVG inside a stage that clips it:
// panning and zooming change one style, not the drawing. A graph that grows past the view (an
// edit) is fitted again, or what it added is brought into view once the view was moved by hand.
import {html} from './dom.js';

const MIN_SCALE = 0.05;
const MAX_SCALE = 4;
const STEP = 1.25;      // a key or button's zoom
const READABLE = 0.8;   // a search brings its match to at least this scale
const MARGIN = 16;      // px around the graph when it is fitted
export const MOVED = 4;  // px: a press that moves less is a click (the studio's drags too)
const EDGE = 40;        // px: a drag this near the stage's edge pans the view that way
const EDGE_SPEED = 12;  // px a frame that it pans with the pointer at the edge itself

export class Viewport {
  /**
   * @param {HTMLElement} stage the element that clips the graph and takes its pointer and keys
   * @param {SVGSVGElement} svg
   * @param {(target: Element) => boolean} canPan whether a drag from `target` pans
   */
  constructor(stage, svg, canPan) {
    this.stage = stage;
    this.svg = svg;
    this.scale = 1;
    this.x = 0;  // px: where the graph's (0, 0) is in the stage
    this.y = 0;
    this.fitted = false;  // once: a graph drawn again keeps the view it had
    this.byHand = false;  // zoomed or panned since the graph was last fitted
    /** Called when the graph moved in the stage (panned, zoomed). */
    this.onMove = () => {};
    stage.addEventListener('wheel', (event) => {
      event.preventDefault();
      const sideways = Math.abs(event.deltaX) > Math.abs(event.deltaY);
      if (sideways) this.pan(-event.deltaX, 0);
      else if (event.shiftKey) this.pan(-event.deltaY, 0);
      else this.zoom(Math.exp(-event.deltaY * 0.002), ...this.atPointer(event));
    }, {passive: false});
    let drag = null;
    stage.addEventListener('pointerdown', (event) => {
      if (!event.target.closest('input, select, textarea, button')) stage.focus({preventScroll: true});
      if (event.button !== 0 || !canPan(event.target)) return;
      drag = {pointer: event.pointerId, cx: event.clientX, cy: event.clientY, x: this.x, y: this.y, moved: false};
    });
    stage.addEventListener('pointermove', (event) => {
      if (!drag || event.pointerId !== drag.pointer) return;
      const dx = event.clientX - drag.cx;
      const dy = event.clientY - drag.cy;
      if (!drag.moved) {
        if (Math.hypot(dx, dy) < MOVED) return;
        // Captured once it is a drag, not before: a click still goes to what was clicked.
        drag.moved = true;
        stage.setPointerCapture(event.pointerId);
        stage.classList.add('panning');
      }
      this.byHand = true;
      this.moveTo(drag.x + dx, drag.y + dy);
    });
    const end = () => {
      if (!drag) return;
      drag = null;
      stage.classList.remove('panning');
    };
    stage.addEventListener('pointerup', end);
    stage.addEventListener('pointercancel', end);
    // A layer's title reached by Tab is brought into view (the stage clips, it does not scroll).
    stage.addEventListener('focusin', (event) => {
      if (event.target instanceof SVGGraphicsElement) this.include(event.target.getBBox());
    });
    stage.addEventListener('keydown', (event) => {
      if (event.target.closest('input, select, textarea') || event.ctrlKey || event.metaKey || event.altKey) return;
      const by = (event.shiftKey ? 0.5 : 0.15);
      const {width, height} = this.box();
      if (event.key === '+' || event.key === '=') this.zoom(STEP);
      else if (event.key === '-') this.zoom(1 / STEP);
      else if (event.key === '0') this.fit();
      else if (event.key === 'ArrowLeft') this.pan(width * by, 0);
      else if (event.key === 'ArrowRight') this.pan(-width * by, 0);
      else if (event.key === 'ArrowUp') this.pan(0, height * by);
      else if (event.key === 'ArrowDown') this.pan(0, -height * by);
      else return;
      event.preventDefault();
    });
  }

  /**
   * While something is dragged (a behaviour, a layer): with the pointer (`clientX`, `clientY`)
   * within EDGE px of the stage's edge, the view pans that way every frame, faster nearer the edge,
   * until the graph's far side is in view, so that a drop off-screen can be reached. `moved()` runs
   * after each step: the graph moved under a pointer that stayed put. Called with every pointer
   * move of the drag; a pointer out of the band stops it, as stopEdgePan() does when the drag ends.
   */
  edgePan(clientX, clientY, moved) {
    this.edge = {clientX, clientY, moved};
    if (!this.edgeFrame) this.edgeFrame = requestAnimationFrame(() => this.edgeStep());
  }

  stopEdgePan() {
    this.edge = null;
    cancelAnimationFrame(this.edgeFrame);
    this.edgeFrame = 0;
  }

  edgeStep() {
    this.edgeFrame = 0;
    if (!this.edge) return;
    const [dx, dy] = this.edgeVelocity(this.edge.clientX, this.edge.clientY);
    if (!dx && !dy) return;
    this.pan(dx, dy);
    this.edge.moved();
    this.edgeFrame = requestAnimationFrame(() => this.edgeStep());
  }

  /** How far a frame of edgePan moves the graph, in px: [0, 0] away from the edges. */
  edgeVelocity(clientX, clientY) {
    const [px, py] = this.atPointer({clientX, clientY});
    const {width, height} = this.box();
    if (px < 0 || py < 0 || px > width || py > height) return [0, 0];
    const speed = (distance) => (distance < EDGE ? Math.ceil(EDGE_SPEED * (1 - distance / EDGE)) : 0);
    // Near the left edge the graph moves right, bringing in what is left of the view.
    const dx = speed(px) - speed(width - px);
    const dy = speed(py) - speed(height - py);
    // Never past the graph's own side, which stops EDGE px inside the stage.
    const right = this.x + (Number(this.svg.getAttribute('width')) || 1) * this.scale;
    const bottom = this.y + (Number(this.svg.getAttribute('height')) || 1) * this.scale;
    const limit = (d, near, far, size) =>
      (d > 0 ? Math.min(d, Math.max(0, EDGE - near)) : Math.max(d, Math.min(0, size - EDGE - far)));
    return [limit(dx, this.x, right, width), limit(dy, this.y, bottom, height)];
  }

  /** The stage's size, in px. */
  box() {
    return {width: this.stage.clientWidth, height: this.stage.clientHeight};
  }

  /** The point of the stage under the pointer of `event`. */
  atPointer(event) {
    const box = this.stage.getBoundingClientRect();
    return [event.clientX - box.left - this.stage.clientLeft, event.clientY - box.top - this.stage.clientTop];
  }

  /** The point of the graph (SVG user units) at (px, py) of the stage. */
  toGraph(px, py) {
    return {x: (px - this.x) / this.scale, y: (py - this.y) / this.scale};
  }

  apply() {
    this.svg.style.transform = `translate(${this.x}px, ${this.y}px) scale(${this.scale})`;
    this.stage.dataset.scale = String(this.scale);
    this.onMove();
  }

  moveTo(x, y) {
    this.x = x;
    this.y = y;
    this.apply();
  }

  pan(dx, dy) {
    this.byHand = true;
    this.moveTo(this.x + dx, this.y + dy);
  }

  /** Zooms by `factor` about (px, py) of the stage (its middle by default), which stays put. */
  zoom(factor, px = this.box().width / 2, py = this.box().height / 2) {
    const scale = Math.min(MAX_SCALE, Math.max(MIN_SCALE, this.scale * factor));
    this.byHand = true;
    const at = this.toGraph(px, py);
    this.scale = scale;
    this.moveTo(px - at.x * scale, py - at.y * scale);
  }

  /** The whole graph in the stage, centred; never enlarged past its own size. */
  fit() {
    const width = Number(this.svg.getAttribute('width')) || 1;
    const height = Number(this.svg.getAttribute('height')) || 1;
    const box = this.box();
    this.scale = Math.max(MIN_SCALE, Math.min(1, (box.width - 2 * MARGIN) / width, (box.height - 2 * MARGIN) / height));
    this.moveTo((box.width - width * this.scale) / 2, Math.max(MARGIN, (box.height - height * this.scale) / 2));
    this.byHand = false;
  }

  /** `rect` (SVG user units) in the middle of the stage, at a scale it can be read at. */
  show(rect) {
    if (this.scale < READABLE) this.scale = READABLE;
    this.centre(rect);
  }

  centre(rect) {
    this.byHand = true;
    const box = this.box();
    this.moveTo(box.width / 2 - (rect.x + rect.width / 2) * this.scale,
                box.height / 2 - (rect.y + rect.height / 2) * this.scale);
  }

  /** Whether `rect` (SVG user units) lies wholly in the stage. */
  shows(rect) {
    const box = this.box();
    const left = this.x + rect.x * this.scale;
    const top = this.y + rect.y * this.scale;
    return left >= 0 && top >= 0 && left + rect.width * this.scale <= box.width + 0.5 &&
           top + rect.height * this.scale <= box.height + 0.5;
  }

  /** `rect` (SVG user units) in the middle of the stage unless it is in it already. */
  include(rect) {
    if (!this.shows(rect)) this.centre(rect);
  }

  /** The graph is laid out anew (ELK's layout after a provisional one): fitted again unless moved. */
  refit() {
    if (!this.byHand) this.fitted = false;
  }

  /**
   * The graph was drawn (again): fitted the first time. After that a new graph (an edit, a
   * reload) that no longer fits in the stage is fitted again if the view is still the last fit,
   * else what it added (`added`, SVG user units; null: nothing, or nothing drawn) is brought into
   * the middle when it is out of the view; a view that shows it is kept as it is. A layer folded or
   * unfolded (`redrawn` false) keeps the view.
   */
  contentChanged(redrawn = false, added = null) {
    if (!this.fitted) {
      this.fitted = true;
      this.fit();
      return;
    }
    if (!redrawn) return;
    if (!this.byHand) {
      const whole = {x: 0, y: 0, width: Number(this.svg.getAttribute('width')) || 1,
                     height: Number(this.svg.getAttribute('height')) || 1};
      if (!this.shows(whole)) this.fit();
    } else if (added) {
      this.include(added);
    }
  }
}

/**
 * Gives `graph` (a GraphView drawn in `panel`) its zoom, pan and search: a bar of tools above it
 * and a stage around its SVG. A drag pans when it starts off a behaviour and a layer's title (a
 * view that drags them, the studio, keeps those drags). `onFind('layer/name')` is called with
 * each match the search brings into view.
 * @param {import('./graph.js').GraphView} graph
 * @param {HTMLElement} panel
 * @param {(key: string) => void} [onFind]
 */
export function navigate(graph, panel, onFind = () => {}) {
  const svg = graph.svg;
  const tools = html('div', {class: 'graph-tools'});
  panel.insertBefore(tools, svg);
  const stage = html('div', {class: 'graph-stage', tabindex: '0', 'aria-label': 'the graph: wheel or + − to zoom, drag or arrow keys to pan, 0 to fit'});
  panel.insertBefore(stage, svg);
  stage.appendChild(svg);
  const view = new Viewport(stage, svg, (target) => !target.closest('g.behaviour, g.layer-head, .layer-title'));
  graph.view = view;
  view.onMove = () => graph.screenChanged();

  const search = html('input', {id: 'graph-search', type: 'search', placeholder: 'find a behaviour', size: '22',
                                'aria-label': 'find a behaviour by name; Enter shows the next match, Shift+Enter the previous'}, tools);
  const count = html('span', {id: 'graph-matches', class: 'hint'}, tools);
  const button = (id, label, title, action) => {
    const b = html('button', {id, type: 'button', title}, tools);
    b.textContent = label;
    b.onclick = action;
  };
  button('zoom-out', '−', 'zoom out (−)', () => view.zoom(1 / STEP));
  button('zoom-in', '+', 'zoom in (+)', () => view.zoom(STEP));
  button('zoom-fit', 'Fit', 'the whole graph (0)', () => view.fit());
  html('span', {class: 'hint'}, tools).textContent =
      'wheel, + −: zoom · drag, arrows: pan · 0: fit · a layer\'s title: fold';

  let found = [];
  let at = -1;  // the match shown last
  const words = () => search.value.trim().toLowerCase();
  const mark = () => {
    graph.mark(words());
    found = graph.matches(words());
    at = -1;
    count.textContent = !words() ? '' : found.length ? `${found.length} found` : 'none found';
  };
  search.addEventListener('input', mark);
  search.addEventListener('keydown', (event) => {
    if (event.key === 'Escape') {
      search.value = '';
      mark();
    }
    if (event.key !== 'Enter') return;
    event.preventDefault();
    // The graph may have been drawn again since (an edit): the matches as they are now.
    found = graph.matches(words());
    if (!found.length) return;
    if (at < 0) at = event.shiftKey ? found.length - 1 : 0;
    else at = (at + (event.shiftKey ? -1 : 1) + found.length) % found.length;
    const key = found[at];
    graph.reveal(key);
    count.textContent = `${at + 1} of ${found.length}`;
    onFind(key);
  });
  return view;
}
