// The trace view: a recorded run (`arbiter view`), with a slider through its steps; or two
// (`arbiter view A --compare B`), B's rows under A's, with the steps where they differ marked and
// a button to the first of them.
import {BreakBar, replyText} from '../breaks.js';
import {setStatus} from '../panels.js';
import {RunPage} from '../run_page.js';

// The index of the record of `step`, or of the nearest step the trace has.
function indexOfStep(columns, step) {
  const index = Math.max(0, columns.indexAtOrBefore(step));
  const next = Math.min(index + 1, columns.length - 1);
  return Math.abs(columns.steps[next] - step) < Math.abs(columns.steps[index] - step) ? next : index;
}

/** The step records of a trace's text (its header left out). */
const recordsOf = (text) => text.split('\n').filter((line) => line.trim()).slice(1).map((line) => JSON.parse(line));

/** The first step after `step` in runs of steps ([[from, to], ...]), or null. */
function nextIn(runs, step) {
  for (const [from, to] of runs) {
    if (to > step) return Math.max(from, step + 1);
  }
  return null;
}

/**
 * @param {{step: number, compare?: {a: string, b: string}}} info the server's /info: the step to
 *     open at, and the runs compared
 */
export async function trace(info) {
  const page = new RunPage();
  document.getElementById('trace-controls').hidden = false;
  setStatus('trace', 'trace');
  const [graph, text, textB, differences] = await Promise.all([
    fetch('graph').then((r) => r.json()), fetch('trace').then((r) => r.text()),
    info.compare ? fetch('trace?run=b').then((r) => r.text()) : null,
    info.compare ? fetch('compare').then((r) => r.json()) : null]);
  for (const record of recordsOf(text)) page.add(record);
  if (differences) page.compareWith(recordsOf(textB), differences);
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
  if (differences) compareBar(differences, () => records[Number(scrub.value)]?.step ?? 0, (step) => go(indexOfStep(page.columns, step)));
  // At the step in the address, else where `arbiter view` says (--step, by default the last).
  const asked = Number(new URLSearchParams(location.search).get('step')) || info.step;
  if (records.length) go(indexOfStep(page.columns, asked));
  setStatus(differences ? `${records.length} steps compared with ${page.columnsB.length}` : `trace of ${records.length} steps`, 'trace');
}

/**
 * The bar over the page comparing runs A and B: their names, where they first differ and what
 * differs there, and buttons (and the key n) to the first and the next step where they differ.
 */
function compareBar(differences, shown, go) {
  document.getElementById('compare-bar').hidden = false;
  document.getElementById('compare-runs').textContent = `A ${differences.a} · B ${differences.b}`;
  const first = differences.first;
  const what = document.getElementById('compare-what');
  const firstButton = document.getElementById('compare-first');
  const nextButton = document.getElementById('compare-next');
  if (!first) {
    what.textContent = 'identical: no step differs';
    firstButton.hidden = nextButton.hidden = true;
    return;
  }
  what.textContent = `first differ at step ${first.step}${first.what.length ? `: ${first.what.join(', ')}` : ' (one run is longer)'}`;
  firstButton.onclick = () => go(first.step);
  const next = () => {
    const step = nextIn(differences.steps, shown());
    if (step !== null) go(step);
  };
  nextButton.onclick = next;
  document.addEventListener('keydown', (event) => {
    if (event.key === 'n' && !event.target.closest('input, select, textarea')) next();
  });
}
