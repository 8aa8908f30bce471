// Plots of the actuators' values over the steps in view (uPlot): any number of plots, each of
// any numeric actuators and vector components (`gait_velocity[0]`), under the timelines and on
// the same scale of steps, with the same cursor, hover, zoom, pan and click to jump. Comparing two
// runs, each value of B is drawn dashed beside A's, named `value (B)`.
import uPlot from 'uplot';
import {least, levelFor, lowerBound, most} from './columns.js';
import {html} from './dom.js';
import {attachPointer} from './time_view.js';
import {formatTime} from './timeline.js';

const HEIGHT = 150;
const AXIS_SIZE = 56;  // the y axis, right of the steps
const COLOURS = ['#1570ef', '#d92d20', '#12b76a', '#f79009', '#7a5af8', '#0e9384', '#dd2590', '#344054'];

/** A number as a plot's legend writes it. */
const formatNumber = (value) => (Number.isFinite(value) ? (Number.isInteger(value) ? String(value) : value.toFixed(3)) : '–');

/** The actuator a plotted value is of: `gait_velocity` for `gait_velocity[0]`. */
const actuatorOf = (key) => key.replace(/\[\d+\]$/, '');

export class Plots {
  /**
   * @param {HTMLElement} section the plots' section
   * @param {import('./columns.js').Columns} columns
   * @param {import('./time_view.js').TimeView} view
   * @param {() => number} stripWidth how wide the timelines draw their steps (CSS pixels)
   */
  constructor(section, columns, view, stripWidth) {
    this.list = section.querySelector('#plot-list');
    this.adder = section.querySelector('#plot-add');
    this.columns = columns;
    this.view = view;
    this.stripWidth = stripWidth;
    /** Called with an actuator's name when its name in a legend is clicked. */
    this.onActuator = (name) => {};
    this.compared = null;  // B's columns, when comparing
    this.aligned = new Map();  // key -> B's values at A's steps
    /** @type {{box: HTMLElement, keys: string[], legend: HTMLElement, chart: uPlot | null}[]} */
    this.plots = [];
    this.fills = [];  // each select's refill
    this.fillChoices(this.adder);
    this.adder.addEventListener('change', () => {
      if (this.adder.value) this.add([this.adder.value]);
      this.adder.value = '';
    });
    // The plots the address asks for (`?plot=gait_velocity[0],head_angle&plot=kick`: a plot
    // each), made once the values have arrived: a link or a headless screenshot shows them.
    this.asked = new URLSearchParams(location.search).getAll('plot').map((list) => list.split(',').filter(Boolean));
    view.subscribe(() => this.draw());
  }

  /** Offers in `select` the numeric series, also those that appear later (a reload adds them). */
  fillChoices(select) {
    const fill = () => {
      if (select.options.length - 1 === this.columns.values.size) return;
      const first = select.options[0];
      select.replaceChildren(first);
      for (const key of this.columns.values.keys()) html('option', {value: key}, select).textContent = key;
      select.value = '';
    };
    this.fills.push(fill);
    fill();
  }

  /** A new plot of `keys` ('actuator' or 'actuator[i]'). */
  add(keys) {
    const box = html('div', {class: 'plot'}, this.list);
    const side = html('div', {class: 'plot-side'}, box);
    const legend = html('ul', {class: 'plot-legend'}, side);
    const tools = html('div', {class: 'plot-tools'}, side);
    const more = html('select', {'aria-label': 'plot another value here'}, tools);
    html('option', {value: ''}, more).textContent = 'add a value…';
    this.fillChoices(more);
    const fill = this.fills[this.fills.length - 1];
    const close = html('button', {type: 'button', class: 'plot-close', title: 'remove this plot'}, tools);
    close.textContent = 'remove';
    const area = html('div', {class: 'plot-area'}, box);
    const plot = {box, keys: [], legend, area, chart: null};
    // On the press, not the click: the legend is redrawn with each frame of a live run, which may
    // come between the press and the release.
    legend.addEventListener('pointerdown', (event) => {
      const item = event.button === 0 && event.target.closest('.plot-name, .plot-swatch') && event.target.closest('li[data-series]');
      if (item) this.onActuator(actuatorOf(item.dataset.series));
    });
    this.plots.push(plot);
    more.addEventListener('change', () => {
      if (more.value && !plot.keys.includes(more.value)) this.setKeys(plot, [...plot.keys, more.value]);
      more.value = '';
    });
    close.onclick = () => {
      plot.chart?.destroy();
      this.fills.splice(this.fills.indexOf(fill), 1);
      box.remove();
      this.plots.splice(this.plots.indexOf(plot), 1);
    };
    this.setKeys(plot, keys);
    return plot;
  }

  /** Compares with run B (its columns): each plot draws B's values too. */
  setCompare(columns) {
    this.compared = columns;
    this.aligned.clear();
  }

  /** B's values of `key` at A's steps (null where B has no such step). */
  valuesOfB(key) {
    let values = this.aligned.get(key);
    if (values && values.length === this.columns.length) return values;
    const b = this.compared;
    const series = b.values.get(key);
    values = this.columns.steps.map((step) => {
      const index = b.indexAtOrBefore(step);
      return series && index >= 0 && b.steps[index] === step ? series[index] : null;
    });
    this.aligned.set(key, values);
    return values;
  }

  setKeys(plot, keys) {
    plot.keys = keys;
    plot.box.dataset.series = keys.join(' ');
    plot.chart?.destroy();
    const view = this.view;
    const options = {
      width: this.width(),
      height: HEIGHT,
      legend: {show: false},
      padding: [8, 0, 4, 0],
      cursor: {show: false, drag: {x: false, y: false}},
      select: {show: false},
      // Step s is drawn at the middle of its slot, as in the timelines: from - 0.5 to to + 0.5.
      scales: {x: {time: false, auto: false, range: () => [view.from - 0.5, view.to + 0.5]}},
      axes: [{show: false}, {side: 1, size: AXIS_SIZE, font: '10.5px "DejaVu Sans", sans-serif', gap: 3}],
      series: [{}],
      hooks: {draw: [(chart) => this.drawCursor(chart)]},
    };
    // A's values, then B's dashed. Zoomed out to many steps a pixel (dense), each value is the
    // highest and the lowest of each block of steps, drawn as a bar from one to the other
    // (drawDense): a line through every block's extremes would zigzag across the plot at each
    // pixel, and a software rasteriser takes some hundred milliseconds a frame to fill it.
    plot.dense = this.level() > 0;
    const runs = this.compared ? [['', null], [' (B)', [5, 3]]] : [['', null]];
    for (const [suffix, dash] of runs) {
      keys.forEach((key, i) => {
        const line = {label: `${key}${suffix}`, stroke: COLOURS[i % COLOURS.length], width: 1.5, points: {show: false},
                      ...(dash ? {dash} : {}), ...(plot.dense ? {paths: () => null} : {})};
        options.series.push(line);
        if (plot.dense) options.series.push({...line, label: `${key}${suffix} lowest`});
      });
    }
    if (plot.dense) options.hooks.draw.unshift((chart) => this.drawDense(chart, keys.length));
    plot.chart = new uPlot(options, this.data(plot), plot.area);
    attachPointer(plot.chart.over, view, () => {
      const box = plot.chart.over.getBoundingClientRect();
      return {left: box.left, width: Math.max(1, box.width)};
    });
    this.legend(plot);
  }

  /** The uPlot's width: its steps exactly under the timelines' (its y axis to their right). */
  width() {
    return Math.max(200, Math.round(this.stripWidth()) + AXIS_SIZE);
  }

  data(plot) {
    const columns = this.columns;
    const empty = () => new Array(columns.length).fill(null);
    const a = plot.keys.map((key) => columns.values.get(key) || empty());
    const series = [...a, ...(this.compared ? plot.keys.map((key) => this.valuesOfB(key)) : [])];
    const {steps} = columns;
    const view = this.view;
    const level = this.level();
    if (!level || !plot.dense) return [steps, ...series];
    // Many steps to a pixel: each block of steps a pixel or two wide is given to uPlot as its
    // highest and lowest value, so that a frame of a long recording costs its pixels.
    const size = 2 ** level;
    const blocks = Math.ceil(steps.length / size);
    const first = Math.max(0, Math.floor(lowerBound(steps, view.from) / size) - 1);
    const last = Math.min(blocks - 1, Math.floor(lowerBound(steps, view.to + 1) / size) + 1);
    const lows = series.map((values) => columns.pyramid(values, 'least', least).level(level));
    const highs = series.map((values) => columns.pyramid(values, 'most', most).level(level));
    const x = [];
    const y = series.flatMap(() => [[], []]);
    for (let block = first; block <= last; ++block) {
      x.push((steps[block * size] + steps[Math.min((block + 1) * size, steps.length) - 1]) / 2);
      series.forEach((values, s) => {
        y[2 * s].push(highs[s][block]);
        y[2 * s + 1].push(lows[s][block]);
      });
    }
    return [x, ...y];
  }

  /** The Pyramid level the plots draw from for the steps in view: 0, every step. */
  level() {
    const view = this.view;
    return levelFor((view.to - view.from + 1) / Math.max(1, this.stripWidth()));
  }

  /** Each series with its value at the hovered step, or else at the step shown. */
  legend(plot) {
    const view = this.view;
    const step = view.hover ?? view.cursor;
    const index = step === null ? -1 : this.columns.indexAtOrBefore(step);
    const exact = index >= 0 && this.columns.steps[index] === step;
    plot.legend.replaceChildren();
    const head = html('li', {class: 'plot-step'}, plot.legend);
    head.textContent = exact ? `step ${step}  ${formatTime(this.columns.t[index])}` : '';
    plot.keys.forEach((key, i) => {
      const item = html('li', {'data-series': key}, plot.legend);
      html('span', {class: 'plot-swatch', style: `background: ${COLOURS[i % COLOURS.length]}`}, item);
      html('span', {class: 'plot-name', title: `explain ${actuatorOf(key)}`}, item).textContent = key;
      const value = exact ? this.columns.values.get(key)?.[index] : NaN;
      html('span', {class: 'plot-value'}, item).textContent = formatNumber(value);
      const remove = html('button', {type: 'button', class: 'plot-remove', title: `remove ${key}`}, item);
      remove.textContent = '×';
      remove.onclick = () => this.setKeys(plot, plot.keys.filter((other) => other !== key));
    });
    if (!this.compared) return;
    plot.keys.forEach((key, i) => {
      const item = html('li', {'data-series': key, 'data-run': 'b'}, plot.legend);
      html('span', {class: 'plot-swatch dashed', style: `border-color: ${COLOURS[i % COLOURS.length]}`}, item);
      html('span', {class: 'plot-name', title: `explain ${actuatorOf(key)}`}, item).textContent = `${key} (B)`;
      html('span', {class: 'plot-value'}, item).textContent = formatNumber(exact ? this.valuesOfB(key)[index] : NaN);
    });
  }

  /**
   * A dense plot's blocks of steps (data: x, then the highest and the lowest of each series), a
   * bar each from the lowest to the highest, on whole pixels; B's paler.
   */
  drawDense(chart, count) {
    const context = chart.ctx;
    const [x, ...y] = chart.data;
    const {left, width} = chart.bbox;
    // Each bar from half way to the block before to half way to the next: no seams between.
    const half = (x.length > 1 ? chart.valToPos(x[1], 'x', true) - chart.valToPos(x[0], 'x', true) : 1) / 2;
    context.save();
    for (let s = 0; 2 * s + 1 < y.length; ++s) {
      const high = y[2 * s];
      const low = y[2 * s + 1];
      context.fillStyle = COLOURS[(s % count) % COLOURS.length];
      context.globalAlpha = s < count ? 1 : 0.45;
      for (let i = 0; i < x.length; ++i) {
        if (high[i] === null || low[i] === null) continue;
        const middle = chart.valToPos(x[i], 'x', true);
        const px = Math.floor(middle - half);
        const barWidth = Math.max(1, Math.floor(middle + half) - px);
        if (px + barWidth < left || px > left + width) continue;
        const top = Math.floor(chart.valToPos(high[i], 'y', true));
        const bottom = Math.ceil(chart.valToPos(low[i], 'y', true));
        context.fillRect(px, top - 1, barWidth, Math.max(2, bottom - top + 2));
      }
    }
    context.restore();
  }

  drawCursor(chart) {
    const view = this.view;
    const context = chart.ctx;
    const {left, top, width, height} = chart.bbox;
    const x = (step) => left + ((step - view.from + 0.5) / (view.to - view.from + 1)) * width;
    context.save();
    if (view.hover !== null) {
      context.fillStyle = 'rgba(21, 112, 239, 0.35)';
      context.fillRect(x(view.hover) - 0.5, top, 1, height);
    }
    if (view.cursor !== null && view.cursor >= view.from && view.cursor <= view.to) {
      context.fillStyle = '#d92d20';
      context.fillRect(x(view.cursor) - 1, top, 2, height);
    }
    context.restore();
  }

  draw() {
    for (const fill of this.fills) fill();
    if (this.asked.length && this.columns.length) {
      for (const keys of this.asked) {
        const known = keys.filter((key) => this.columns.values.has(key));
        if (known.length) this.add(known);
      }
      this.asked = [];
    }
    if (!this.plots.length) return;
    const width = this.width();
    for (const plot of this.plots) {
      // Zoomed across the line between every step and blocks of them: the series change.
      if (plot.dense !== this.level() > 0) this.setKeys(plot, plot.keys);
      const chart = plot.chart;
      if (chart.width !== width) chart.setSize({width, height: HEIGHT});
      chart.batch(() => {
        chart.setData(this.data(plot), false);
        chart.setScale('x', {min: this.view.from - 0.5, max: this.view.to + 0.5});
      });
      this.legend(plot);
    }
  }
}
