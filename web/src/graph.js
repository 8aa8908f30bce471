// The graph of a program (the JSON dump): a column per layer, in execution order, with its
// sensors on top, its behaviours laid out by ELK's layered algorithm with the inhibitions as
// edges (inhibitor above inhibited), and its actuators below; actuator -> sensor flows between
// the columns. Boxes are sized to the text they hold, measured in the page's font, and ELK keeps
// edges off the boxes, so no label lies under an edge. A click on a layer's title folds its
// behaviours away (folds.js); graph_nav.js adds zoom, pan and search.
import ELK from 'elkjs/lib/elk-api.js';
import {version as elkVersion} from 'elkjs/package.json';

import {colour, el, formatValue, text} from './dom.js';
import {Folds} from './folds.js';
import {quickLayout} from './quick_layout.js';
import {levelsOf} from './records.js';

const COLUMN = 270;   // the narrowest width of a layer's column
const BOX_W = 168;    // the narrowest behaviour box
const BOX_H = 40;
const PORT_H = 22;
const BAR = 5;        // half the inhibited end's bar, and how far before the box it is
// Values as wide as most of each type's, to size actuator rows by.
const TYPICAL_VALUE = {bool: 'false', int: '-12345', double: '-12.345', vec2: '[-1.234, -1.234]',
                       vec3: '[-1.234, -1.234, -1.234]', string: '"a short text"', other: '{"a": 1, "b": 2}'};
const INHIBITORS_ROOM = 260;  // a list of inhibitors wider than this is wrapped
const LARGE = 200;            // behaviours: from here, only those on the screen are redrawn,
const LARGE_PERIOD = 100;     // and at most every this many ms
const FOLD_MARK = 14;         // room for the ▾ before a layer's title

// ELK lays out in web workers (elk-worker.js, served beside app.js): a layer of 50 behaviours
// costs it tens of milliseconds of CPU, which the page's thread would spend not answering. Two
// workers lay out two layers at once on two cores; more would mostly wait for one.
const WORKERS = 2;
let pool = null;
/** The workers, started at the first call: [{elk, failed, pending, layouts}]. */
function workers() {
  pool ??= Array.from({length: WORKERS}, () => {
    // A worker that cannot load (its script not served) would leave its layouts waiting for
    // ever: `failed` rejects instead, and the drawing fails with the reason.
    let fail;
    const failed = new Promise((resolve, reject) => { fail = reject; });
    failed.catch(() => {});
    const elk = new ELK({
      workerUrl: 'elk-worker.js',
      workerFactory: (url) => {
        const worker = new Worker(url);
        worker.addEventListener('error', (event) =>
          fail(new Error(`ELK's worker (${url}) failed: ${event.message || 'its script did not load'}`)));
        return worker;
      },
    });
    return {elk, failed, pending: 0, layouts: 0};
  });
  return pool;
}

/**
 * ELK's layout of `graph`, by `worker` or else the one with the least work queued (counted in
 * boxes and edges).
 */
function elkLayout(graph, worker = workers().reduce((a, b) => (b.pending < a.pending ? b : a))) {
  const cost = graph.children.length + graph.edges.length;
  worker.pending += cost;
  ++worker.layouts;
  const done = () => { worker.pending -= cost; };
  const layout = worker.elk.layout(graph);
  layout.then(done, done);
  return Promise.race([layout, worker.failed]);
}
const LAYOUT = {
  'elk.algorithm': 'layered',
  'elk.direction': 'DOWN',
  'elk.edgeRouting': 'ORTHOGONAL',
  // Behaviours that no inhibition orders stay in execution order, left to right.
  'elk.layered.considerModelOrder.strategy': 'NODES_AND_EDGES',
  'elk.spacing.nodeNode': '20',
  'elk.layered.spacing.nodeNodeBetweenLayers': '34',
  'elk.spacing.edgeNode': '14',
  'elk.layered.spacing.edgeNodeBetweenLayers': '14',
  'elk.spacing.edgeEdge': '10',
  'elk.padding': '[top=0,left=0,bottom=0,right=0]',
};

// Widths of text as the page draws it: a hidden probe inside `svg` carries the classes the CSS
// sizes text by (`.behaviour .name`, `.port text`, ...). Each text is measured once, and the
// texts prepare()d before the first width is read are laid out together: one layout of the page
// for all of them, where one per text cost most of a large graph's drawing. `widths` (class,
// class, text -> width) keeps them from one drawing to the next: an edit or a reload measures only
// the texts it brings (the page's fonts are the system's, which do not change under it).
const KEPT_WIDTHS = 20000;  // texts kept at most: a long session of renames does not grow them for ever
function textMeasure(svg, widths = new Map()) {
  const probe = el('g', {visibility: 'hidden'}, svg);
  const known = new Map();  // class, class, text -> its node, until its width is read
  if (widths.size > KEPT_WIDTHS) widths.clear();
  const prepare = (content, groupClass, textClass) => {
    const key = `${groupClass ?? ''}\n${textClass ?? ''}\n${content}`;
    if (!widths.has(key) && !known.has(key)) {
      const group = el('g', groupClass ? {class: groupClass} : {}, probe);
      known.set(key, text('text', textClass ? {class: textClass, x: 0, y: 0} : {x: 0, y: 0}, content, group));
    }
    return key;
  };
  let rendered = false;  // some text measured wider than 0: the graph is on the page
  const measure = (content, groupClass, textClass) => {
    const key = prepare(content, groupClass, textClass);
    const kept = widths.get(key);
    if (kept !== undefined) return kept;
    let width = known.get(key);
    if (typeof width !== 'number') {
      width = width.getComputedTextLength();
      known.set(key, width);
      rendered ||= width > 0;
    }
    return width;
  };
  /** Adds a text to be measured with the others; its width is 0 until measured. */
  measure.prepare = (content, groupClass, textClass) => {
    prepare(content, groupClass, textClass);
    return 0;
  };
  measure.done = () => {
    probe.remove();
    // A text the CSS hides (the studio's levels) is 0 wide, and kept so; but when nothing was
    // wider, the graph itself was not rendered (display: none), and nothing is kept.
    if (!rendered) return;
    for (const [key, width] of known) {
      if (typeof width === 'number') widths.set(key, width);
    }
  };
  return measure;
}

// Wraps lists of inhibitors of a layer's behaviours ("⊣ a, b, c") into lines of at most `room`
// pixels, by the widths of their names. A list that is a part of another, in the same order,
// never takes more lines than it: so the lines a box has for all of its inhibitors are enough
// for any of them.
function inhibitorWrap(layer, measure) {
  const widthOf = new Map(layer.behaviours.map((behaviour) => [behaviour.name, measure(behaviour.name, 'behaviour', 'level')]));
  const x = measure('x', 'behaviour', 'level');
  const separator = measure('x, x', 'behaviour', 'level') - 2 * x;
  const indent = measure('⊣ x', 'behaviour', 'level') - x;
  const slack = 2 + separator;  // for the comma that ends a line, and rounding
  return {
    indent,
    width: (list) => indent + list.reduce((sum, name) => sum + widthOf.get(name), 0) + separator * (list.length - 1) + slack,
    widest: (list) => indent + Math.max(...list.map((name) => widthOf.get(name))) + slack,
    lines(list, room) {
      const lines = [];
      let width = 0;
      for (const name of list) {
        const w = widthOf.get(name);
        if (lines.length && width + separator + w + slack <= room) {
          lines[lines.length - 1].push(name);
          width += separator + w;
        } else {
          lines.push([name]);
          width = indent + w;
        }
      }
      return lines;
    },
  };
}

// The sizes of a layer's boxes and rows, from the widths of what they will hold.
function sizeLayer(layer, measure) {
  // Each behaviour's possible inhibitors (declared and implied), in execution order.
  const rowIndex = new Map(layer.behaviours.map((behaviour, row) => [behaviour.name, row]));
  const inhibitorsOf = new Map(layer.behaviours.map((behaviour) => [behaviour.name, []]));
  for (const inhibition of layer.inhibitions) inhibitorsOf.get(inhibition.inhibited)?.push(inhibition.inhibitor);
  for (const list of inhibitorsOf.values()) list.sort((a, b) => rowIndex.get(a) - rowIndex.get(b));
  let boxW = BOX_W;
  for (const behaviour of layer.behaviours) {
    boxW = Math.max(boxW, 34 + measure(behaviour.name, 'behaviour', 'name') + 10,
                    34 + measure('activation 0.00 of 0.00', 'behaviour', 'level') + 10);
  }
  // The active inhibitors are listed under the levels, wrapped to the box: it is as wide as the
  // longest list needs, up to INHIBITORS_ROOM, and has as many lines as the longest list takes at
  // that width.
  const wrap = inhibitorWrap(layer, measure);
  let room = boxW - 44;
  for (const list of inhibitorsOf.values()) {
    if (list.length) room = Math.max(room, Math.min(INHIBITORS_ROOM, wrap.width(list)), wrap.widest(list));
  }
  boxW = room + 44;
  let sensorW = boxW;
  for (const sensor of layer.sensors) sensorW = Math.max(sensorW, 8 + measure(sensor.name, 'port') + 10);
  // An actuator's row holds its name, its value (as wide as a typical one of its type) and, when
  // the value is held, since when.
  const heldW = measure('held since step 12345', 'port', 'held-note');
  const actuatorW = Math.max(0, ...layer.actuators.map((actuator) =>
      Math.max(COLUMN - 44, 8 + measure(actuator.name, 'port') + 10 +
               measure(TYPICAL_VALUE[actuator.type] || TYPICAL_VALUE.other, 'port', 'value') + 8 + heldW + 8)));
  const titleW = Math.max(measure(layer.name, null, 'layer-title'),
                          measure(layer.interface ? `interface ${layer.interface}` : 'normalised', null, 'layer-class'));
  const heights = new Map(layer.behaviours.map((behaviour) =>
      [behaviour.name, BOX_H + 12 * wrap.lines(inhibitorsOf.get(behaviour.name), room).length]));
  const nameW = new Map(layer.actuators.map((actuator) => [actuator.name, measure(actuator.name, 'port')]));
  return {rowIndex, wrap, room, boxW, sensorW, actuatorW, titleW, heights, nameW};
}

// ELK's layout of a layer's behaviours and inhibitions, at (0, 0): the one in `laid` (key ->
// layout) when the layer has the same boxes and edges as one laid out before, else a new one.
// ELK takes tens of milliseconds for a layer of 50 behaviours: an edit lays out the layers it
// changed, not all. Returns {key, graph, layout: a promise of it, done: it, once it is known}.
function layoutLayer(layer, size, laid) {
  const graph = {
    id: 'layer',
    layoutOptions: LAYOUT,
    children: layer.behaviours.map((behaviour) =>
      ({id: `b:${behaviour.name}`, width: size.boxW, height: size.heights.get(behaviour.name)})),
    edges: layer.inhibitions.map((inhibition, index) =>
      ({id: `i:${index}`, sources: [`b:${inhibition.inhibitor}`], targets: [`b:${inhibition.inhibited}`]})),
  };
  const key = JSON.stringify(graph);
  const known = laid.get(key);
  if (known) return known;
  const stored = storedLayout(key);
  if (stored) return {key, graph, layout: Promise.resolve(stored), done: stored};
  const entry = {key, graph, layout: elkLayout(graph), done: null};
  entry.layout.then((result) => {
    entry.done = result;
    storeLayout(key, result);
  }, () => {});
  return entry;
}

// Layouts kept in the browser's storage by the graph they are of, so that a page opened again on
// the same graph (the studio's and the live view's address is the same each time, unless port 0
// is asked for) draws it at once: the first layouts in a page wait for ELK's worker to load and
// are its slowest (keepWarm()). ELK is deterministic: the same graph, sizes and options, which the
// key holds, give the same layout. Each layout is an item of its own, found by a hash of its key
// and checked against the key; the STORED_LAYOUTS most recently stored are kept.
const STORED_LAYOUTS = 64;
const STORE_PREFIX = `arbiter.layout.${elkVersion}.`;
const STORE_INDEX = 'arbiter.layouts';
function keyHash(key) {  // cyrb53: 53 bits, as a base-36 string
  let h1 = 0xdeadbeef;
  let h2 = 0x41c6ce57;
  for (let i = 0; i < key.length; ++i) {
    const c = key.charCodeAt(i);
    h1 = Math.imul(h1 ^ c, 2654435761);
    h2 = Math.imul(h2 ^ c, 1597334677);
  }
  h1 = Math.imul(h1 ^ (h1 >>> 16), 2246822507) ^ Math.imul(h2 ^ (h2 >>> 13), 3266489909);
  h2 = Math.imul(h2 ^ (h2 >>> 16), 2246822507) ^ Math.imul(h1 ^ (h1 >>> 13), 3266489909);
  return (4294967296 * (2097151 & h2) + (h1 >>> 0)).toString(36);
}
function storedLayout(key) {
  try {
    const item = localStorage.getItem(STORE_PREFIX + keyHash(key));
    if (!item) return null;
    const {graph, layout} = JSON.parse(item);
    return graph === key ? layout : null;
  } catch {
    return null;  // no storage (a private window, storage turned off): ELK lays it out
  }
}
function storeLayout(key, layout) {
  try {
    const name = STORE_PREFIX + keyHash(key);
    const index = JSON.parse(localStorage.getItem(STORE_INDEX) || '[]').filter((other) => other !== name);
    index.push(name);
    while (index.length > STORED_LAYOUTS) localStorage.removeItem(index.shift());
    localStorage.setItem(name, JSON.stringify({graph: key, layout}));
    localStorage.setItem(STORE_INDEX, JSON.stringify(index));
  } catch {
    // Full or turned off: the layout is not kept, which costs only time.
  }
}

// ELK's code is loaded and compiled as it first runs, which makes a page's first layout cost more
// than twice a later one: a view starts each worker on a small graph while it waits for its own.
// Its inhibitions cross and skip rows, so that the code of those cases is compiled too.
const WARM_UP = {
  id: 'warm-up', layoutOptions: LAYOUT,
  children: Array.from({length: 12}, (_, i) => ({id: `b${i}`, width: 100 + 10 * (i % 3), height: 40 + 12 * (i % 2)})),
  edges: [[0, 1], [0, 3], [2, 5], [1, 4], [3, 6], [4, 7], [6, 8], [5, 9], [7, 10], [2, 11], [8, 11]]
      .map(([a, b], i) => ({id: `e${i}`, sources: [`b${a}`], targets: [`b${b}`]})),
};
let warmed = null;
function warmUp() {
  if (warmed) return;
  const started = performance.now();
  warmed = Promise.all(workers().map(({elk}) => elk.layout(WARM_UP)))
      .then(() => performance.measure('arbiter:layout:warm-up', {start: started}), () => {});
}

// V8 optimises ELK's code only after it has run many times: in a worker, a layer of 50
// behaviours took 280 ms to lay out the first time, 90 ms the fourth and 30-50 ms from about the
// tenth on. So after the first drawing, each worker goes on laying out the drawing's largest layers
// while it has nothing else to do, until it has done WARM_LAYOUTS layouts: the layouts of the
// edits that follow then cost their warmed price. A layout asked for meanwhile goes to the other
// worker if it is idle, else waits for the one in progress.
const WARM_LAYOUTS = 12;
let keptWarm = false;
function keepWarm(keys) {
  if (keptWarm || keys.length === 0) return;
  keptWarm = true;
  const graphs = keys.map((key) => JSON.parse(key)).sort((a, b) => b.children.length - a.children.length).slice(0, 2);
  const started = performance.now();
  let working = 0;
  for (const worker of workers()) {
    ++working;
    const next = () => {
      if (worker.layouts >= WARM_LAYOUTS) {
        if (--working === 0) performance.measure('arbiter:layout:kept-warm', {start: started});
        return;
      }
      if (worker.pending > 0) {
        setTimeout(next, 50);
        return;
      }
      elkLayout(graphs[worker.layouts % graphs.length], worker).then(() => setTimeout(next, 0), () => {});
    };
    next();
  }
}

/** The layers (by name) and behaviours ('layer/name') of the program `after` that `before` has not. */
function addedTo(before, after) {
  const layers = new Set(before.layers.map((layer) => layer.name));
  const behaviours = new Set(before.layers.flatMap((layer) => layer.behaviours.map((b) => `${layer.name}/${b.name}`)));
  return {
    layers: new Set(after.layers.map((layer) => layer.name).filter((name) => !layers.has(name))),
    behaviours: new Set(after.layers.flatMap((layer) => layer.behaviours.map((b) => `${layer.name}/${b.name}`))
        .filter((key) => !behaviours.has(key))),
  };
}

// The points of an ELK edge, offset by (dx, dy).
function edgePoints(edge, dx, dy) {
  const points = [];
  for (const section of edge.sections || []) {
    for (const p of [section.startPoint, ...(section.bendPoints || []), section.endPoint]) {
      points.push({x: p.x + dx, y: p.y + dy});
    }
  }
  return points;
}

export class GraphView {
  /**
   * @param {SVGSVGElement} svg
   * @param {(key: string | null) => void} onHover called with 'layer/name' or null
   * @param {Folds} [folds] the layers folded away (shared with the timelines)
   */
  constructor(svg, onHover, folds = new Folds()) {
    this.svg = svg;
    this.onHover = onHover;
    /** Called with 'layer/name' when a behaviour is clicked. */
    this.onClick = (key) => {};
    /** Called after every drawing of the SVG (a new graph, a layer folded or unfolded). */
    this.onBuilt = () => {};
    /** The zoom and pan (graph_nav.js), when the view has them; else the page scrolls. */
    this.view = null;
    this.folds = folds;
    folds.subscribe(() => this.rebuild());
    this.drawn = null;  // {graph, sizes, layouts}: what the SVG shows, to draw again when a layer folds
    this.laid = new Map();  // the layers' layouts of the last drawing, by their ELK graphs (layoutLayer())
    this.textWidths = new Map();  // the texts measured in earlier drawings (textMeasure())
    warmUp();
    this.words = '';    // marked (mark())
    this.highlighted = null;
    /** Called with the actuator's name when its row is clicked. */
    this.onPort = (name) => {};
    this.behaviours = new Map();  // 'layer/name' -> {group, rect, level, mark, name, inhibitors, ...}
    this.ports = new Map();       // actuator name -> {group, value, title, about}
    this.drawing = 0;
    this.shownAt = -Infinity;  // when a large graph was last redrawn
    this.trailing = null;      // its next redraw
  }

  /**
   * Lays `graph` out and draws it in place of what the SVG showed. False when a later call
   * replaced it before its layout was done (a reload that followed closely).
   */
  async draw(graph) {
    const drawing = ++this.drawing;
    // The layout's time, for the benchmark (web/bench/studio_frames.mjs): measured up to the SVG
    // built, not painted.
    const started = performance.now();
    const measure = textMeasure(this.svg, this.textWidths);
    // Sized twice: first to gather the texts to measure, which are then measured together.
    for (const layer of graph.layers) sizeLayer(layer, measure.prepare);
    const sizes = graph.layers.map((layer) => sizeLayer(layer, measure));
    measure.done();
    const measured = performance.now();
    const laid = new Map();
    const entries = graph.layers.map((layer, index) => {
      const entry = layoutLayer(layer, sizes[index], this.laid);
      laid.set(entry.key, entry);
      return entry;
    });
    // A page's first drawing does not wait for ELK's first layouts, its slowest (quick_layout.js):
    // the graph is shown at once, laid out as ELK would lay out most layers, and drawn again with
    // ELK's layouts when they come. A later drawing keeps the one shown until its layouts come.
    const provisional = !this.drawn && entries.some((entry) => !entry.done);
    if (provisional) {
      this.drawn = {graph, sizes, layouts: entries.map((entry) => entry.done ?? quickLayout(entry.graph))};
      this.svg.dataset.provisional = 'true';
      this.rebuild({layers: new Set(), behaviours: new Set()});
      performance.measure('arbiter:layout:provisional', {start: started});
    }
    // Layouts under way are found by the drawings that follow, not asked of ELK again.
    for (const [key, entry] of laid) this.laid.set(key, entry);
    const layouts = await Promise.all(entries.map((entry) => entry.layout));
    if (drawing !== this.drawing) return false;
    this.laid = laid;
    const laidOut = performance.now();
    const before = this.drawn?.graph;
    this.drawn = {graph, sizes, layouts};
    // ELK's drawing in place of a provisional one (this drawing's, or that of one it replaced) is
    // fitted again, unless the view was moved.
    if (this.svg.dataset.provisional) this.view?.refit();
    delete this.svg.dataset.provisional;
    this.rebuild(before ? addedTo(before, graph) : {layers: new Set(), behaviours: new Set()});
    performance.measure('arbiter:layout', {start: started});
    performance.measure('arbiter:layout:text', {start: started, end: measured});
    performance.measure('arbiter:layout:elk', {start: measured, end: laidOut});
    performance.measure('arbiter:layout:svg', {start: laidOut});
    keepWarm([...laid.keys()]);
    return true;
  }

  /**
   * Draws what draw() laid out again, as the folds are now; `added` (the layers and behaviours new
   * in a new drawing) when draw() calls it.
   */
  rebuild(added = null) {
    if (!this.drawn) return;
    const {graph, sizes, layouts} = this.drawn;
    this.build(graph, sizes, layouts);
    this.watchScreen();
    this.mark(this.words);
    this.highlight(this.highlighted);
    if (this.record) this.show(this.record);
    this.view?.contentChanged(!!added, added && this.boundsOf(added));
    this.onBuilt();
  }

  /** The rectangle (SVG user units) round the columns and boxes drawn of `added`; null: none drawn. */
  boundsOf(added) {
    const rects = [];
    for (const column of this.svg.querySelectorAll('g.layer')) {
      if (added.layers.has(column.dataset.layer)) rects.push(column.querySelector('rect.layer-box'));
    }
    for (const key of added.behaviours) {
      const item = this.behaviours.get(key);
      if (item) rects.push(item.rect);
    }
    if (!rects.length) return null;
    const edges = rects.map((r) => {
      const [x, y, width, height] = ['x', 'y', 'width', 'height'].map((name) => Number(r.getAttribute(name)));
      return [x, y, x + width, y + height];
    });
    const left = Math.min(...edges.map((e) => e[0]));
    const top = Math.min(...edges.map((e) => e[1]));
    return {x: left, y: top, width: Math.max(...edges.map((e) => e[2])) - left,
            height: Math.max(...edges.map((e) => e[3])) - top};
  }

  build(graph, sizes, layouts) {
    const svg = this.svg;
    this.behaviours.clear();
    this.ports.clear();
    svg.replaceChildren();
    const measure = textMeasure(svg, this.textWidths);
    const edges = el('g', {class: 'edges'});
    const flows = el('g', {class: 'flows'});
    const sensorAt = new Map();    // 'layer/actuator' -> {x, y, ...}
    const actuatorAt = new Map();  // actuator -> {x, y, layerIndex}
    let height = 0;
    let x = 10;
    graph.layers.forEach((layer, index) => {
      const size = sizes[index];
      const layout = layouts[index];
      const foldable = layer.behaviours.length > 0;
      const folded = foldable && this.folds.has(layer.name);
      const foldedNote = `${layer.behaviours.length} behaviour${layer.behaviours.length === 1 ? '' : 's'} folded away`;
      const inner = Math.max(size.sensorW, folded ? measure(foldedNote, null, 'section-label') : layout.width || 0,
                             size.actuatorW + 16, size.titleW + (foldable ? FOLD_MARK : 0));
      const width = Math.max(folded ? 0 : COLUMN - 20, 12 + inner + 12);
      const column = el('g', {class: `layer${folded ? ' folded' : ''}`, 'data-layer': layer.name}, svg);
      const box = el('rect', {class: 'layer-box', x, y: 4, width, rx: 8}, column);
      if (foldable) {
        // The title folds the layer away and back, by click or by key (Enter, Space).
        const head = el('g', {class: 'layer-head', tabindex: 0, role: 'button', 'aria-expanded': String(!folded),
                              'aria-label': `${folded ? 'unfold' : 'fold'} layer ${layer.name}`}, column);
        text('text', {class: 'fold-mark', x: x + 12, y: 24}, folded ? '▸' : '▾', head);
        text('text', {class: 'layer-title', x: x + 12 + FOLD_MARK, y: 24}, layer.name, head);
        const toggle = () => this.folds.set(layer.name);
        head.addEventListener('click', toggle);
        head.addEventListener('keydown', (event) => {
          if (event.key !== 'Enter' && event.key !== ' ') return;
          event.preventDefault();
          toggle();
          // The new drawing's head keeps the focus, for the next key.
          this.svg.querySelector(`g.layer[data-layer="${CSS.escape(layer.name)}"] .layer-head`)?.focus({preventScroll: true});
        });
      } else {
        text('text', {class: 'layer-title', x: x + 12, y: 24}, layer.name, column);
      }
      if (layer.interface) text('text', {class: 'layer-class', x: x + 12, y: 40}, `interface ${layer.interface}`, column);
      else if (layer.normalise) text('text', {class: 'layer-class', x: x + 12, y: 40}, 'normalised', column);
      let y = 50;
      if (layer.sensors.length) {
        text('text', {class: 'section-label', x: x + 12, y: y + 8}, 'sensors', column);
        y += 14;
        for (const sensor of layer.sensors) {
          const g = el('g', {class: 'port sensor', 'data-sensor': `${layer.name}/${sensor.name}`}, column);
          el('rect', {x: x + 12, y, width: size.sensorW, height: PORT_H - 4}, g);
          text('text', {x: x + 20, y: y + 13}, sensor.name, g);
          sensorAt.set(`${layer.name}/${sensor.name}`, {x: x + 12, y: y + (PORT_H - 4) / 2, lastStep: sensor.last_step,
                                                        from: sensor.layer, layerIndex: index});
          y += PORT_H;
        }
        y += 6;
      }
      if (folded) {
        text('text', {class: 'section-label folded-note', x: x + 12, y: y + 8}, foldedNote, column);
        y += 20;
      } else if (layer.behaviours.length) {
        y += 4;
        this.buildBehaviours(layer, size, layout, x + 12, y, column, edges);
        y += layout.height + 8;
      }
      if (layer.actuators.length) {
        text('text', {class: 'section-label', x: x + 12, y: y + 8}, 'actuators', column);
        y += 14;
        for (const actuator of layer.actuators) {
          const g = el('g', {class: 'port actuator', 'data-actuator': actuator.name}, column);
          el('rect', {x: x + 12, y, width: size.actuatorW, height: PORT_H - 4}, g);
          text('text', {x: x + 20, y: y + 13}, actuator.name, g);
          const value = text('text', {class: 'value', x: x + 20 + size.nameW.get(actuator.name) + 10, y: y + 13}, '', g);
          const about = `${actuator.name}: ${actuator.type}${actuator.aggregate ? ', aggregate' : ''}; written by ${actuator.writers.join(', ') || 'the interface'}`;
          const title = el('title', {}, g);
          title.textContent = about;
          actuatorAt.set(actuator.name, {x: x + 12 + size.actuatorW, y: y + (PORT_H - 4) / 2, right: x + width,
                                         layerIndex: index});
          this.ports.set(actuator.name, {group: g, value, title, about});
          // Explained as `arbiter explain` names actuators.
          g.addEventListener('mouseenter', () => this.onHover(`actuators/${actuator.name}`));
          g.addEventListener('mouseleave', () => this.onHover(null));
          g.addEventListener('click', () => this.onPort(actuator.name));
          y += PORT_H;
        }
      }
      box.setAttribute('height', y + 8);
      height = Math.max(height, y + 16);
      x += width + 20;
    });
    measure.done();
    // A flow to an earlier (or the same) layer runs back under the columns, each in a lane of its
    // own, so that it does not cross the graph.
    let lanes = 0;
    for (const [key, sensor] of sensorAt) {
      const source = actuatorAt.get(key.split('/')[1]);
      if (!source) continue;
      let d;
      if (source.layerIndex < sensor.layerIndex) {
        // Straight out of its column (under the behaviours ELK may have put right of the
        // actuators), then a curve to the sensor.
        const bend = Math.max(40, Math.abs(sensor.x - source.right) / 3);
        d = `M${source.x},${source.y} H${source.right} C${source.right + bend},${source.y} ` +
            `${sensor.x - bend},${sensor.y} ${sensor.x},${sensor.y}`;
      } else {
        const lane = lanes++;
        const below = height + 4 + 7 * lane;
        const out = source.x + 8 + 3 * lane;
        const into = Math.max(2, sensor.x - 6 - 3 * lane);
        d = `M${source.x},${source.y} H${out} V${below} H${into} V${sensor.y} H${sensor.x}`;
      }
      const path = el('path', {class: `flow${sensor.lastStep ? ' last-step' : ''}`, d, 'data-flow': key}, flows);
      el('title', {}, path).textContent = `${sensor.from} → ${key}${sensor.lastStep ? ' (last step\'s value)' : ''}`;
    }
    height += 7 * lanes + 8;
    svg.appendChild(edges);
    svg.appendChild(flows);
    svg.setAttribute('width', x);
    svg.setAttribute('height', height);
  }

  // A layer's behaviours where ELK put them, offset by (left, top), and its inhibitions as ELK
  // routed them, drawn as the Graphviz dump draws them: a double line for a chaining inhibition,
  // a single one for a non-chaining one, dashed for one implied by chaining; a bar across the
  // inhibited end, as in the paper's figures.
  buildBehaviours(layer, size, layout, left, top, column, edges) {
    const byId = new Map((layout.children || []).map((node) => [node.id, node]));
    for (const behaviour of layer.behaviours) {
      const key = `${layer.name}/${behaviour.name}`;
      const node = byId.get(`b:${behaviour.name}`);
      const bx = left + node.x;
      const by = top + node.y;
      const g = el('g', {class: 'behaviour', 'data-name': key, 'data-class': behaviour.class}, column);
      const rect = el('rect', {x: bx, y: by, width: node.width, height: node.height, fill: colour(0)}, g);
      const mark = text('text', {class: 'mark', x: bx + 8, y: by + 17}, '', g);
      const name = text('text', {class: 'name', x: bx + 22, y: by + 17}, behaviour.name, g);
      const level = text('text', {class: 'level', x: bx + 22, y: by + 32}, 'activation 0', g);
      const lines = (node.height - BOX_H) / 12;
      const inhibitors = lines ? text('text', {class: 'level inhibitors', x: bx + 22, y: by + 45}, '', g) : null;
      el('title', {}, g).textContent = `${key} (${behaviour.class}), execution order ${behaviour.order}`;
      g.addEventListener('mouseenter', () => this.onHover(key));
      g.addEventListener('mouseleave', () => this.onHover(null));
      g.addEventListener('click', () => this.onClick(key));
      this.behaviours.set(key, {key, group: g, rect, level, mark, name, inhibitors, order: size.rowIndex,
                                wrap: (list) => size.wrap.lines(list, size.room), indent: size.wrap.indent});
    }
    const routed = new Map((layout.edges || []).map((edge) => [edge.id, edge]));
    layer.inhibitions.forEach((inhibition, index) => {
      const points = edgePoints(routed.get(`i:${index}`) || {}, left, top);
      if (points.length < 2) return;
      // The line stops at the bar, BAR before the box.
      const end = points[points.length - 1];
      const before = points[points.length - 2];
      const length = Math.hypot(end.x - before.x, end.y - before.y) || 1;
      const ux = (end.x - before.x) / length;
      const uy = (end.y - before.y) / length;
      end.x -= ux * BAR;
      end.y -= uy * BAR;
      const d = points.map((p, i) => `${i ? 'L' : 'M'}${p.x},${p.y}`).join(' ');
      const kind = inhibition.implicit ? 'implicit' : inhibition.chaining ? 'chaining' : 'non-chaining';
      const g = el('g', {class: `edge ${kind}`, 'data-kind': kind, 'data-layer': layer.name,
                         'data-from': inhibition.inhibitor, 'data-to': inhibition.inhibited}, edges);
      el('title', {}, g).textContent = inhibition.implicit
          ? `implied by chaining ${inhibition.via.join(' => ')}`
          : `${inhibition.inhibitor} ${inhibition.chaining ? '=>' : '->'} ${inhibition.inhibited}`;
      if (kind === 'chaining') {
        el('path', {class: 'edge-outer', d}, g);
        el('path', {class: 'edge-inner', d}, g);
      } else {
        el('path', {class: `edge-line ${kind}`, d}, g);
      }
      el('line', {class: 'edge-line', x1: end.x - uy * BAR, y1: end.y + ux * BAR, x2: end.x + uy * BAR, y2: end.y - ux * BAR}, g);
    });
  }

  /**
   * The behaviours whose 'layer/name' holds `words` (lower case), folded away or not, in
   * execution order; none when `words` is empty.
   */
  matches(words) {
    if (!words || !this.drawn) return [];
    const found = [];
    for (const layer of this.drawn.graph.layers) {
      for (const behaviour of layer.behaviours) {
        const key = `${layer.name}/${behaviour.name}`;
        if (key.toLowerCase().includes(words)) found.push(key);
      }
    }
    return found;
  }

  /**
   * Marks the behaviours whose 'layer/name' holds `words` (lower case) and dims the others (none
   * when empty); a folded layer that holds some says how many.
   * @returns {string | null} the first match, in execution order
   */
  mark(words) {
    this.words = words;
    const found = this.matches(words);
    const matched = new Set(found);
    for (const [key, item] of this.behaviours) {
      item.group.classList.toggle('matched', matched.has(key));
      item.group.classList.toggle('unmatched', !!words && !matched.has(key));
    }
    for (const column of this.svg.querySelectorAll('g.layer.folded')) {
      const count = found.filter((key) => key.startsWith(`${column.dataset.layer}/`)).length;
      column.classList.toggle('has-matches', count > 0);
      if (count) column.dataset.matches = String(count);
      else delete column.dataset.matches;
    }
    return found[0] ?? null;
  }

  /** Brings `key`'s box into view, unfolding its layer if it is folded away. */
  reveal(key) {
    const layer = key.slice(0, key.indexOf('/'));
    if (this.folds.has(layer)) this.folds.set(layer, false);
    const item = this.behaviours.get(key);
    if (!item) return;
    if (this.view) this.view.show(item.rect.getBBox());
    else item.group.scrollIntoView({block: 'center', inline: 'center'});
  }

  /** Marks the hovered behaviour ('layer/name') or actuator ('actuators/name'), or none (null). */
  highlight(key) {
    this.highlighted = key;
    for (const [name, item] of this.behaviours) item.group.classList.toggle('hovered', name === key);
    for (const [name, port] of this.ports) port.group.classList.toggle('hovered', `actuators/${name}` === key);
  }

  /**
   * Large graphs are redrawn only where they are on the screen: a behaviour scrolled (or panned)
   * into view is brought up to the step shown then. (Small ones are redrawn whole: nothing to
   * gain.) Where each box lies in the SVG is measured once a drawing; what is on the screen is
   * then computed from two rectangles, the SVG's and what clips it. An IntersectionObserver of
   * every box did the same, but cost the browser some milliseconds every frame at 1000 boxes.
   */
  watchScreen() {
    this.large = this.behaviours.size >= LARGE;
    this.measured = false;
    if (!this.large || this.screenWatched) return;
    this.screenWatched = true;
    // Capturing: the panel's own horizontal scroll as well as the page's.
    document.addEventListener('scroll', () => this.screenChanged(), {capture: true, passive: true});
    window.addEventListener('resize', () => this.screenChanged());
  }

  /** Measures where each box lies, in the SVG's units; false while the SVG is not laid out. */
  measureBoxes() {
    const svg = this.svg.getBoundingClientRect();
    const width = Number(this.svg.getAttribute('width'));
    if (!svg.width || !width) return false;
    const scale = svg.width / width;
    for (const item of this.behaviours.values()) {
      const box = item.group.getBoundingClientRect();
      // Folded away: never on the screen.
      item.box = box.width ? [(box.left - svg.left) / scale, (box.top - svg.top) / scale,
                              (box.right - svg.left) / scale, (box.bottom - svg.top) / scale] : null;
    }
    this.measured = true;
    return true;
  }

  /** Whether a box is on the screen now, as a function of the box; null: all are. */
  onScreen() {
    if (!this.large) return null;
    if (!this.measured && !this.measureBoxes()) return () => false;
    const svg = this.svg.getBoundingClientRect();
    const clip = this.svg.parentElement.getBoundingClientRect();
    const scale = svg.width / Number(this.svg.getAttribute('width'));
    // The screen's part of what clips the SVG, in the SVG's units.
    const left = (Math.max(0, clip.left) - svg.left) / scale;
    const top = (Math.max(0, clip.top) - svg.top) / scale;
    const right = (Math.min(window.innerWidth, clip.right) - svg.left) / scale;
    const bottom = (Math.min(window.innerHeight, clip.bottom) - svg.top) / scale;
    return (item) => !!item.box && item.box[2] > left && item.box[0] < right && item.box[3] > top && item.box[1] < bottom;
  }

  /** The page scrolled or the graph moved: the boxes come into view at the step shown. */
  screenChanged() {
    if (!this.large || this.revealing) return;
    this.revealing = requestAnimationFrame(() => {
      this.revealing = 0;
      if (!this.record || !this.large) return;
      const visible = this.onScreen();
      for (const [key, item] of this.behaviours) {
        if (visible(item)) this.showBehaviour(key, item, this.record);
      }
    });
  }

  /**
   * Shows `record` (one step): levels, activity, active inhibitors and actuator values. A large
   * graph is redrawn at most every LARGE_PERIOD ms (the last record asked for is drawn then):
   * painting it costs more than a frame, and the timelines show every step anyway.
   */
  show(record) {
    this.record = record;
    if (this.large) {
      const wait = this.shownAt + LARGE_PERIOD - performance.now();
      if (wait > 0) {
        this.trailing ??= setTimeout(() => {
          this.trailing = null;
          this.show(this.record);
        }, wait);
        return;
      }
      this.shownAt = performance.now();
    }
    const visible = this.onScreen();
    for (const [key, item] of this.behaviours) {
      if (visible && !visible(item)) continue;
      this.showBehaviour(key, item, record);
    }
    for (const [name, port] of this.ports) showActuator(port, record, name);
  }

  /** Shows one behaviour at `record`, if it changed since it was last shown. */
  showBehaviour(key, item, record) {
    const levels = levelsOf(record, key) || {activation: 0, requested: 0, active: false, inhibited_by: []};
    const activation = Number(levels.activation) || 0;
    // Most behaviours keep their levels from one step to the next: a large graph streamed live
    // is redrawn only where it changed.
    const shown = `${activation} ${levels.active} ${levels.requested} ${levels.inhibited_by}`;
    if (item.shown === shown) return;
    item.shown = shown;
    item.rect.setAttribute('fill', colour(activation));
    item.group.setAttribute('data-activation', activation);
    item.group.setAttribute('data-active', levels.active ? 'true' : 'false');
    item.group.classList.toggle('active', !!levels.active);
    item.group.classList.toggle('inhibited', !levels.active && levels.requested > 0);
    item.mark.textContent = levels.active ? '●' : '';
    const ink = activation > 0.55 ? '#fff' : '#1d2733';
    item.name.setAttribute('fill', ink);
    item.level.setAttribute('fill', ink);
    item.level.textContent = `activation ${activation.toFixed(2)} of ${Number(levels.requested).toFixed(2)}`;
    if (item.inhibitors) {
      item.inhibitors.setAttribute('fill', ink);
      item.inhibitors.replaceChildren();
      const active = (levels.inhibited_by || []).filter((name) => item.order.has(name))
          .sort((a, b) => item.order.get(a) - item.order.get(b));
      item.wrap(active).forEach((line, index, lines) => {
        const x = Number(item.inhibitors.getAttribute('x')) + (index ? item.indent : 0);
        const words = (index ? '' : '⊣ ') + line.join(', ') + (index < lines.length - 1 ? ',' : '');
        el('tspan', {x, dy: index ? 12 : 0}, item.inhibitors).textContent = words;
      });
    }
  }
}

// An actuator nobody wrote in a step keeps its last value (docs/semantics.md, "Persistence"):
// such a value is drawn dimmed, with the step since which it is held.
function showActuator(port, record, name) {
  const value = record.actuators ? record.actuators[name] : undefined;
  const held = value && !value.written;
  port.value.replaceChildren(value ? formatValue(value.value) : '');
  port.group.classList.toggle('written', !!(value && value.written));
  port.group.classList.toggle('held', !!held);
  let about = port.about;
  if (value && value.written) {
    port.group.removeAttribute('data-held-since');
    about += `\nwritten in step ${record.step}`;
  } else if (held) {
    const since = record.held && record.held[name];
    let note;
    if (since && since.writtenAt !== null) {
      note = `held since step ${since.writtenAt + 1}`;
      about += `\nheld since step ${since.writtenAt + 1}: last written in step ${since.writtenAt}`;
      port.group.setAttribute('data-held-since', since.writtenAt + 1);
    } else if (since && since.knownFrom <= 1) {
      note = 'default, never written';
      about += '\nits default: not written since the run started';
      port.group.setAttribute('data-held-since', 1);
    } else {
      const from = since ? since.knownFrom : record.step;
      note = `held since before step ${from}`;
      about += `\nheld: not written in steps ${from} to ${record.step} (the steps this page has)`;
      port.group.setAttribute('data-held-since', `<${from}`);
    }
    el('tspan', {class: 'held-note', dx: 8}, port.value).textContent = note;
  }
  port.title.textContent = about;
}
