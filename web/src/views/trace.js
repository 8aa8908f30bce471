// The trace view: a recorded run (`arbiter view`), with a slider through its steps.
import {BreakBar, replyText} from '../breaks.js';
import {setStatus} from '../panels.js';
import {RunPage} from '../run_page.js';

// The index of the record of `step`, or of the nearest step the trace has.
function indexOfStep(columns, step) {
  const index = Math.max(0, columns.indexAtOrBefore(step));
  const next = Math.min(index + 1, columns.length - 1);
  return Math.abs(columns.steps[next] - step) < Math.abs(columns.steps[index] - step) ? next : index;
}

/** @param {{step: number}} info the server's /info: the step to open at */
export async function trace(info) {
  const page = new RunPage();
  document.getElementById('trace-controls').hidden = false;
  setStatus('trace', 'trace');
  const [graph, text] = await Promise.all([fetch('graph').then((r) => r.json()),
                                           fetch('trace').then((r) => r.text())]);
  const lines = text.split('\n').filter((line) => line.trim());
  for (const line of lines.slice(1)) page.add(JSON.parse(line));
  await page.setGraph(graph);
  const records = page.records;
  const scrub = document.getElementById('scrub');
  scrub.min = 0;
  scrub.max = Math.max(0, records.length - 1);
  scrub.value = 0;
  const go = (index) => {
    index = Math.max(0, Math.min(records.length - 1, index));
    scrub.value = index;
    page.show(records[index]);
    // The address names the step shown: a reload or a copied link opens there again.
    const params = new URLSearchParams(location.search);
    params.set('step', records[index].step);
    history.replaceState(null, '', `${location.pathname}?${params}`.replace(/=(?=&|$)/g, ''));
  };
  scrub.oninput = () => go(Number(scrub.value));
  document.getElementById('previous').onclick = () => go(Number(scrub.value) - 1);
  document.getElementById('next').onclick = () => go(Number(scrub.value) + 1);
  // "Next step where": the server seeks the trace from the step shown.
  const breaks = new BreakBar({live: false});
  breaks.setGraph(graph);
  page.onPick = (key) => breaks.pick(key);
  breaks.onNext = async (condition) => {
    const from = records[Number(scrub.value)]?.step ?? 0;
    const reply = await fetch(`seek?condition=${encodeURIComponent(condition)}&from=${from}`);
    if (!reply.ok) {
      breaks.say(await replyText(reply), reply.status === 400);
      return;
    }
    const {step} = await reply.json();
    breaks.say(`step ${step}: ${condition}`);
    go(indexOfStep(page.columns, step));
  };
  // A step clicked in the timelines or plots.
  page.onSeek = (step) => go(indexOfStep(page.columns, step));
  document.addEventListener('keydown', (event) => {
    if (event.target === scrub) return;  // the slider moves itself
    if (event.target.closest('input, select, textarea')) return;  // the caret moves in a field
    if (event.key === 'ArrowLeft') go(Number(scrub.value) - 1);
    if (event.key === 'ArrowRight') go(Number(scrub.value) + 1);
  });
  // At the step in the address, else where `arbiter view` says (--step, by default the last).
  const asked = Number(new URLSearchParams(location.search).get('step')) || info.step;
  if (records.length) go(indexOfStep(page.columns, asked));
  setStatus(`trace of ${records.length} steps`, 'trace');
}
