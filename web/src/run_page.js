// What the live view and the trace view share: a run's graph, side panels and timelines, drawn
// for one step record at a time. A view feeds it the graph and the records and says which step
// to show.
import {Columns} from './columns.js';
import {ExplainPanel} from './explain.js';
import {GraphView} from './graph.js';
import {Plots} from './plots.js';
import {Controllers, Reported} from './panels.js';
import {WriteTracker} from './records.js';
import {SceneView} from './scene.js';
import {TimeView} from './time_view.js';
import {Timelines} from './timeline.js';

export class RunPage {
  /**
   * @param {{reportedKept?: number, followSpan?: number}} [options] followSpan: the steps the
   *     timelines show up to the newest, until zoomed (default: all)
   */
  constructor({reportedKept = Infinity, followSpan = Infinity} = {}) {
    this.records = [];    // live: the last steps received; trace: every step
    this.current = null;  // the record shown
    this.columns = new Columns();  // the records' values, for the timelines and plots
    this.time = new TimeView();
    this.time.followSpan = followSpan;
    /** A step clicked in the timelines or plots: the view shows it. */
    this.onSeek = (step) => {};
    this.time.onSeek = (step) => this.onSeek(step);
    this.writes = new WriteTracker();
    this.explain = new ExplainPanel(document.getElementById('explain'), document.getElementById('explain-subject'));
    this.graph = new GraphView(document.getElementById('graph'), (key) => {
      this.graph.highlight(key || this.explain.pinned);
      this.explain.hover(key);
    });
    /** A behaviour clicked in the graph (`layer/name`), after the explain panel pinned it. */
    this.onPick = (key) => {};
    this.graph.onClick = (key) => {
      this.explain.pin(key);
      this.onPick(key);
    };
    // Actuators and states are explained as `arbiter explain` names them: `actuators/name`,
    // `machine/state`.
    this.graph.onPort = (name) => this.explain.pin(`actuators/${name}`);
    this.explain.onPin = (key) => this.graph.highlight(key);
    this.controllers = new Controllers(document.getElementById('controllers'));
    this.reported = new Reported(document.getElementById('reported'), reportedKept);
    this.scene = new SceneView(document.getElementById('scene-panel'), document.getElementById('scene'));
    // A layer folded in the timelines is folded in the graph, and the other way round.
    this.timelines = new Timelines(document.getElementById('timelines'), this.columns, this.time, this.graph.folds);
    this.timelines.queueAt = (machine) => this.current?.controllers?.[machine]?.queue ?? null;
    this.timelines.onLabel = (key) => this.explain.pin(key);
    // A state's band clicked: the step is shown (onSeek) and the state explained there.
    this.timelines.onState = (machine, state) => this.explain.pin(`${machine}/${state}`);
    // The filter by name finds behaviours in the graph too.
    this.timelines.onFilter = (words) => this.graph.mark(words);
    this.timelines.onFind = (words) => {
      const key = this.graph.mark(words);
      if (!key) return;
      this.graph.reveal(key);
      this.explain.pin(key);
    };
    this.plots = new Plots(document.getElementById('plots'), this.columns, this.time, () => this.timelines.stripWidth);
    this.plots.onActuator = (name) => this.explain.pin(`actuators/${name}`);
    // The state in a state machine's panel.
    document.getElementById('controllers').addEventListener('click', (event) => {
      const state = event.target.closest('.controller[data-controller] .state');
      if (state && state.textContent !== '(none)') {
        this.explain.pin(`${state.closest('.controller').dataset.controller}/${state.textContent}`);
      }
    });
  }

  /**
   * Shows run B over this one (`arbiter view A --compare B`): `records` are B's, `differences`
   * the server's /compare. Before setGraph, which builds the rows.
   */
  compareWith(records, differences) {
    this.columnsB = new Columns();
    for (const record of records) this.columnsB.push(record);
    this.differences = differences;
    this.timelines.setCompare(this.columnsB, differences);
    this.plots.setCompare(this.columnsB);
    this.explain.compare = {a: differences.a, b: differences.b};
    const steps = this.columnsB.steps;
    if (steps.length) {
      this.time.setExtent(Math.min(this.time.first, steps[0]), Math.max(this.time.last, steps[steps.length - 1]));
    }
  }

  /** A record received, in step order: notes what it held and reported. */
  add(record) {
    this.writes.track(record);
    this.reported.collect(record);
    this.records.push(record);
    this.columns.push(record);
    this.time.setExtent(this.records[0].step, record.step);
  }

  /**
   * Keeps the last `kept` records or more: they are dropped in batches, so that the steps
   * streaming in cost no more than their own records.
   */
  trim(kept) {
    if (this.records.length <= 2 * kept) return;
    const dropped = this.records.length - kept;
    this.records.splice(0, dropped);
    this.columns.dropFront(dropped);
    this.time.setExtent(this.records[0].step, this.records[this.records.length - 1].step);
  }

  /** The record of `step`, or undefined. */
  recordAt(step) {
    const index = this.columns.indexAtOrBefore(step);
    return index >= 0 && this.records[index].step === step ? this.records[index] : undefined;
  }

  /** Lays out and draws `graph` (the JSON dump), then the step shown, if any. */
  async setGraph(graph) {
    if (!(await this.graph.draw(graph))) return;
    document.getElementById('title').textContent = graph.name;
    document.title = `arbiter: ${graph.name}`;
    this.controllers.build(graph);
    this.timelines.build(graph);  // and marks the behaviours its filter finds
    this.show(this.current);
  }

  /** Shows `record` (one step) on the graph, the panels and the timelines. */
  show(record) {
    this.current = record;
    document.getElementById('step').textContent = record ? record.step : 0;
    if (!record) return;
    this.graph.show(record);
    this.controllers.show(record);
    this.reported.show(record);
    this.time.setCursor(record.step);
    this.scene.show(record.scene, record.step);
    this.explain.setStep(record.step);
  }
}
