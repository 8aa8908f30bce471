// The live view: the stream of a running engine (`arbiter run --serve`), with Pause, Step and
// Resume.
import {setStatus, showTiming} from '../panels.js';
import {HISTORY} from '../records.js';
import {RunPage} from '../run_page.js';

const REPORTED_KEPT = 200;  // the oldest reported events are dropped

/** @param {{readonly?: boolean}} info the server's /info */
export function live(info) {
  const page = new RunPage({reportedKept: REPORTED_KEPT});
  document.getElementById('live-controls').hidden = !!info.readonly;
  const control = (action) => fetch(`control/${action}`, {method: 'POST'});
  document.getElementById('pause').onclick = () => control('pause');
  document.getElementById('single-step').onclick = () => control('step');
  document.getElementById('resume').onclick = () => control('resume');
  let graphText = '';
  let drawPending = false;
  const events = new EventSource('events');
  events.addEventListener('graph', (event) => {
    // A reload swaps the program in: draw the new graph; the history is kept by name.
    if (event.data === graphText) return;
    graphText = event.data;
    page.setGraph(JSON.parse(event.data));
  });
  events.addEventListener('step', (event) => {
    const record = JSON.parse(event.data);
    const last = page.records[page.records.length - 1];
    if (last && record.step <= last.step) return;  // already have it (a reconnect)
    page.add(record);
    if (page.records.length > HISTORY) page.records.splice(0, page.records.length - HISTORY);
    // Steps arrive in batches (up to 300 when a page connects or falls behind): draw the newest
    // once per frame, not every one of them.
    if (!drawPending) {
      drawPending = true;
      requestAnimationFrame(() => {
        drawPending = false;
        page.show(page.records[page.records.length - 1]);
      });
    }
  });
  // What the step drew (foxglove.SceneUpdate) follows its step: kept with its record.
  events.addEventListener('scene', (event) => {
    const last = page.records[page.records.length - 1];
    if (!last || String(last.step) !== event.lastEventId) return;
    last.scene = JSON.parse(event.data);
    if (page.current === last) page.scene.show(last.scene, last.step);  // drawn before it came
  });
  events.addEventListener('status', (event) => {
    const status = JSON.parse(event.data);
    if (status.finished) setStatus('finished', 'finished');
    else setStatus(status.paused ? 'paused' : 'running', status.paused ? 'paused' : 'running');
  });
  events.addEventListener('timing', (event) => showTiming(JSON.parse(event.data)));
  events.onerror = () => setStatus('connection lost: reconnecting…', 'lost');
}
