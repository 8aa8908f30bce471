// The web view of an arbiter run: live (a stream of step records from `arbiter run --serve`)
// or recorded (a trace from `arbiter view`). Both feed the same drawing: the graph comes from the
// JSON dump, each step from a trace record (docs/semantics.md, "The trace").
'use strict';

const SVG = 'http://www.w3.org/2000/svg';
const HISTORY = 300;  // steps a timeline shows
const COLUMN = 270;   // the narrowest width of a layer's column
const BOX_W = 168;    // the narrowest behaviour box
const BOX_H = 40;
const PORT_H = 22;
const ARC_GAP = 12;   // how far right of the boxes an arc between neighbours reaches
const ARC_STEP = 14;  // and how much further for each row more it spans
// Values as wide as most of each type's, to size actuator rows by.
const TYPICAL_VALUE = {bool: 'false', int: '-12345', double: '-12.345', vec2: '[-1.234, -1.234]',
                       vec3: '[-1.234, -1.234, -1.234]', string: '"a short text"', other: '{"a": 1, "b": 2}'};
const INHIBITORS_ROOM = 260;  // a list of inhibitors wider than this is wrapped

const view = {
  mode: '',
  graph: null,
  graphText: '',
  records: [],      // live: the last steps received; trace: every step
  current: null,    // the record shown
  behaviours: new Map(),  // 'layer/name' -> {group, rect, level, mark}
  ports: new Map(),       // actuator name -> {group, value}
  timelines: new Map(),   // 'layer/name' -> canvas
  reported: [],     // what behaviour code reported (records' "reported"), oldest first
  writes: {last: null, knownFrom: 1, at: new Map()},  // for trackWrites()
  hovered: null,
  drawPending: false,  // live: a frame will draw the newest step
  explainPending: false,
  explainShown: '',
};

function el(tag, attributes = {}, parent = null, ns = SVG) {
  const node = ns ? document.createElementNS(ns, tag) : document.createElement(tag);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  if (parent) parent.appendChild(node);
  return node;
}

function text(tag, attributes, content, parent) {
  const node = el(tag, attributes, parent);
  node.textContent = content;
  return node;
}

function colour(level) {
  const a = Math.max(0, Math.min(1, Number(level) || 0));
  return `hsl(210, ${30 + 55 * a}%, ${95 - 53 * a}%)`;
}

// Widths of text as the page draws it: a hidden probe inside `svg` carries the classes the CSS
// sizes text by (`.behaviour .name`, `.port text`, ...).
function textMeasure(svg) {
  const probe = el('g', {visibility: 'hidden'}, svg);
  const measure = (content, groupClass, textClass) => {
    const group = el('g', groupClass ? {class: groupClass} : {}, probe);
    const node = text('text', textClass ? {class: textClass, x: 0, y: 0} : {x: 0, y: 0}, content, group);
    const width = node.getComputedTextLength();
    group.remove();
    return width;
  };
  measure.done = () => probe.remove();
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

function formatValue(value) {
  if (Array.isArray(value)) return '[' + value.map(formatValue).join(', ') + ']';
  if (typeof value === 'number') return Number.isInteger(value) ? String(value) : value.toFixed(3);
  return JSON.stringify(value);
}

// The graph: a column per layer (in execution order), its sensors on top, its behaviours in
// execution (topological) order, its actuators below; inhibitions as arcs on the right of the
// behaviours, actuator -> sensor flows between columns. Boxes and columns are sized to the text
// they will hold (measured in the page's font), so that no label runs under an arc or into the
// next column.
function buildGraph(graph) {
  view.graph = graph;
  view.behaviours.clear();
  view.ports.clear();
  document.getElementById('title').textContent = graph.name;
  document.title = `arbiter: ${graph.name}`;
  const svg = document.getElementById('graph');
  svg.replaceChildren();
  const measure = textMeasure(svg);
  const edges = el('g', {class: 'edges'});
  const flows = el('g', {class: 'flows'});
  const sensorAt = new Map();    // 'layer/actuator' -> {x, y}
  const actuatorAt = new Map();  // actuator -> {x, y, layerIndex}
  let height = 0;
  let x = 10;
  graph.layers.forEach((layer, index) => {
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
    // The active inhibitors are listed under the levels, wrapped to the box: it is as wide as
    // the longest list needs, up to INHIBITORS_ROOM, and has as many lines as the longest list
    // takes at that width.
    const wrap = inhibitorWrap(layer, measure);
    let room = boxW - 44;
    for (const list of inhibitorsOf.values()) {
      if (list.length) room = Math.max(room, Math.min(INHIBITORS_ROOM, wrap.width(list)), wrap.widest(list));
    }
    boxW = room + 44;
    for (const sensor of layer.sensors) boxW = Math.max(boxW, 8 + measure(sensor.name, 'port') + 10);
    // Arcs nest by span (in rows): the widest reaches this far right of the boxes.
    let widestSpan = 0;
    for (const inhibition of layer.inhibitions) {
      const from = rowIndex.get(inhibition.inhibitor);
      const to = rowIndex.get(inhibition.inhibited);
      if (from !== undefined && to !== undefined) widestSpan = Math.max(widestSpan, Math.abs(to - from));
    }
    const arcs = layer.inhibitions.length ? ARC_GAP + ARC_STEP * widestSpan + 6 : 0;
    // An actuator's row holds its name, its value (as wide as a typical one of its type) and,
    // when the value is held, since when.
    const heldW = measure('held since step 12345', 'port', 'held-note');
    const actuatorW = Math.max(0, ...layer.actuators.map((actuator) =>
        Math.max(COLUMN - 44, 8 + measure(actuator.name, 'port') + 10 +
                 measure(TYPICAL_VALUE[actuator.type] || TYPICAL_VALUE.other, 'port', 'value') + 8 + heldW + 8)));
    const titleW = Math.max(measure(layer.name, null, 'layer-title'),
                            measure(layer.interface ? `interface ${layer.interface}` : 'normalised', null, 'layer-class'));
    // Back flows leave an actuator to its right, a few pixels per lane.
    const inner = Math.max(boxW + arcs, actuatorW + 16, titleW);
    const width = Math.max(COLUMN - 20, 12 + inner + 12);
    const column = el('g', {class: 'layer', 'data-layer': layer.name}, svg);
    const box = el('rect', {class: 'layer-box', x, y: 4, width, rx: 8}, column);
    text('text', {class: 'layer-title', x: x + 12, y: 24}, layer.name, column);
    if (layer.interface) text('text', {class: 'layer-class', x: x + 12, y: 40}, `interface ${layer.interface}`, column);
    else if (layer.normalise) text('text', {class: 'layer-class', x: x + 12, y: 40}, 'normalised', column);
    let y = 50;
    if (layer.sensors.length) {
      text('text', {class: 'section-label', x: x + 12, y: y + 8}, 'sensors', column);
      y += 14;
      for (const sensor of layer.sensors) {
        const g = el('g', {class: 'port sensor', 'data-sensor': `${layer.name}/${sensor.name}`}, column);
        el('rect', {x: x + 12, y, width: boxW, height: PORT_H - 4}, g);
        text('text', {x: x + 20, y: y + 13}, sensor.name, g);
        sensorAt.set(`${layer.name}/${sensor.name}`, {x: x + 12, y: y + (PORT_H - 4) / 2, lastStep: sensor.last_step, from: sensor.layer, layerIndex: index});
        y += PORT_H;
      }
      y += 6;
    }
    const middleOf = new Map();
    for (const behaviour of layer.behaviours) {
      const key = `${layer.name}/${behaviour.name}`;
      // A box that can be inhibited has lines for its active inhibitors.
      const lines = wrap.lines(inhibitorsOf.get(behaviour.name), room).length;
      const boxH = BOX_H + 12 * lines;
      middleOf.set(behaviour.name, y + boxH / 2);
      const g = el('g', {class: 'behaviour', 'data-name': key, 'data-class': behaviour.class}, column);
      const rect = el('rect', {x: x + 12, y, width: boxW, height: boxH, fill: colour(0)}, g);
      const mark = text('text', {class: 'mark', x: x + 20, y: y + 17}, '', g);
      const name = text('text', {class: 'name', x: x + 34, y: y + 17}, behaviour.name, g);
      const level = text('text', {class: 'level', x: x + 34, y: y + 32}, 'activation 0', g);
      const inhibitors = lines ? text('text', {class: 'level inhibitors', x: x + 34, y: y + 45}, '', g) : null;
      el('title', {}, g).textContent = `${key} (${behaviour.class}), execution order ${behaviour.order}`;
      g.addEventListener('mouseenter', () => hover(key));
      g.addEventListener('mouseleave', () => hover(null));
      view.behaviours.set(key, {group: g, rect, level, mark, name, inhibitors, order: rowIndex,
                                wrap: (list) => wrap.lines(list, room), indent: wrap.indent});
      y += boxH + 8;
    }
    for (const inhibition of layer.inhibitions) {
      const from = middleOf.get(inhibition.inhibitor);
      const to = middleOf.get(inhibition.inhibited);
      if (from === undefined || to === undefined) continue;
      const span = Math.abs(rowIndex.get(inhibition.inhibited) - rowIndex.get(inhibition.inhibitor));
      const right = x + 12 + boxW;
      const reach = right + ARC_GAP + ARC_STEP * span;
      const d = `M${right},${from} C${reach},${from} ${reach},${to} ${right + 6},${to}`;
      const kind = inhibition.implicit ? 'implicit' : inhibition.chaining ? 'chaining' : 'non-chaining';
      const g = el('g', {class: `edge ${kind}`, 'data-kind': kind, 'data-layer': layer.name,
                         'data-from': inhibition.inhibitor, 'data-to': inhibition.inhibited}, edges);
      const how = inhibition.implicit ? `implied by chaining ${inhibition.via.join(' => ')}`
                                      : `${inhibition.inhibitor} ${inhibition.chaining ? '=>' : '->'} ${inhibition.inhibited}`;
      el('title', {}, g).textContent = how;
      if (kind === 'chaining') {
        el('path', {class: 'edge-outer', d}, g);
        el('path', {class: 'edge-inner', d}, g);
      } else {
        el('path', {class: `edge-line ${kind}`, d}, g);
      }
      // The inhibited end: a bar across the arc, as in the paper's figures.
      el('line', {class: 'edge-line', x1: right + 6, y1: to - 6, x2: right + 6, y2: to + 6}, g);
    }
    if (layer.actuators.length) {
      text('text', {class: 'section-label', x: x + 12, y: y + 8}, 'actuators', column);
      y += 14;
      for (const actuator of layer.actuators) {
        const g = el('g', {class: 'port actuator', 'data-actuator': actuator.name}, column);
        el('rect', {x: x + 12, y, width: actuatorW, height: PORT_H - 4}, g);
        text('text', {x: x + 20, y: y + 13}, actuator.name, g);
        const value = text('text', {class: 'value', x: x + 20 + measure(actuator.name, 'port') + 10, y: y + 13}, '', g);
        const about = `${actuator.name}: ${actuator.type}${actuator.aggregate ? ', aggregate' : ''}; written by ${actuator.writers.join(', ') || 'the interface'}`;
        const title = el('title', {}, g);
        title.textContent = about;
        actuatorAt.set(actuator.name, {x: x + 12 + actuatorW, y: y + (PORT_H - 4) / 2, layerIndex: index});
        view.ports.set(actuator.name, {group: g, value, title, about});
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
      const bend = Math.max(40, Math.abs(sensor.x - source.x) / 3);
      d = `M${source.x},${source.y} C${source.x + bend},${source.y} ${sensor.x - bend},${sensor.y} ${sensor.x},${sensor.y}`;
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
  buildControllers(graph);
  buildTimelines(graph);
}

function buildControllers(graph) {
  const box = document.getElementById('controllers');
  box.replaceChildren();
  if (!graph.state_machines.length) {
    el('p', {class: 'empty'}, box, null).textContent = 'none';
    return;
  }
  for (const machine of graph.state_machines) {
    const div = el('div', {class: 'controller', 'data-controller': machine.name}, box, null);
    const head = el('div', {class: 'head'}, div, null);
    el('span', {class: 'name'}, head, null).textContent = machine.name + (machine.standalone ? '' : ' (owned)');
    el('span', {class: 'status'}, head, null).textContent = '';
    const state = el('div', {}, div, null);
    state.append('state ');
    el('span', {class: 'state'}, state, null).textContent = '(none)';
    const queue = el('div', {class: 'queue'}, div, null);
    queue.textContent = 'queue: ' + (machine.queue.join(', ') || '(empty)');
    el('div', {class: 'events'}, div, null);
  }
}

function buildTimelines(graph) {
  const rows = document.getElementById('timeline-rows');
  rows.replaceChildren();
  view.timelines.clear();
  for (const layer of graph.layers) {
    for (const behaviour of layer.behaviours) {
      const key = `${layer.name}/${behaviour.name}`;
      const row = el('div', {class: 'timeline', 'data-name': key}, rows, null);
      el('span', {class: 'label', title: key}, row, null).textContent = key;
      const canvas = el('canvas', {width: 3 * HISTORY, height: 26}, row, null);
      view.timelines.set(key, canvas);
    }
  }
}

const REPORTED_SHOWN = 8;
const REPORTED_KEPT = 200;  // live: the oldest are dropped

function collectReported(record) {
  for (const event of record.reported || []) view.reported.push({step: record.step, ...event});
}

// The last events reported at or before the shown step, newest first.
function showReported(record) {
  const list = document.getElementById('reported');
  const shown = view.reported.filter((event) => event.step <= record.step).slice(-REPORTED_SHOWN);
  list.replaceChildren();
  if (!shown.length) el('li', {class: 'empty'}, list, null).textContent = 'nothing reported yet';
  for (const event of shown.reverse()) {
    const item = el('li', {class: 'event'}, list, null);
    item.textContent = `step ${event.step}  ${event.by}: ${event.text}`;
  }
}

function levelsOf(record, key) {
  const [layer, name] = key.split('/');
  return record && record.layers && record.layers[layer] ? record.layers[layer][name] : undefined;
}

// Shows `record` (one step) on the graph, the controllers and the timelines.
function show(record) {
  view.current = record;
  document.getElementById('step').textContent = record ? record.step : 0;
  if (!record) return;
  for (const [key, item] of view.behaviours) {
    const levels = levelsOf(record, key) || {activation: 0, requested: 0, active: false, inhibited_by: []};
    const activation = Number(levels.activation) || 0;
    item.rect.setAttribute('fill', colour(activation));
    item.group.setAttribute('data-activation', activation);
    item.group.setAttribute('data-active', levels.active ? 'true' : 'false');
    item.group.classList.toggle('active', !!levels.active);
    item.group.classList.toggle('inhibited', !levels.active && levels.requested > 0);
    item.mark.textContent = levels.active ? '●' : '';
    const dark = activation > 0.55;
    item.name.setAttribute('fill', dark ? '#fff' : '#1d2733');
    item.level.setAttribute('fill', dark ? '#fff' : '#1d2733');
    item.level.textContent = `activation ${activation.toFixed(2)} of ${Number(levels.requested).toFixed(2)}`;
    if (item.inhibitors) {
      item.inhibitors.setAttribute('fill', dark ? '#fff' : '#1d2733');
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
  for (const [name, port] of view.ports) showActuator(port, record, name);
  for (const div of document.querySelectorAll('.controller')) {
    const state = record.controllers ? record.controllers[div.dataset.controller] : undefined;
    if (!state) continue;
    div.className = `controller ${state.status}`;
    div.querySelector('.status').textContent = `${state.status}, cycle ${state.cycle}`;
    div.querySelector('.state').textContent = state.state || '(none)';
    const queue = div.querySelector('.queue');
    queue.replaceChildren('queue: ');
    if (!state.queue.length) queue.append('(empty)');
    for (const item of state.queue) el('span', {}, queue, null).textContent = item;
    div.querySelector('.events').textContent = state.events.length ? state.events.join(' · ') : 'no events this step';
  }
  showReported(record);
  drawTimelines();
  if (view.hovered) explain(view.hovered);
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

// Notes on `record` since when each actuator it did not write has held its value, from the records
// before it (in order): `record.held[name] = {writtenAt, knownFrom}`, where writtenAt is the last
// step that wrote it (null: none seen) and knownFrom the first step seen without a gap.
function trackWrites(record) {
  const writes = view.writes;
  if (writes.last === null || record.step !== writes.last + 1) {
    // The first record, or the page missed steps (it fell behind, or was away too long):
    // what was written before them is unknown.
    writes.knownFrom = record.step;
    writes.at.clear();
  }
  writes.last = record.step;
  record.held = {};
  for (const [name, value] of Object.entries(record.actuators || {})) {
    if (value.written) writes.at.set(name, record.step);
    else record.held[name] = {writtenAt: writes.at.has(name) ? writes.at.get(name) : null, knownFrom: writes.knownFrom};
  }
}

function drawTimelines() {
  const records = view.records;
  const end = view.current ? records.indexOf(view.current) + 1 : records.length;
  const begin = Math.max(0, end - HISTORY);
  const range = document.getElementById('timeline-range');
  range.textContent = end > begin ? `steps ${records[begin].step} to ${records[end - 1].step}` : '';
  for (const [key, canvas] of view.timelines) {
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

function hover(key) {
  view.hovered = key;
  for (const [name, item] of view.behaviours) item.group.classList.toggle('hovered', name === key);
  if (key) explain(key);
}

// The `explain` answer for the hovered behaviour at the shown step, asked of the server.
async function explain(key) {
  if (!view.current || view.explainPending) return;
  const ask = `${view.current.step} ${key}`;
  if (ask === view.explainShown) return;
  view.explainPending = true;
  try {
    const response = await fetch(`explain?step=${view.current.step}&target=${encodeURIComponent(key)}`);
    document.getElementById('explain').textContent = await response.text();
    view.explainShown = ask;
  } catch (error) {
    document.getElementById('explain').textContent = `explain failed: ${error}`;
  } finally {
    view.explainPending = false;
  }
  if (view.hovered && view.current && `${view.current.step} ${view.hovered}` !== view.explainShown) {
    explain(view.hovered);
  }
}

function setStatus(text, kind) {
  const status = document.getElementById('status');
  status.textContent = text;
  status.className = `badge ${kind}`;
}

function showTiming(timing) {
  const us = (seconds) => `${(seconds * 1e6).toFixed(1)} µs`;
  const stats = (h) => `p50 ${us(h.p50)}  p99 ${us(h.p99)}  max ${us(h.max)}`;
  const lines = [`step duration  ${stats(timing.duration)}`];
  if (timing.paced) {
    lines.push(`period jitter  ${stats(timing.jitter)}`);
    lines.push(`overruns ${timing.overruns}, periods missed ${timing.missed} (period ${us(timing.period)})`);
  }
  document.getElementById('timing-panel').hidden = false;
  document.getElementById('timing').textContent = lines.join('\n');
}

function startLive(readonly) {
  document.getElementById('live-controls').hidden = !!readonly;
  const control = (action) => fetch(`control/${action}`, {method: 'POST'});
  document.getElementById('pause').onclick = () => control('pause');
  document.getElementById('single-step').onclick = () => control('step');
  document.getElementById('resume').onclick = () => control('resume');
  const events = new EventSource('events');
  events.addEventListener('graph', (event) => {
    // A reload swaps the program in: draw the new graph; the history is kept by name.
    if (event.data === view.graphText) return;
    view.graphText = event.data;
    buildGraph(JSON.parse(event.data));
    show(view.current);
  });
  events.addEventListener('step', (event) => {
    const record = JSON.parse(event.data);
    const last = view.records[view.records.length - 1];
    if (last && record.step <= last.step) return;  // already have it (a reconnect)
    trackWrites(record);
    view.records.push(record);
    if (view.records.length > HISTORY) view.records.splice(0, view.records.length - HISTORY);
    collectReported(record);
    if (view.reported.length > REPORTED_KEPT) view.reported.splice(0, view.reported.length - REPORTED_KEPT);
    // Steps arrive in batches (up to 300 when a page connects or falls behind): draw the newest
    // once per frame, not every one of them.
    if (!view.drawPending) {
      view.drawPending = true;
      requestAnimationFrame(() => {
        view.drawPending = false;
        show(view.records[view.records.length - 1]);
      });
    }
  });
  events.addEventListener('status', (event) => {
    const status = JSON.parse(event.data);
    if (status.finished) setStatus('finished', 'finished');
    else setStatus(status.paused ? 'paused' : 'running', status.paused ? 'paused' : 'running');
  });
  events.addEventListener('timing', (event) => showTiming(JSON.parse(event.data)));
  events.onerror = () => setStatus('connection lost: reconnecting…', 'lost');
}

// The index of the record of `step`, or of the nearest step the trace has.
function indexOfStep(step) {
  let best = 0;
  view.records.forEach((record, index) => {
    if (Math.abs(record.step - step) < Math.abs(view.records[best].step - step)) best = index;
  });
  return best;
}

async function startTrace(openStep) {
  document.getElementById('trace-controls').hidden = false;
  setStatus('trace', 'trace');
  const [graph, trace] = await Promise.all([fetch('graph').then((r) => r.json()),
                                            fetch('trace').then((r) => r.text())]);
  const lines = trace.split('\n').filter((line) => line.trim());
  view.records = lines.slice(1).map((line) => JSON.parse(line));
  view.records.forEach(collectReported);
  view.records.forEach(trackWrites);
  buildGraph(graph);
  const scrub = document.getElementById('scrub');
  scrub.min = 0;
  scrub.max = Math.max(0, view.records.length - 1);
  scrub.value = 0;
  const go = (index) => {
    index = Math.max(0, Math.min(view.records.length - 1, index));
    scrub.value = index;
    show(view.records[index]);
    // The address names the step shown: a reload or a copied link opens there again.
    history.replaceState(null, '', `${location.pathname}?step=${view.records[index].step}`);
  };
  scrub.oninput = () => go(Number(scrub.value));
  document.getElementById('previous').onclick = () => go(Number(scrub.value) - 1);
  document.getElementById('next').onclick = () => go(Number(scrub.value) + 1);
  document.addEventListener('keydown', (event) => {
    if (event.target === scrub) return;  // the slider moves itself
    if (event.key === 'ArrowLeft') go(Number(scrub.value) - 1);
    if (event.key === 'ArrowRight') go(Number(scrub.value) + 1);
  });
  // At the step in the address, else where `arbiter view` says (--step, by default the last).
  const asked = Number(new URLSearchParams(location.search).get('step')) || openStep;
  if (view.records.length) go(indexOfStep(asked));
  setStatus(`trace of ${view.records.length} steps`, 'trace');
}

async function start() {
  const reply = await fetch('info');
  if (reply.status === 403) {
    // The server lets in only the holder of its token (the URL arbiter printed).
    setStatus('token needed', 'lost');
    const note = document.getElementById('token-needed');
    note.textContent = await reply.text();
    note.hidden = false;
    return;
  }
  // The server has put the token in a cookie: keep it out of the address bar and history, and keep
  // the rest of the address (?step=N).
  const params = new URLSearchParams(location.search);
  if (params.has('token')) {
    params.delete('token');
    const rest = params.toString();
    history.replaceState(null, '', location.pathname + (rest ? `?${rest}` : ''));
  }
  const info = await reply.json();
  view.mode = info.mode;
  document.getElementById('mode').textContent = info.mode === 'live' ? 'live' : 'recorded';
  document.body.dataset.mode = info.mode;
  if (info.mode === 'live') startLive(info.readonly);
  else await startTrace(info.step);
  document.body.dataset.ready = 'true';
}

start();
