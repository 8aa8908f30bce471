// Breakpoints on the page: a condition as `arbiter run --break` takes it (docs/cli.md,
// "Breakpoints"), typed or picked: clicking a behaviour in the graph offers "NAME activates", an
// actuator's value "NAME > VALUE", a state machine's state "MACHINE/STATE ends", and the field's
// list offers one for every behaviour, state and value of the graph. Live, Break sets
// it on the engine, which pauses at the step where it becomes true; in a recorded run, Next shows
// the next step where it does.
import {html} from './dom.js';

const VECTOR_SIZE = {vec2: 2, vec3: 3};
const NUMBERS = new Set(['bool', 'int', 'double']);

/** The conditions the graph offers, as the field's list suggests them. */
export function conditionsOf(graph) {
  const out = [];
  const counts = new Map();
  for (const layer of graph.layers) {
    for (const behaviour of layer.behaviours) counts.set(behaviour.name, (counts.get(behaviour.name) || 0) + 1);
  }
  for (const layer of graph.layers) {
    for (const behaviour of layer.behaviours) {
      const name = counts.get(behaviour.name) > 1 ? `${layer.name}/${behaviour.name}` : behaviour.name;
      out.push(`${name} activates`, `${name} deactivates`);
    }
  }
  for (const machine of graph.state_machines) {
    for (const state of machine.states) out.push(`${machine.name}/${state.name} starts`, `${machine.name}/${state.name} ends`);
  }
  for (const layer of graph.layers) {
    for (const actuator of layer.actuators) {
      if (NUMBERS.has(actuator.type)) out.push(`${actuator.name} > 0.5`);
      for (let i = 0; i < (VECTOR_SIZE[actuator.type] || 0); ++i) out.push(`${actuator.name}[${i}] > 0.5`);
    }
  }
  out.push('event ~ "TEXT"', 'step >= 1');
  return out;
}

export class BreakBar {
  /**
   * @param {{live: boolean}} options live: Break sets breakpoints on the engine; else Next seeks
   */
  constructor({live}) {
    this.box = document.getElementById('break-controls');
    this.input = document.getElementById('break-condition');
    this.options = document.getElementById('break-options');
    this.list = document.getElementById('break-list');
    this.message = document.getElementById('break-message');
    this.add = document.getElementById('break-add');
    this.next = document.getElementById('break-next');
    this.add.hidden = !live;
    this.next.hidden = live;
    this.box.hidden = false;
    /** Break (live) or Next (recorded) was pressed on this condition. */
    this.onAdd = (condition) => {};
    this.onRemove = (condition) => {};
    this.onNext = (condition) => {};
    const submit = () => {
      const condition = this.input.value.trim();
      if (!condition) return;
      if (live) this.onAdd(condition);
      else this.onNext(condition);
    };
    this.add.onclick = submit;
    this.next.onclick = submit;
    this.input.addEventListener('keydown', (event) => {
      if (event.key === 'Enter') submit();
    });
    this.types = new Map();  // actuator → its type, for the condition a click on its value offers
    document.addEventListener('click', (event) => {
      const port = event.target.closest?.('.port.actuator[data-actuator]');
      if (port) this.pickValue(port.dataset.actuator, port.querySelector('.value')?.textContent || '');
      const state = event.target.closest?.('.controller[data-controller] .state');
      if (state && state.textContent !== '(none)') {
        const machine = state.closest('.controller').dataset.controller;
        this.input.value = `${machine}/${state.textContent} ends`;
      }
    });
  }

  /** An actuator's value clicked: break when it rises above what it shows now. */
  pickValue(name, shown) {
    const size = VECTOR_SIZE[this.types.get(name)] || 0;
    const numbers = (shown.match(/-?\d+(\.\d+)?(e-?\d+)?/g) || []).map(Number);
    const now = /^true/.test(shown) ? 1 : numbers.length ? numbers[0] : 0;
    this.input.value = `${name}${size ? '[0]' : ''} > ${now}`;
  }

  /** Offers the graph's conditions in the field's list. */
  setGraph(graph) {
    this.types.clear();
    for (const layer of graph.layers) for (const actuator of layer.actuators) this.types.set(actuator.name, actuator.type);
    this.options.replaceChildren();
    for (const condition of conditionsOf(graph)) html('option', {value: condition}, this.options);
  }

  /** A behaviour clicked (`layer/name`): "break when it activates", ready to set. */
  pick(key) {
    if (!key) return;
    this.input.value = `${key} activates`;
  }

  /** The breakpoints set, each with its remove button. */
  show(conditions) {
    this.list.replaceChildren();
    for (const condition of conditions) {
      const item = html('span', {class: 'breakpoint', 'data-condition': condition}, this.list);
      item.append(condition);
      const remove = html('button', {type: 'button', class: 'break-remove', title: `remove the breakpoint '${condition}'`}, item);
      remove.textContent = '×';
      remove.onclick = () => this.onRemove(condition);
    }
  }

  /** What the engine or the server said, or nothing ('' hides it). */
  say(text, error = false) {
    this.message.textContent = text;
    this.message.hidden = !text;
    this.message.className = error ? 'break-message error' : 'break-message';
  }
}

/**
 * The text of a server's refusal: a located condition error is several lines (the message, the
 * condition underlined, notes); the page shows it in a pre.
 */
export async function replyText(reply) {
  return (await reply.text()).replace(/\n+$/, '');
}
