// Arbiter's web app. The server's /info says which view to start; each view draws a run with the
// shared graph, timeline and explain modules (run_page.js); the studio edits a config. A new view
// is a module in views/ and an entry in VIEWS, with the mode its server reports in /info (two runs
// compared are the trace view's, given /info's `compare`).
import {setStatus} from './panels.js';
import {holdLoad, snapshotAsked} from './snapshot.js';
import {live} from './views/live.js';
import {studio} from './views/studio.js';
import {trace} from './views/trace.js';

const VIEWS = {
  live: {badge: 'live', start: live},      // arbiter run --serve
  trace: {badge: 'recorded', start: trace},  // arbiter view
  studio: {badge: 'studio', start: studio},  // arbiter edit, arbiter run --serve --edit
};

async function start() {
  const reply = await fetch('info');
  if (reply.status === 403) {
    // The server lets in only the holder of its token (the URL arbiter printed).
    // Only the message: an empty graph, timelines and controls would say nothing true.
    const note = document.getElementById('token-needed');
    note.textContent = await reply.text();
    note.hidden = false;
    document.body.replaceChildren(note);
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
  const view = VIEWS[info.mode];
  if (!view) {
    setStatus(`this page cannot show a server in mode '${info.mode}'`, 'lost');
    return;
  }
  document.getElementById('mode').textContent = view.badge;
  document.body.dataset.mode = info.mode;
  await view.start(info);
  document.body.dataset.ready = 'true';
}

// Asked for a snapshot, the page is loaded once it is drawn (or has said why it cannot be).
const releaseLoad = snapshotAsked() ? holdLoad() : () => {};
// Two frames after it is ready: the timelines and plots draw in the next one.
start().finally(() => requestAnimationFrame(() => requestAnimationFrame(releaseLoad)));
