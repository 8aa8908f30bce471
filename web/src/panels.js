// The side panels of a run: its state machines, what behaviour code reported, its timing, and
// the status badge.
import {html} from './dom.js';

/** Each state machine: its status and cycle, its state, its queue and the step's events. */
export class Controllers {
  /** @param {HTMLElement} box */
  constructor(box) {
    this.box = box;
  }

  build(graph) {
    this.box.replaceChildren();
    if (!graph.state_machines.length) {
      html('p', {class: 'empty'}, this.box).textContent = 'none';
      return;
    }
    for (const machine of graph.state_machines) {
      const div = html('div', {class: 'controller', 'data-controller': machine.name}, this.box);
      const head = html('div', {class: 'head'}, div);
      html('span', {class: 'name'}, head).textContent = machine.name + (machine.standalone ? '' : ' (owned)');
      html('span', {class: 'status'}, head).textContent = '';
      const state = html('div', {}, div);
      state.append('state ');
      html('span', {class: 'state'}, state).textContent = '(none)';
      const queue = html('div', {class: 'queue'}, div);
      queue.textContent = 'queue: ' + (machine.queue.join(', ') || '(empty)');
      html('div', {class: 'events'}, div);
    }
  }

  show(record) {
    for (const div of this.box.querySelectorAll('.controller')) {
      const state = record.controllers ? record.controllers[div.dataset.controller] : undefined;
      if (!state) continue;
      div.className = `controller ${state.status}`;
      div.querySelector('.status').textContent = `${state.status}, cycle ${state.cycle}`;
      div.querySelector('.state').textContent = state.state || '(none)';
      const queue = div.querySelector('.queue');
      queue.replaceChildren('queue: ');
      if (!state.queue.length) queue.append('(empty)');
      for (const item of state.queue) html('span', {}, queue).textContent = item;
      div.querySelector('.events').textContent = state.events.length ? state.events.join(' · ') : 'no events this step';
    }
  }
}

const REPORTED_SHOWN = 8;

/** What behaviour and interface code reported (records' "reported"). */
export class Reported {
  /**
   * @param {HTMLOListElement} list
   * @param {number} kept how many events to keep: the oldest are dropped
   */
  constructor(list, kept = Infinity) {
    this.list = list;
    this.kept = kept;
    this.events = [];  // oldest first
  }

  collect(record) {
    for (const event of record.reported || []) this.events.push({step: record.step, ...event});
    if (this.events.length > this.kept) this.events.splice(0, this.events.length - this.kept);
  }

  /** The last events reported at or before `record`'s step, newest first. */
  show(record) {
    const shown = this.events.filter((event) => event.step <= record.step).slice(-REPORTED_SHOWN);
    this.list.replaceChildren();
    if (!shown.length) html('li', {class: 'empty'}, this.list).textContent = 'nothing reported yet';
    for (const event of shown.reverse()) {
      html('li', {class: 'event'}, this.list).textContent = `step ${event.step}  ${event.by}: ${event.text}`;
    }
  }
}

/** The run's step timing, as its summary gives it (docs/cli.md). */
export function showTiming(timing) {
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

export function setStatus(text, kind) {
  const status = document.getElementById('status');
  status.textContent = text;
  status.className = `badge ${kind}`;
}
