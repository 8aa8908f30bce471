// The studio's structure edits (docs/studio.md): moving a behaviour or a layer, adding and removing
// a plugin, a layer, a state machine, an actuator or a sensor, wiring a behaviour's ports and editing a state machine's states and queue. Each is a button or
// a small form, so that the mouse and the keyboard (Tab, Enter) reach every one (a queue's items are
// dragged too); each asks the server for one operation, which the edit engine makes as a text edit
// and checks.
import {html} from './dom.js';
import {MOVED} from './graph_nav.js';

const TYPES = ['double', 'bool', 'int', 'vec2', 'vec3', 'string'];

function button(parent, label, title, onclick, attributes = {}) {
  const b = html('button', {type: 'button', title, ...attributes}, parent);
  b.textContent = label;
  b.onclick = onclick;
  return b;
}

/** A form that runs `submit` on Enter or its button, as the page's other forms do. */
function form(parent, id, label, submit) {
  const f = html('form', {id, class: 'studio-op'}, parent);
  f.onsubmit = (event) => {
    event.preventDefault();
    submit();
  };
  return {form: f, done: () => { html('button', {type: 'submit'}, f).textContent = label; }};
}

function select(parent, values, attributes) {
  const s = html('select', attributes, parent);
  for (const value of values) html('option', {value}, s).textContent = value;
  return s;
}

/** The selected behaviour's moves and ports. */
function behaviourOps(box, graph, layer, behaviour, operation) {
  html('h3', {}, box).textContent = `Move ${behaviour.name}`;
  const names = layer.behaviours.map((b) => b.name);
  const at = names.indexOf(behaviour.name);
  const row = html('div', {class: 'studio-op'}, box);
  const move = (index, toLayer = '') => operation(
      {op: 'move_behaviour', layer: layer.name, name: behaviour.name, index, ...(toLayer ? {to_layer: toLayer} : {})},
      `moved ${layer.name}/${behaviour.name} to ${toLayer || layer.name} position ${index}`);
  button(row, '↑ earlier', 'declared before the behaviour above it', () => move(at - 1),
         {id: 'move-behaviour-up', ...(at === 0 ? {disabled: ''} : {})});
  button(row, '↓ later', 'declared after the behaviour below it', () => move(at + 1),
         {id: 'move-behaviour-down', ...(at === names.length - 1 ? {disabled: ''} : {})});
  const others = graph.layers.filter((l) => !l.interface && l.name !== layer.name).map((l) => l.name);
  if (others.length) {
    const {form: f, done} = form(box, 'move-to-layer', 'Move', () =>
      move(Number(position.value), target.value));
    f.append('to layer ');
    const target = select(f, others, {id: 'move-target-layer', 'aria-label': 'the layer it moves to'});
    f.append(' at ');
    const position = html('input', {id: 'move-target-index', type: 'number', min: '0', value: '0', size: '3',
                                    'aria-label': 'its position there, from 0'}, f);
    done();
  }
  const ports = Object.entries(behaviour.ports || {});
  if (!ports.length) return;
  html('h3', {}, box).textContent = 'Ports';
  const names_ = [...(layer.actuators || []).map((a) => a.name), ...(layer.sensors || []).map((s) => s.name)];
  for (const [port, target] of ports) {
    const {form: f, done} = form(box, `wire-${port}`, 'Wire', () =>
      operation({op: 'wire_port', layer: layer.name, behaviour: behaviour.name, port, target: input.value.trim()},
                `wired ${behaviour.name}.${port} to ${input.value.trim()}`));
    f.dataset.port = port;
    f.append(`${port} → `);
    const input = html('input', {value: target || '', size: '14', list: `port-names-${layer.name}`,
                                 placeholder: 'unbound', 'aria-label': `what port ${port} binds`}, f);
    done();
  }
  const list = html('datalist', {id: `port-names-${layer.name}`}, box);
  for (const name of names_) html('option', {value: name}, list);
}

/** Every layer's place and actuators; a layer added or removed. */
function layerOps(box, graph, operation) {
  html('h3', {}, box).textContent = 'Layers and actuators';
  graph.layers.forEach((layer, index) => {
    const row = html('div', {class: 'studio-op layer-op', 'data-layer': layer.name}, box);
    html('strong', {}, row).textContent = layer.name;
    const move = (to) => operation({op: 'move_layer', layer: layer.name, index: to},
                                   `moved layer ${layer.name} to position ${to}`);
    button(row, '↑', `layer ${layer.name} before the one above it`, () => move(index - 1),
           {class: 'move-layer-up', ...(index === 0 ? {disabled: ''} : {})});
    button(row, '↓', `layer ${layer.name} after the one below it`, () => move(index + 1),
           {class: 'move-layer-down', ...(index === graph.layers.length - 1 ? {disabled: ''} : {})});
    for (const actuator of layer.actuators || []) {
      const item = html('span', {class: 'actuator-op', 'data-actuator': actuator.name}, row);
      item.append(` ${actuator.name}: ${actuator.type} `);
      button(item, '×', `remove actuator ${actuator.name} (refused while something uses it)`, () =>
        operation({op: 'remove_actuator', layer: layer.name, name: actuator.name},
                  `removed actuator ${actuator.name}`), {class: 'remove-actuator'});
    }
    const {form: f, done} = form(box, `add-actuator-${layer.name}`, 'Add actuator', () =>
      operation({op: 'add_actuator', layer: layer.name, name: name.value.trim(), type: type.value},
                `added actuator ${layer.name}/${name.value.trim()}`));
    f.classList.add('add-actuator');
    const name = html('input', {size: '12', placeholder: 'name', 'aria-label': `a new actuator of ${layer.name}`}, f);
    f.append(' ');
    const type = select(f, TYPES, {'aria-label': 'its type'});
    done();
    // What it reads: actuators of other layers, each with ×, and one more by name.
    if (!layer.interface || (layer.sensors || []).length) {
      const reads = html('div', {class: 'studio-op sensors-op', 'data-layer': layer.name}, box);
      reads.append(`${layer.name} reads: `);
      for (const sensor of layer.sensors || []) {
        const item = html('span', {class: 'sensor-op', 'data-sensor': sensor.name}, reads);
        item.append(` ${sensor.name} `);
        button(item, '×', `stop reading ${sensor.name} (refused while a port is bound to it)`, () =>
          operation({op: 'remove_sensor', layer: layer.name, name: sensor.name}, `removed sensor ${sensor.name}`),
               {class: 'remove-sensor'});
      }
    }
    const others = graph.layers.filter((l) => l.name !== layer.name)
        .flatMap((l) => (l.actuators || []).map((a) => a.name))
        .filter((a) => !(layer.sensors || []).some((s) => s.name === a));
    const {form: r, done: read} = form(box, `add-sensor-${layer.name}`, 'Read', () =>
      operation({op: 'add_sensor', layer: layer.name, name: sensor.value.trim()},
                `${layer.name} reads ${sensor.value.trim()}`));
    r.classList.add('add-sensor');
    r.append(`${layer.name} reads `);
    const sensor = html('input', {size: '12', list: `sensor-names-${layer.name}`, placeholder: 'actuator',
                                  'aria-label': `an actuator of another layer that ${layer.name} reads`}, r);
    const names = html('datalist', {id: `sensor-names-${layer.name}`}, r);
    for (const name of others) html('option', {value: name}, names);
    read();
    // Last in the row: removing a layer takes its behaviours, actuators and inhibitions with it.
    button(row, '× layer', `remove layer ${layer.name} with its behaviours (refused while another layer reads it)`,
           () => operation({op: 'remove_layer', name: layer.name}, `removed layer ${layer.name}`),
           {class: 'remove-layer'});
  });
  const {form: f, done} = form(box, 'new-layer', 'Add layer', () => {
    const at = position.value.trim();
    operation({op: 'add_layer', name: name.value.trim(), ...(at ? {index: Number(at)} : {}),
               ...(iface.value.trim() ? {interface: iface.value.trim()} : {})},
              `added layer ${name.value.trim()}`);
  });
  f.append('new layer ');
  const name = html('input', {id: 'new-layer-name', size: '12', placeholder: 'name', 'aria-label': 'a new layer'}, f);
  f.append(' at ');
  const position = html('input', {id: 'new-layer-index', type: 'number', min: '0', size: '3', placeholder: 'end',
                                  'aria-label': 'its position, from 0 (empty: last)'}, f);
  f.append(' interface ');
  const iface = html('input', {id: 'new-layer-interface', size: '12', placeholder: 'none',
                               'aria-label': 'its interface class, for an interface layer'}, f);
  done();
}

/**
 * The items of `list` reordered by dragging one (not by its buttons) above or below another: a line
 * shows where it lands while dragging, and `move(from, to)` is called on the drop, `to` being its
 * place once moved. Escape, or a drop where it is, moves nothing.
 */
function dragToReorder(list, move) {
  let drag = null;
  const items = () => [...list.children];
  const clear = () => {
    for (const item of items()) item.classList.remove('dragging', 'drop-before', 'drop-after');
  };
  // The gap before which the pointer at `y` drops: the first item whose middle is below it.
  const gapAt = (y) => {
    const gap = items().findIndex((item) => {
      const box = item.getBoundingClientRect();
      return y < box.top + box.height / 2;
    });
    return gap < 0 ? items().length : gap;
  };
  const end = () => {
    drag = null;
    clear();
    window.removeEventListener('keydown', escape, true);
  };
  const escape = (event) => {
    if (event.key !== 'Escape' || !drag) return;
    event.stopPropagation();
    end();
  };
  list.addEventListener('pointerdown', (event) => {
    const item = event.target.closest('li');
    if (event.button !== 0 || !item || event.target.closest('button')) return;
    drag = {from: items().indexOf(item), y: event.clientY, moved: false, to: null};
    event.preventDefault();
  });
  list.addEventListener('pointermove', (event) => {
    if (!drag) return;
    if (!drag.moved) {
      if (Math.abs(event.clientY - drag.y) < MOVED) return;
      drag.moved = true;
      list.setPointerCapture(event.pointerId);
      window.addEventListener('keydown', escape, true);
    }
    clear();
    const all = items();
    all[drag.from].classList.add('dragging');
    const gap = gapAt(event.clientY);
    const to = gap > drag.from ? gap - 1 : gap;
    drag.to = to === drag.from ? null : to;
    if (drag.to === null) return;
    if (gap < all.length) all[gap].classList.add('drop-before');
    else all[gap - 1].classList.add('drop-after');
  });
  list.addEventListener('pointerup', () => {
    const was = drag;
    if (!was) return;
    end();
    if (was.moved && was.to !== null) move(was.from, was.to);
  });
  list.addEventListener('pointercancel', end);
}

/**
 * State machines added and removed; each one's queue (reordered by dragging or by buttons, an item
 * removed, a state planned with params) and states.
 */
function queueOps(box, graph, operation) {
  const machines = graph.state_machines || [];
  html('h3', {}, box).textContent = 'State machines';
  const {form: add, done: added} = form(box, 'new-state-machine', 'Add state machine', () =>
    operation({op: 'add_state_machine', name: machineName.value.trim()},
              `added state machine ${machineName.value.trim()}`));
  add.append('new state machine ');
  const machineName = html('input', {id: 'new-state-machine-name', size: '12', placeholder: 'name',
                                     'aria-label': 'a new state machine'}, add);
  added();
  for (const machine of machines) {
    const head = html('div', {class: 'studio-op machine-op', 'data-machine': machine.name}, box);
    html('strong', {}, head).textContent = machine.name;
    button(head, '× machine', `remove state machine ${machine.name} (refused while something owns it)`, () =>
      operation({op: 'remove_state_machine', name: machine.name}, `removed state machine ${machine.name}`),
           {class: 'remove-state-machine'});
    const list = html('ol', {class: 'queue-op', 'data-machine': machine.name, start: '0'}, box);
    const queue = machine.queue || [];
    dragToReorder(list, (from, to) => operation({op: 'move_queue_entry', machine: machine.name, from, to},
                                                `moved item ${from} of ${machine.name}'s queue to ${to}`));
    queue.forEach((state, index) => {
      const item = html('li', {title: 'drag to move it in the queue'}, list);
      item.append(`${typeof state === 'string' ? state : state.name || JSON.stringify(state)} `);
      const move = (to) => operation({op: 'move_queue_entry', machine: machine.name, from: index, to},
                                     `moved item ${index} of ${machine.name}'s queue to ${to}`);
      button(item, '↑', 'earlier in the queue', () => move(index - 1),
             {class: 'queue-up', ...(index === 0 ? {disabled: ''} : {})});
      button(item, '↓', 'later in the queue', () => move(index + 1),
             {class: 'queue-down', ...(index === queue.length - 1 ? {disabled: ''} : {})});
      button(item, '×', 'remove it from the queue', () =>
        operation({op: 'remove_queue_entry', machine: machine.name, index},
                  `removed item ${index} of ${machine.name}'s queue`), {class: 'queue-remove'});
    });
    // Its states: each with × (refused while something names it), and one to declare.
    const states = html('div', {class: 'studio-op states-op', 'data-machine': machine.name}, box);
    states.append(`${machine.name}'s states: `);
    for (const declared of machine.states) {
      const item = html('span', {class: 'state-op', 'data-state': declared.name}, states);
      item.append(` ${declared.name} (${declared.class}) `);
      button(item, '×', `remove state ${declared.name} (refused while something names it)`, () =>
        operation({op: 'remove_state', machine: machine.name, name: declared.name},
                  `removed state ${machine.name}/${declared.name}`), {class: 'remove-state'});
    }
    const {form: add, done: added} = form(box, `add-state-${machine.name}`, 'Add state', () =>
      operation({op: 'add_state', machine: machine.name, name: stateName.value.trim(), type: stateClass.value.trim()},
                `added state ${machine.name}/${stateName.value.trim()}`));
    const stateName = html('input', {size: '12', placeholder: 'name', 'aria-label': `a new state of ${machine.name}`}, add);
    add.append(' of class ');
    const stateClass = html('input', {size: '14', value: 'scripted', 'aria-label': 'its class'}, add);
    added();
    const {form: f, done} = form(box, `plan-${machine.name}`, 'Plan', () => {
      let params;
      try {
        params = values.value.trim() ? JSON.parse(values.value) : undefined;
      } catch {
        values.setCustomValidity('write the params as JSON: {"hold": 2}');
        values.reportValidity();
        return;
      }
      operation({op: 'add_queue_entry', machine: machine.name, state: state.value, ...(params ? {params} : {})},
                `planned ${state.value} in ${machine.name}'s queue`);
    });
    f.classList.add('plan-state');
    f.append(`${machine.name}: plan `);
    const state = select(f, machine.states.map((s) => s.name), {'aria-label': `a state of ${machine.name}`});
    f.append(' with ');
    const values = html('input', {size: '14', placeholder: '{"hold": 2}', 'aria-label': 'its params, as JSON'}, f);
    values.oninput = () => values.setCustomValidity('');
    done();
  }
}

/**
 * A plugin named in the config, whose classes join the palette: one of `plugins` (on the plugin
 * path, not named yet) chosen from a list, or another typed by name (a path, or one installed later).
 */
function pluginOps(box, plugins, operation) {
  const {form: f, done} = form(box, 'new-plugin', 'Add plugin', () => {
    const name = (choice?.value || typed.value).trim();
    operation({op: 'add_plugin', name}, `added plugin ${name}`);
  });
  f.append('plugin ');
  const choice = plugins.length ? html('select', {id: 'new-plugin-choice', 'aria-label': 'a plugin on the plugin path'}, f) : null;
  if (choice) {
    for (const name of plugins) html('option', {value: name}, choice).textContent = name;
    html('option', {value: ''}, choice).textContent = 'another, by name:';
    f.append(' ');
  }
  const typed = html('input', {id: 'new-plugin-name', size: '12', placeholder: plugins.length ? 'name' : 'soccer',
                               'aria-label': 'a plugin the config loads, by name or path'}, f);
  // A name typed is the one meant: the list says so rather than adding the plugin it shows.
  if (choice) typed.oninput = () => { if (typed.value.trim()) choice.value = ''; };
  done();
}

/**
 * Draws the structure edits for `graph` (the dump of the texts; null while they do not compile)
 * and the selection (`{kind: 'behaviour', layer, name}` or another), into a panel of the page's
 * side panel made on first use. `operation(body, done)` is the studio's: one edit request;
 * `plugins` the ones on the plugin path that the config does not name (the state's `plugins_to_add`).
 */
export function showStructure(graph, selected, operation, plugins = []) {
  let box = document.getElementById('structure');
  if (!box) {
    const aside = document.querySelector('aside');
    html('h2', {}, aside).textContent = 'Structure';
    box = html('div', {id: 'structure', class: 'inspector'}, aside);
  }
  box.replaceChildren();
  if (!graph) {
    html('p', {class: 'empty'}, box).textContent = 'the text does not compile';
    return;
  }
  const layer = selected?.kind === 'behaviour' && graph.layers.find((l) => l.name === selected.layer);
  const behaviour = layer && layer.behaviours.find((b) => b.name === selected.name);
  if (behaviour) behaviourOps(box, graph, layer, behaviour, operation);
  pluginOps(box, plugins, operation);
  layerOps(box, graph, operation);
  queueOps(box, graph, operation);
}
