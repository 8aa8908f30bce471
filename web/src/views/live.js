// The live view: the stream of a running engine (`arbiter run --serve`), with Pause, Step and
// Resume while it runs, and the safe values it output while paused.
import {BreakBar, replyText} from '../breaks.js';
import {setStatus, showTiming} from '../panels.js';
import {HISTORY} from '../records.js';
import {RunPage} from '../run_page.js';
import {snapshotAsked} from '../snapshot.js';

const REPORTED_KEPT = 200;  // the oldest reported events are dropped

/**
 * @param {{readonly?: boolean}} info the server's /info
 * @returns {Promise<void>} resolved at once, or for a snapshot once it is drawn
 */
export function live(info) {
  const page = new RunPage({reportedKept: REPORTED_KEPT, followSpan: HISTORY});
  const snapshot = snapshotAsked();
  const controls = document.getElementById('live-controls');
  // A snapshot is a picture: nothing on it can pause the run.
  controls.hidden = !!info.readonly || snapshot;
  const buttons = ['pause', 'single-step', 'resume'].map((id) => document.getElementById(id));
  const control = (action) => fetch(`control/${action}`, {method: 'POST'});
  buttons[0].onclick = () => control('pause');
  buttons[1].onclick = () => control('step');
  buttons[2].onclick = () => control('resume');
  // Breakpoints: set and removed on the engine, which answers between two steps; the status
  // lists them and names the one the run is paused at.
  const breaks = controls.hidden ? null : new BreakBar({live: true});
  if (breaks) {
    const change = async (kind, condition) => {
      const reply = await fetch(`control/break?${kind}=${encodeURIComponent(condition)}`, {method: 'POST'});
      breaks.say(reply.ok ? '' : await replyText(reply), !reply.ok);
    };
    breaks.onAdd = (condition) => change('add', condition);
    breaks.onRemove = (condition) => change('remove', condition);
    page.onPick = (key) => breaks.pick(key);
  }
  // The safe-value pass of the engine that paused: shown instead of its last step's commands
  // (that is what its interface layers output), until the next step.
  let safe = null;
  const showSafe = () => {
    if (pinned) return;
    const shown = page.records[page.records.length - 1];
    if (!safe || !shown || safe.step !== shown.step) return;
    // An actuator without a safe value keeps the last step's value, held as it was.
    safe.held = {...shown.held};
    // The safe pass draws nothing: the world is as its step drew it.
    safe.scene = shown.scene;
    for (const [name, value] of Object.entries(safe.actuators || {})) {
      if (value.written) delete safe.held[name];
    }
    page.show(safe);
    document.body.dataset.safe = 'true';
  };
  // A step clicked in the timelines stays shown while the run goes on, until Follow (or End).
  let pinned = null;
  const followButton = document.getElementById('follow');
  const follow = () => {
    pinned = null;
    followButton.hidden = true;
    delete document.body.dataset.pinned;
    const last = page.records[page.records.length - 1];
    if (last) page.show(last);
    showSafe();
  };
  followButton.onclick = follow;
  page.onSeek = (step) => {
    const record = page.recordAt(step);
    if (!record) return;
    if (record === page.records[page.records.length - 1]) {
      follow();
      return;
    }
    pinned = record;
    followButton.hidden = false;
    document.body.dataset.pinned = String(step);
    delete document.body.dataset.safe;
    page.show(record);
  };
  document.addEventListener('keydown', (event) => {
    if (event.key === 'End' && pinned) follow();
  });
  let graphText = '';
  let graphDrawn = Promise.resolve();
  let drawPending = false;
  const events = new EventSource(snapshot ? 'events?snapshot=1' : 'events');
  events.addEventListener('graph', (event) => {
    // A reload swaps the program in: draw the new graph; the history is kept by name.
    if (event.data === graphText) return;
    graphText = event.data;
    const graph = JSON.parse(event.data);
    graphDrawn = page.setGraph(graph);
    if (breaks) breaks.setGraph(graph);
  });
  events.addEventListener('step', (event) => {
    const record = JSON.parse(event.data);
    const last = page.records[page.records.length - 1];
    if (last && record.step <= last.step) return;  // already have it (a reconnect)
    page.add(record);
    page.trim(HISTORY);
    if (pinned && !page.recordAt(pinned.step)) follow();  // the step shown has been dropped
    // Steps arrive in batches (up to 300 when a page connects or falls behind): draw the newest
    // once per frame, not every one of them.
    if (!drawPending) {
      drawPending = true;
      requestAnimationFrame(() => {
        drawPending = false;
        if (pinned) return;
        delete document.body.dataset.safe;
        page.show(page.records[page.records.length - 1]);
        showSafe();
      });
    }
  });
  events.addEventListener('safe', (event) => {
    safe = JSON.parse(event.data);
    if (!drawPending) showSafe();
  });
  // What the step drew (foxglove.SceneUpdate) follows its step: kept with its record.
  events.addEventListener('scene', (event) => {
    const last = page.records[page.records.length - 1];
    if (!last || String(last.step) !== event.lastEventId) return;
    last.scene = JSON.parse(event.data);
    if (safe && safe.step === last.step) safe.scene = last.scene;
    // Drawn before it came (the step, or the safe pass after it).
    if (page.current === last || (page.current === safe && safe.step === last.step)) {
      page.scene.show(last.scene, last.step);
    }
  });
  events.addEventListener('status', (event) => {
    const status = JSON.parse(event.data);
    if (status.finished) {
      // Nothing is left to pause, step or resume.
      setStatus('finished', 'finished');
      for (const button of buttons) button.disabled = true;
      controls.hidden = true;
    } else if (status.paused && status.break) {
      setStatus(`paused at step ${status.break.step}: break ${status.break.condition}`, 'break');
    } else {
      setStatus(status.paused ? 'paused' : 'running', status.paused ? 'paused' : 'running');
    }
    if (breaks && status.breakpoints) breaks.show(status.breakpoints);
    if (status.break && !status.finished) document.body.dataset.break = String(status.break.step);
    else delete document.body.dataset.break;
  });
  events.addEventListener('timing', (event) => showTiming(JSON.parse(event.data)));
  events.onerror = () => setStatus('connection lost: reconnecting…', 'lost');
  if (!snapshot) return Promise.resolve();
  // The server ends a snapshot's stream with "end" once it has sent the run up to the step it
  // had when the page connected.
  return new Promise((resolve) => {
    events.addEventListener('end', async () => {
      events.close();
      await graphDrawn;
      delete document.body.dataset.safe;
      page.show(page.records[page.records.length - 1] || null);
      showSafe();
      const status = document.getElementById('status');
      status.textContent = `snapshot: ${status.textContent}`;
      document.body.dataset.snapshot = 'true';
      resolve();
    });
  });
}
