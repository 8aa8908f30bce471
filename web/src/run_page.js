// What the live view and the trace view share: a run's graph, side panels and timelines, drawn
// for one step record at a time. A view feeds it the graph and the records and says which step
// to show.
import {ExplainPanel} from './explain.js';
import {GraphView} from './graph.js';
import {Controllers, Reported} from './panels.js';
import {WriteTracker} from './records.js';
import {SceneView} from './scene.js';
import {Timelines} from './timeline.js';

export class RunPage {
  /** @param {{reportedKept?: number}} [options] */
  constructor({reportedKept = Infinity} = {}) {
    this.records = [];    // live: the last steps received; trace: every step
    this.current = null;  // the record shown
    this.writes = new WriteTracker();
    this.explain = new ExplainPanel(document.getElementById('explain'));
    this.graph = new GraphView(document.getElementById('graph'), (key) => {
      this.graph.highlight(key);
      this.explain.hover(key);
    });
    this.controllers = new Controllers(document.getElementById('controllers'));
    this.reported = new Reported(document.getElementById('reported'), reportedKept);
    this.scene = new SceneView(document.getElementById('scene-panel'), document.getElementById('scene'));
    this.timelines = new Timelines(document.getElementById('timeline-rows'), document.getElementById('timeline-range'));
  }

  /** A record received, in step order: notes what it held and reported. */
  add(record) {
    this.writes.track(record);
    this.reported.collect(record);
    this.records.push(record);
  }

  /** Lays out and draws `graph` (the JSON dump), then the step shown, if any. */
  async setGraph(graph) {
    if (!(await this.graph.draw(graph))) return;
    document.getElementById('title').textContent = graph.name;
    document.title = `arbiter: ${graph.name}`;
    this.controllers.build(graph);
    this.timelines.build(graph);
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
    this.scene.show(record.scene, record.step);
    this.timelines.draw(this.records, record);
    this.explain.setStep(record.step);
  }
}
