// The studio: a config's graph beside its text (`arbiter edit`, `arbiter run --serve --edit`;
// docs/studio.md). The graph is drawn as the live view draws it (graph.js); every change, by mouse
// or keyboard or typed in the text, goes to the server, which makes it as an edit of the text
// (the edit engine the language server uses) and answers with the new texts, graph and
// diagnostics. Nothing is written until Save, after a review of what it changes.
import {el, html} from '../dom.js';
import {GraphView} from '../graph.js';
import {navigate} from '../graph_nav.js';
import {setStatus} from '../panels.js';
import {showStructure} from '../studio_ops.js';

const TYPING_PAUSE = 300;  // ms after the last key before the text is parsed again
const POLL = 2000;         // ms between looks at the server's texts: another tab's edits and saves
const GRIP = 9;            // px: the width of a behaviour's grip, the strip on its left edge that moves it

// Requests under way and graphs being laid out: `data-busy` on the body says when the page has
// settled (tests, screenshots).
let busy = 0;
function working(delta) {
  busy += delta;
  document.body.dataset.busy = busy > 0 ? 'true' : 'false';
}

async function call(path, body) {
  working(1);
  try {
    return await request(path, body);
  } finally {
    working(-1);
  }
}

async function request(path, body) {
  const reply = await fetch(path, body === undefined ? {} : {
    method: 'POST',
    headers: {'Content-Type': 'application/json'},
    body: JSON.stringify(body),
  });
  let json = null;
  try {
    json = await reply.json();
  } catch {
    json = {error: `${reply.status}: the server's answer is not JSON`};
  }
  return {status: reply.status, json};
}

const number = (node, name) => Number(node.getAttribute(name));
const textsOf = (state) => Object.fromEntries(state.files.map((file) => [file.path, file.text]));
const sameTexts = (a, b) => Object.keys(a).every((path) => a[path] === b[path]);

/** The value a form field gives for a param of `type`, or throws saying why it is not one. */
function fieldValue(input, type) {
  if (input.type === 'checkbox') return input.checked;
  const raw = input.value.trim();
  if (type === 'double' || type === 'int') {
    if (raw === '' || !Number.isFinite(Number(raw))) throw new Error(`'${raw}' is not a number`);
    return Number(raw);
  }
  if (type === 'string') return input.value;
  try {
    return JSON.parse(raw);
  } catch {
    throw new Error(`'${raw}' is not a value: write it as in the config, e.g. [1, 2] or {"a": 1}`);
  }
}

/** The UI of the studio, built into the page's side panel. */
function buildPanels() {
  const aside = document.querySelector('aside');
  aside.replaceChildren();
  const tools = html('div', {class: 'studio-tools'}, aside);
  const undo = html('button', {id: 'undo', type: 'button', title: 'undo the last change (Ctrl+Z)'}, tools);
  undo.textContent = 'Undo';
  const redo = html('button', {id: 'redo', type: 'button', title: 'redo (Ctrl+Shift+Z)'}, tools);
  redo.textContent = 'Redo';
  const chaining = html('select', {id: 'new-chaining', 'aria-label': 'a new inhibition is'}, tools);
  for (const [value, label] of [['true', 'drag adds =>  (chaining)'], ['false', 'drag adds ->  (non-chaining)']]) {
    html('option', {value}, chaining).textContent = label;
  }
  const revert = html('button', {id: 'revert', type: 'button',
                                 title: 'the files as they are on the disk now, in place of the edits (Undo brings the edits back)'}, tools);
  revert.textContent = 'Reload from disk';
  const review = html('button', {id: 'review', type: 'button', title: 'what saving changes, then Save'}, tools);
  review.textContent = 'Review and save…';
  // The palette: a behaviour of a registered class, added to a layer.
  const palette = html('form', {id: 'palette', class: 'studio-tools'}, aside);
  palette.append('add ');
  const paletteClass = html('select', {id: 'add-class', 'aria-label': 'the class of the new behaviour'}, palette);
  palette.append(' as ');
  const paletteName = html('input', {id: 'add-name', size: '14', placeholder: 'name', 'aria-label': 'the new behaviour\'s name'}, palette);
  palette.append(' to ');
  const paletteLayer = html('select', {id: 'add-layer', 'aria-label': 'the layer it joins'}, palette);
  const paletteAdd = html('button', {id: 'add-behaviour', type: 'submit'}, palette);
  paletteAdd.textContent = 'Add';
  const message = html('p', {id: 'studio-message', class: 'studio-message', role: 'status'}, aside);
  const reviewBox = html('div', {id: 'review-panel', class: 'review-panel', hidden: ''}, aside);
  html('h2', {}, reviewBox).textContent = 'Review';
  const reviewText = html('pre', {id: 'review-text'}, reviewBox);
  const reviewButtons = html('div', {class: 'studio-tools'}, reviewBox);
  const save = html('button', {id: 'save', type: 'button'}, reviewButtons);
  save.textContent = 'Save';
  const cancel = html('button', {id: 'cancel-review', type: 'button'}, reviewButtons);
  cancel.textContent = 'Back to editing';
  const textHead = html('h2', {}, aside);
  textHead.textContent = 'Text ';
  const fileSelect = html('select', {id: 'file', 'aria-label': 'the file shown'}, textHead);
  const textarea = html('textarea', {id: 'text', spellcheck: 'false', 'aria-label': 'the config\'s text'}, aside);
  html('h2', {}, aside).textContent = 'Problems';
  const problems = html('ol', {id: 'problems', class: 'problems'}, aside);
  html('h2', {}, aside).textContent = 'Selected';
  const inspector = html('div', {id: 'inspector', class: 'inspector'}, aside);
  return {undo, redo, chaining, revert, review, message, palette, paletteClass, paletteName, paletteLayer, reviewBox, reviewText, save, cancel, inspector,
          fileSelect, textarea, problems};
}

export async function studio(info) {
  const ui = buildPanels();
  const svg = document.getElementById('graph');
  const graph = new GraphView(svg, (key) => graph.highlight(key || selected?.key));
  // Zoom, pan, fold and search; a behaviour found is selected, as if clicked.
  navigate(graph, document.getElementById('graph-panel'), (key) => {
    const [layer, name] = key.split('/');
    select({kind: 'behaviour', layer, name, key});
  });
  graph.onBuilt = decorate;
  let state = null;
  let shownGraph = null;  // the last graph that compiled: drawn while the text does not
  let classes = new Map();
  let generation = 0;     // of the state shown: a look at the server's started before a change is stale
  let selected = null;    // {kind: 'behaviour', key, layer, name} or {kind: 'inhibition', layer, inhibitor, inhibited}
  let file = null;        // the path shown in the text pane
  const undoStack = [];
  const redoStack = [];

  const say = (text, kind = '') => {
    ui.message.textContent = text;
    ui.message.dataset.kind = kind;
  };

  // A diagnostic belongs to a behaviour when it names it, or lies in its declaration's lines.
  function problemsOf(layer, behaviour) {
    const mine = [];
    const declared = layer.behaviours.map((b) => b.location).filter((l) => l && l.file === behaviour.location?.file)
        .map((l) => l.line).sort((a, b) => a - b);
    const start = behaviour.location?.line ?? -1;
    const next = declared.find((line) => line > start) ?? start + 1;
    for (const d of state.diagnostics) {
      const named = d.message.includes(`'${behaviour.name}'`);
      const within = d.file === behaviour.location?.file && d.line >= start && d.line < next;
      if (named || within) mine.push(d);
    }
    return mine;
  }

  function markProblems() {
    if (!shownGraph) return;
    for (const layer of shownGraph.layers) {
      for (const behaviour of layer.behaviours) {
        const item = graph.behaviours.get(`${layer.name}/${behaviour.name}`);
        if (!item) continue;
        const found = problemsOf(layer, behaviour);
        const worst = found.some((d) => d.severity === 'error') ? 'error' : found.length ? 'warning' : '';
        item.group.classList.toggle('has-error', worst === 'error');
        item.group.classList.toggle('has-warning', worst === 'warning');
        if (worst) item.group.dataset.problems = found.map((d) => `${d.severity}: ${d.message}`).join('\n');
        else delete item.group.dataset.problems;
      }
    }
    for (const edge of svg.querySelectorAll('g.edge')) {
      const {from, to} = edge.dataset;
      // As the messages quote an inhibition: 'a => b' (a chain they cite names no one edge).
      const found = state.diagnostics.filter((d) => d.message.includes(`'${from} => ${to}'`) || d.message.includes(`'${from} -> ${to}'`));
      edge.classList.toggle('has-warning', found.length > 0);
      if (found.length) edge.dataset.problems = found.map((d) => `${d.severity}: ${d.message}`).join('\n');
    }
  }

  function showProblems() {
    ui.problems.replaceChildren();
    if (!state.diagnostics.length) {
      html('li', {class: 'empty'}, ui.problems).textContent = 'none: arbiter validate passes';
      return;
    }
    for (const d of state.diagnostics) {
      const li = html('li', {class: `problem ${d.severity}`, tabindex: '0'}, ui.problems);
      li.textContent = `${d.file.split('/').pop()}:${d.line}:${d.column}: ${d.severity}[${d.code}]: ${d.message}`;
      // To the place in the text.
      li.onclick = () => {
        showFile(d.file);
        const lines = ui.textarea.value.split('\n');
        let at = 0;
        for (let i = 0; i < d.line - 1 && i < lines.length; ++i) at += lines[i].length + 1;
        at += Math.max(0, d.column - 1);
        ui.textarea.focus();
        ui.textarea.setSelectionRange(at, at);
      };
    }
  }

  function showFile(path) {
    file = path;
    const entry = state.files.find((f) => f.path === path) || state.files[0];
    file = entry.path;
    ui.fileSelect.value = file;
    if (ui.textarea.value !== entry.text) ui.textarea.value = entry.text;
  }

  function showFiles() {
    ui.fileSelect.replaceChildren();
    for (const f of state.files) {
      const option = html('option', {value: f.path}, ui.fileSelect);
      option.textContent = f.path + (f.edited ? ' (edited)' : '') + (f.changed_on_disk ? ' (changed on the disk)' : '');
    }
    showFile(file || state.files[0]?.path);
  }

  async function show(next) {
    working(1);
    try {
      await showState(next);
    } finally {
      working(-1);
    }
  }

  async function showState(next) {
    ++generation;
    state = next;
    document.body.dataset.edited = state.files.some((f) => f.edited) ? 'true' : 'false';
    document.body.dataset.valid = state.graph ? 'true' : 'false';
    showFiles();
    showProblems();
    ui.undo.disabled = !undoStack.length;
    ui.redo.disabled = !redoStack.length;
    if (state.graph) {
      shownGraph = state.graph;
      const layers = state.graph.layers.filter((l) => !l.interface).map((l) => l.name);
      if (layers.join() !== [...ui.paletteLayer.options].map((o) => o.value).join()) {
        const chosen = ui.paletteLayer.value;
        ui.paletteLayer.replaceChildren();
        for (const name of layers) html('option', {value: name}, ui.paletteLayer).textContent = name;
        if (layers.includes(chosen)) ui.paletteLayer.value = chosen;
      }
      document.getElementById('title').textContent = `${state.graph.name} — studio`;
      if (!await graph.draw(state.graph)) return;
      svg.classList.remove('stale');
    } else {
      svg.classList.add('stale');
    }
    markProblems();
    inspect();
  }

  // What the studio adds to each drawing of the graph (a new one, a layer folded).
  function decorate() {
    // An inhibition is clicked to edit it: a wider, unpainted copy of its line takes the clicks.
    for (const edge of svg.querySelectorAll('g.edge:not(.implicit)')) {
      const line = edge.querySelector('path');
      if (line) el('path', {class: 'edge-hit', d: line.getAttribute('d')}, edge);
    }
    // A behaviour is moved by its grip, a layer by its title (the drags below).
    for (const item of graph.behaviours.values()) {
      const r = item.rect;
      const d = `M${number(r, 'x')},${number(r, 'y')} h${GRIP} v${number(r, 'height')} h${-GRIP} z`;
      const grip = el('path', {class: 'grip', d}, item.group);
      el('title', {}, grip).textContent = 'drag to move it: to another place in its layer, or into another layer (or Alt+drag the box)';
    }
    for (const head of svg.querySelectorAll('g.layer-head, g.layer > text.layer-title')) {
      el('title', {}, head).textContent = head.matches('g') ? 'click to fold; drag to move the layer' : 'drag to move the layer';
    }
    markSelected();
    markProblems();
  }

  // Runs a change: `request()` resolves with the server's answer; the texts before it go on the
  // undo stack when it changed them.
  async function change(request, done = '') {
    const before = textsOf(state);
    const {status, json} = await request();
    if (!json.files) {
      say(json.error || `refused (${status})`, 'error');
      return false;
    }
    if (!sameTexts(before, textsOf(json))) {
      undoStack.push(before);
      redoStack.length = 0;
    }
    await show(json);
    if (json.refused) say(`refused: ${json.refused}`, 'error');
    else say(done || (state.graph ? 'ok' : 'the text does not compile: see the problems below'), '');
    return !json.refused;
  }
  // A plugin named in the config brings its classes: the palette lists them from then on.
  const operation = async (body, done) => {
    const ok = await change(() => call('studio/edit', body), done);
    if (ok && body.op === 'add_plugin') await loadClasses();
    return ok;
  };
  const setTexts = (texts) => call('studio/texts', {texts});

  async function step(from, to) {
    if (!from.length) return;
    const texts = from.pop();
    to.push(textsOf(state));
    const {json} = await setTexts(texts);
    if (json.files) await show(json);
    say('', '');
  }
  ui.revert.onclick = () => change(() => call('studio/revert', {}), 'the files as they are on the disk');
  ui.undo.onclick = () => step(undoStack, redoStack);
  ui.redo.onclick = () => step(redoStack, undoStack);
  document.addEventListener('keydown', (event) => {
    if (event.target.closest('input, textarea, select')) return;  // their own undo, their own keys
    if ((event.ctrlKey || event.metaKey) && event.key.toLowerCase() === 'z') {
      event.preventDefault();
      if (event.shiftKey) ui.redo.click();
      else ui.undo.click();
    } else if ((event.key === 'Delete' || event.key === 'Backspace') && selected?.kind === 'inhibition') {
      removeInhibition(selected);
    } else if (event.key === 'Escape' && drag) {
      cancelDrag();
    } else if (event.key === 'Escape') {
      select(null);
    }
  });

  // The text pane: parsed again once typing pauses; one undo step per burst of typing.
  let typing = null;
  let typedFrom = null;
  ui.fileSelect.onchange = () => showFile(ui.fileSelect.value);
  ui.textarea.addEventListener('input', () => {
    if (typedFrom === null) {
      typedFrom = textsOf(state);
      working(1);  // until the text typed is parsed
    }
    clearTimeout(typing);
    typing = setTimeout(async () => {
      const path = file;
      const before = typedFrom;
      typedFrom = null;
      try {
        const {json} = await setTexts({[path]: ui.textarea.value});
        if (!json.files) {
          say(json.error, 'error');
          return;
        }
        undoStack.push(before);
        redoStack.length = 0;
        // Typing goes on meanwhile: keep what the pane holds now.
        const typed = ui.textarea.value;
        await show(json);
        if (typed !== ui.textarea.value && file === path) ui.textarea.value = typed;
      } finally {
        working(-1);
      }
    }, TYPING_PAUSE);
  });

  // Selection and the inspector.
  function select(item) {
    selected = item;
    markSelected();
    graph.highlight(item?.kind === 'behaviour' ? item.key : null);
    inspect();
  }

  function markSelected() {
    for (const edge of svg.querySelectorAll('g.edge.selected')) edge.classList.remove('selected');
    if (selected?.kind === 'inhibition') {
      svg.querySelector(`g.edge[data-layer="${selected.layer}"][data-from="${selected.inhibitor}"][data-to="${selected.inhibited}"]`)
          ?.classList.add('selected');
    }
  }

  const declared = (layer) => layer.inhibitions.filter((i) => !i.implicit);
  const layerOf = (name) => shownGraph?.layers.find((l) => l.name === name);

  function removeInhibition(i) {
    select(null);
    return operation({op: 'remove_inhibition', layer: i.layer, inhibitor: i.inhibitor, inhibited: i.inhibited},
                     `removed ${i.inhibitor} ⊣ ${i.inhibited}`);
  }

  function inhibitionRow(parent, layer, i) {
    const row = html('div', {class: 'inhibition-row', 'data-from': i.inhibitor, 'data-to': i.inhibited}, parent);
    html('code', {}, row).textContent = `${i.inhibitor} ${i.chaining ? '=>' : '->'} ${i.inhibited}`;
    const flip = html('button', {type: 'button', class: 'flip'}, row);
    flip.textContent = i.chaining ? 'make non-chaining (->)' : 'make chaining (=>)';
    flip.onclick = () => operation({op: 'flip_chaining', layer: layer.name, inhibitor: i.inhibitor, inhibited: i.inhibited},
                                   `flipped ${i.inhibitor} ⊣ ${i.inhibited}`);
    const remove = html('button', {type: 'button', class: 'delete'}, row);
    remove.textContent = 'delete';
    remove.onclick = () => removeInhibition({layer: layer.name, ...i});
  }

  function inspect() {
    showStructure(state.graph, selected, operation, state.plugins_to_add);
    const box = ui.inspector;
    box.replaceChildren();
    const layer = selected && layerOf(selected.layer);
    if (!selected || !layer) {
      html('p', {class: 'empty'}, box).textContent =
          'Click a behaviour or an inhibition. Drag from one behaviour to another to add an inhibition; ' +
          'drag a behaviour by its grip (its left edge), or with Alt, to move it; drag a layer by its title to move the layer.';
      return;
    }
    if (selected.kind === 'inhibition') {
      const i = declared(layer).find((x) => x.inhibitor === selected.inhibitor && x.inhibited === selected.inhibited);
      if (!i) {
        html('p', {class: 'empty'}, box).textContent = 'no such inhibition now';
        return;
      }
      html('p', {}, box).textContent = `inhibition in layer ${layer.name}`;
      inhibitionRow(box, layer, i);
      return;
    }
    const behaviour = layer.behaviours.find((b) => b.name === selected.name);
    if (!behaviour) {
      html('p', {class: 'empty'}, box).textContent = 'no such behaviour now';
      return;
    }
    const head = html('p', {}, box);
    head.textContent = `${layer.name}/${behaviour.name} (${behaviour.class})`;
    const problems = problemsOf(layer, behaviour);
    for (const d of problems) html('p', {class: `problem ${d.severity}`}, box).textContent = `${d.severity}: ${d.message}`;
    // Rename: every reference follows.
    const rename = html('form', {class: 'rename'}, box);
    const nameInput = html('input', {id: 'rename-input', value: behaviour.name, 'aria-label': 'new name'}, rename);
    const renameButton = html('button', {type: 'submit', id: 'rename'}, rename);
    renameButton.textContent = 'Rename';
    rename.onsubmit = async (event) => {
      event.preventDefault();
      const to = nameInput.value.trim();
      if (to === behaviour.name) return;
      if (await operation({op: 'rename', kind: 'behaviour', scope: layer.name, name: behaviour.name, to},
                          `renamed ${behaviour.name} to ${to}`)) {
        select({kind: 'behaviour', layer: layer.name, name: to, key: `${layer.name}/${to}`});
      }
    };
    const remove = html('button', {type: 'button', id: 'remove-behaviour'}, box);
    remove.textContent = `Remove ${behaviour.name}`;
    remove.title = 'its declaration and the inhibitions that name it';
    remove.onclick = async () => {
      if (await operation({op: 'remove_behaviour', layer: layer.name, name: behaviour.name},
                          `removed ${layer.name}/${behaviour.name}`)) {
        select(null);
      }
    };
    // Inhibitions, by keyboard too: those it takes part in, and one to add.
    html('h3', {}, box).textContent = 'Inhibitions';
    for (const i of declared(layer).filter((x) => x.inhibitor === behaviour.name || x.inhibited === behaviour.name)) {
      inhibitionRow(box, layer, i);
    }
    const add = html('form', {class: 'add-inhibition'}, box);
    add.append(`${behaviour.name} inhibits `);
    const target = html('select', {'aria-label': 'the behaviour it inhibits'}, add);
    for (const other of layer.behaviours) {
      if (other.name !== behaviour.name) html('option', {value: other.name}, target).textContent = other.name;
    }
    const addButton = html('button', {type: 'submit'}, add);
    addButton.textContent = 'Add';
    add.onsubmit = (event) => {
      event.preventDefault();
      addInhibition(layer.name, behaviour.name, target.value);
    };
    // The params, in a form made from the class's declared params.
    html('h3', {}, box).textContent = 'Params';
    const spec = classes.get(behaviour.class);
    if (!spec || !spec.params.length) {
      html('p', {class: 'empty'}, box).textContent = spec ? 'the class declares none' : 'the class is not known here';
      return;
    }
    const form = html('div', {class: 'params'}, box);
    for (const param of spec.params) paramField(form, layer, behaviour, param);
  }

  function paramField(form, layer, behaviour, param) {
    const row = html('label', {class: 'param', 'data-param': param.name}, form);
    const range = param.minimum !== null || param.maximum !== null
      ? ` in [${param.minimum ?? '−∞'}, ${param.maximum ?? '∞'}]` : '';
    const name = html('span', {class: 'param-name'}, row);
    name.textContent = `${param.name}${param.required ? ' *' : ''}`;
    const current = behaviour.params?.[param.name] ?? param.default;
    let input;
    if (param.type === 'bool') {
      input = html('input', {type: 'checkbox'}, row);
      input.checked = !!current;
    } else if (param.choices && param.choices.length) {
      input = html('select', {}, row);
      for (const choice of param.choices) html('option', {value: choice}, input).textContent = choice;
      input.value = current ?? '';
    } else if (param.type === 'double' || param.type === 'int') {
      const attributes = {type: 'number', step: param.type === 'int' ? '1' : 'any'};
      if (param.minimum !== null) attributes.min = param.minimum;
      if (param.maximum !== null) attributes.max = param.maximum;
      input = html('input', attributes, row);
      input.value = current ?? '';
    } else {
      input = html('input', {type: 'text'}, row);
      input.value = param.type === 'string' ? (current ?? '') : JSON.stringify(current ?? null);
    }
    input.setAttribute('aria-label', param.name);
    const about = html('small', {class: 'param-about'}, row);
    about.textContent = `${param.type}${range}; default ${JSON.stringify(param.default)}. ${param.description}`;
    const error = html('small', {class: 'param-error'}, row);
    let sent = current;  // Enter, then the change event: one edit
    const apply = async () => {
      let value;
      try {
        value = fieldValue(input, param.type);
      } catch (e) {
        error.textContent = e.message;
        return;
      }
      if (JSON.stringify(value) === JSON.stringify(sent)) return;
      sent = value;
      const ok = await operation({op: 'set_param', layer: layer.name, behaviour: behaviour.name, param: param.name, value},
                                 `${behaviour.name}.${param.name} = ${JSON.stringify(value)}`);
      // Refused: the field says why, in validate's words (inspect() has rebuilt the form).
      if (!ok) {
        const again = ui.inspector.querySelector(`.param[data-param="${param.name}"] .param-error`);
        if (again) again.textContent = ui.message.textContent;
      }
    };
    input.addEventListener('change', apply);
    input.addEventListener('keydown', (event) => {
      if (event.key === 'Enter') apply();
    });
  }

  function addInhibition(layer, inhibitor, inhibited) {
    const chaining = ui.chaining.value === 'true';
    return operation({op: 'add_inhibition', layer, inhibitor, inhibited, chaining},
                     `added ${inhibitor} ${chaining ? '=>' : '->'} ${inhibited}`);
  }

  // Mouse: a click selects; a drag from one behaviour to another adds an inhibition; a drag by a
  // behaviour's grip (its left edge), or with Alt held, moves it, and a drag by a layer's title
  // moves the layer. While a move is dragged, one line shows where it would land: the drop is
  // computed from the boxes as drawn, and nothing is laid out until the server has moved it.
  const toSvg = (event) => {
    const point = new DOMPoint(event.clientX, event.clientY).matrixTransform(svg.getScreenCTM().inverse());
    return point;
  };
  // The columns as drawn, in the graph's order, each with its behaviours' boxes in declaration order.
  function columnsDrawn() {
    const layers = graph.drawn.graph.layers;
    return [...svg.querySelectorAll('g.layer')].map((column, index) => {
      const box = column.querySelector('rect.layer-box');
      const names = layers[index].behaviours.map((b) => b.name);
      const boxes = [];
      for (const name of names) {
        const rect = graph.behaviours.get(`${column.dataset.layer}/${name}`)?.rect;
        if (rect) boxes.push({name, x: number(rect, 'x'), y: number(rect, 'y'), w: number(rect, 'width'), h: number(rect, 'height')});
      }
      return {layer: column.dataset.layer, x: number(box, 'x'), w: number(box, 'width'), names, boxes};
    });
  }
  const columnAt = (columns, x) => columns.reduce((best, c) => {
    const distance = Math.max(c.x - x, x - c.x - c.w, 0);
    return !best || distance < best.distance ? {column: c, distance} : best;
  }, null).column;
  // Where a behaviour dropped at `at` lands: its layer and position, and the indicator's line.
  function behaviourDrop(move, at) {
    const column = columnAt(move.columns, at.x);
    let slot = column.names.length;
    let line = [column.x + 12, 46, column.x + column.w - 12, 46];
    let nearest = null;
    for (const b of column.boxes) {
      const dx = Math.max(b.x - at.x, at.x - b.x - b.w, 0);
      const dy = Math.max(b.y - at.y, at.y - b.y - b.h, 0);
      const distance = Math.hypot(dx, dy);
      if (!nearest || distance < nearest.distance) nearest = {b, distance, beside: dy === 0};
    }
    if (nearest) {
      const {b, beside} = nearest;
      // Beside a box (in its row): before or after it by the side; above or below it, by height.
      const after = beside ? at.x > b.x + b.w / 2 : at.y > b.y + b.h / 2;
      slot = column.names.indexOf(b.name) + (after ? 1 : 0);
      if (beside) {
        const x = after ? b.x + b.w + 10 : b.x - 10;
        line = [x, b.y - 2, x, b.y + b.h + 2];
      } else {
        const y = after ? b.y + b.h + 9 : b.y - 9;
        line = [b.x - 4, y, b.x + b.w + 4, y];
      }
    }
    if (column.layer !== move.layer) return {layer: column.layer, index: slot, line};
    const from = column.names.indexOf(move.name);
    const index = slot > from ? slot - 1 : slot;
    return index === from ? null : {layer: column.layer, index, line};
  }
  // Where a layer dropped at `at` lands: before the first column whose middle is right of it.
  function layerDrop(move, at) {
    const columns = move.columns;
    let gap = columns.findIndex((c) => at.x < c.x + c.w / 2);
    if (gap < 0) gap = columns.length;
    const from = columns.findIndex((c) => c.layer === move.layer);
    const index = gap > from ? gap - 1 : gap;
    if (index === from) return null;
    const x = gap < columns.length ? columns[gap].x - 10 : columns.at(-1).x + columns.at(-1).w + 10;
    return {index, line: [x, 4, x, number(svg, 'height')]};
  }
  let drag = null;
  let dragged = false;  // a drag just ended: the click that follows it is not a click
  svg.addEventListener('pointerdown', (event) => {
    if (event.button !== 0) return;
    const start = toSvg(event);
    const head = event.target.closest('g.layer-head, text.layer-title');
    if (head) {
      drag = {kind: 'layer', layer: head.closest('g.layer').dataset.layer, start, moved: false, line: null};
      return;  // a click on the title still folds the layer
    }
    const box = event.target.closest('g.behaviour');
    if (!box) return;
    const [layer, name] = box.dataset.name.split('/');
    const kind = event.target.closest('.grip') || event.altKey ? 'behaviour' : 'inhibition';
    drag = {kind, layer, name, key: box.dataset.name, box, start, moved: false, line: null};
    event.preventDefault();
  });
  window.addEventListener('pointermove', (event) => {
    if (!drag) return;
    const at = toSvg(event);
    if (!drag.moved && Math.hypot(at.x - drag.start.x, at.y - drag.start.y) < 5) return;
    if (!drag.moved) {
      drag.moved = true;
      if (drag.kind === 'inhibition') {
        drag.line = el('line', {class: 'drag-line', x1: drag.start.x, y1: drag.start.y}, svg);
      } else {
        drag.columns = columnsDrawn();
        drag.line = el('line', {class: 'drop-indicator'}, svg);
        drag.box?.classList.add('moving');
      }
    }
    follow(at);
    // Near the frame's edge the view pans (nothing is laid out), and what is under the pointer
    // changes with it.
    drag.client = {clientX: event.clientX, clientY: event.clientY};
    graph.view.edgePan(event.clientX, event.clientY, () => {
      if (drag) follow(toSvg(drag.client));
    });
  });
  // The drag's line to the pointer at `at` (SVG units), or where the move would land.
  function follow(at) {
    if (drag.kind === 'inhibition') {
      drag.line.setAttribute('x2', at.x);
      drag.line.setAttribute('y2', at.y);
      return;
    }
    drag.drop = drag.kind === 'layer' ? layerDrop(drag, at) : behaviourDrop(drag, at);
    if (!drag.drop) {
      drag.line.setAttribute('visibility', 'hidden');
      return;
    }
    const [x1, y1, x2, y2] = drag.drop.line;
    drag.line.setAttribute('visibility', 'visible');
    drag.line.setAttribute('x1', x1);
    drag.line.setAttribute('y1', y1);
    drag.line.setAttribute('x2', x2);
    drag.line.setAttribute('y2', y2);
  }
  svg.addEventListener('click', (event) => {
    if (!dragged) return;
    event.stopPropagation();
    event.preventDefault();
  }, {capture: true});
  function cancelDrag() {
    const was = drag;
    drag = null;
    graph.view.stopEdgePan();
    was.line?.remove();
    was.box?.classList.remove('moving');
    return was;
  }
  window.addEventListener('pointercancel', () => {
    if (drag) cancelDrag();
  });
  window.addEventListener('pointerup', async (event) => {
    if (!drag) return;
    const was = cancelDrag();
    if (!was.moved) {
      if (was.kind !== 'layer') select({kind: 'behaviour', layer: was.layer, name: was.name, key: was.key});
      return;
    }
    dragged = true;
    setTimeout(() => { dragged = false; }, 0);
    if (was.kind === 'layer') {
      if (was.drop) {
        await operation({op: 'move_layer', layer: was.layer, index: was.drop.index},
                        `moved layer ${was.layer} to position ${was.drop.index}`);
      }
      return;
    }
    if (was.kind === 'behaviour') {
      const to = was.drop;
      if (!to) return;
      const moved = await operation(
          {op: 'move_behaviour', layer: was.layer, name: was.name, index: to.index,
           ...(to.layer !== was.layer ? {to_layer: to.layer} : {})},
          `moved ${was.key} to ${to.layer} position ${to.index}`);
      if (moved) select({kind: 'behaviour', layer: to.layer, name: was.name, key: `${to.layer}/${was.name}`});
      return;
    }
    const target = document.elementFromPoint(event.clientX, event.clientY)?.closest('g.behaviour');
    if (!target || target.dataset.name === was.key) return;
    const [layer, name] = target.dataset.name.split('/');
    if (layer !== was.layer) {
      say(`an inhibition joins behaviours of one layer: ${was.layer} and ${layer} are two`, 'error');
      return;
    }
    addInhibition(layer, was.name, name);
  });
  svg.addEventListener('click', (event) => {
    const edge = event.target.closest('g.edge');
    if (!edge || edge.dataset.kind === 'implicit') return;
    select({kind: 'inhibition', layer: edge.dataset.layer, inhibitor: edge.dataset.from, inhibited: edge.dataset.to});
  });

  // Review, then Save.
  ui.review.onclick = () => {
    const edited = state.files.filter((f) => f.edited);
    const lines = [];
    if (!edited.length) lines.push('nothing to save: the files are as on the disk');
    else lines.push(`saves ${edited.map((f) => f.path).join(', ')}`);
    if (state.review === null) lines.push('the graph does not compile: what changes in it cannot be told');
    else if (edited.length) lines.push(state.review || '(no change to the graph: text only)');
    if (state.diagnostics.some((d) => d.severity === 'error')) lines.push('it has errors: see the problems');
    ui.reviewText.textContent = lines.join('\n');
    ui.save.disabled = !edited.length;
    ui.reviewBox.hidden = false;
  };
  ui.cancel.onclick = () => {
    ui.reviewBox.hidden = true;
  };
  ui.save.onclick = async () => {
    const files = state.files.filter((f) => f.edited).map((f) => ({path: f.path, text: f.text, base: f.base}));
    const {status, json} = await call('studio/save', {files});
    ui.reviewBox.hidden = true;
    if (status !== 200) {
      say(json.error || `not saved (${status})`, 'error');
      return;
    }
    await show(json);
    const applied = json.applied;
    if (!applied) {
      say(`saved ${files.map((f) => f.path).join(', ')}`, 'saved');
    } else if (applied.staged) {
      say(`saved; ${applied.summary}\n${applied.diff}`, 'saved');
    } else {
      say(`saved, but ${applied.summary}:\n${applied.messages}`, 'error');
    }
  };

  // Every tab edits the server's one copy of the texts: another tab's edits and saves (and a file
  // changed on the disk) show here once this tab is idle.
  const summary = (st) => JSON.stringify(st.files.map((f) => [f.path, f.text, f.base, f.changed_on_disk]));
  setInterval(async () => {
    if (busy > 0 || typedFrom !== null || document.hidden || !state) return;
    const seen = generation;
    const {json} = await request('studio/state');
    if (seen !== generation || busy > 0 || typedFrom !== null || !json.files) return;
    if (summary(json) !== summary(state)) await show(json);
  }, POLL);

  ui.palette.onsubmit = async (event) => {
    event.preventDefault();
    const name = ui.paletteName.value.trim();
    const layer = ui.paletteLayer.value;
    if (await operation({op: 'add_behaviour', layer, name, type: ui.paletteClass.value},
                        `added ${layer}/${name} (${ui.paletteClass.value})`)) {
      ui.paletteName.value = '';
      select({kind: 'behaviour', layer, name, key: `${layer}/${name}`});
    }
  };

  setStatus(info.live ? 'editing the running engine' : 'editing', 'live');
  async function loadClasses() {
    const catalog = await call('studio/classes');
    classes = new Map(catalog.json.classes.map((c) => [c.name, c]));
    const chosen = ui.paletteClass.value;
    ui.paletteClass.replaceChildren();
    for (const c of catalog.json.classes.filter((c) => c.kind === 'behaviour')) {
      html('option', {value: c.name, title: c.description}, ui.paletteClass).textContent = c.name;
    }
    if (classes.has(chosen)) ui.paletteClass.value = chosen;
  }
  const [, first] = await Promise.all([loadClasses(), call('studio/state')]);
  await show(first.json);
  if (!state.graph) say('the config does not compile: its text and problems are below', 'error');
}
