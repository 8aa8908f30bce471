// The picture of the world that plugin code drew in the step shown (StepContext::scene), as the
// live stream sends it: Foxglove's foxglove.SceneUpdate, the same message a recording holds on
// /arbiter/scene. Drawn as SVG, metres as they are, y up; hidden while no step has a picture.
import {el} from './dom.js';

const MARGIN = 0.5;  // metres around what was drawn

const rgba = (c) => `rgba(${Math.round(c.r * 255)}, ${Math.round(c.g * 255)}, ${Math.round(c.b * 255)}, ${c.a})`;
// The turn about the vertical of a foxglove.Quaternion.
const yaw = (q) => 2 * Math.atan2(q.z, q.w);

export class SceneView {
  /** @param {HTMLElement} panel  @param {SVGSVGElement} root */
  constructor(panel, root) {
    this.panel = panel;
    this.root = root;
    this.bounds = null;  // grows to hold what was drawn, so that the view stays put
  }

  /** Draws `update` (a foxglove.SceneUpdate, or nothing) of step `step`. */
  show(update, step) {
    this.panel.hidden = !update;
    if (!update) return;
    this.root.replaceChildren();
    this.root.dataset.step = String(step);
    const seen = [];
    const point = (x, y) => {
      seen.push([x, y]);
      return `${x},${-y}`;
    };
    // A frame comes in more than one entity: drawn kind by kind, lines under discs under arrows
    // under texts, whatever order they came in.
    const all = (kind) => update.entities.flatMap((entity) => entity[kind]);
    for (const line of all('lines')) {
      const points = line.points.map((p) => point(p.x + line.pose.position.x, p.y + line.pose.position.y)).join(' ');
      const shape = line.type === 1 ? 'polygon' : 'polyline';
      this.root.append(el(shape, {
        points, fill: 'none', stroke: rgba(line.color), 'stroke-width': line.thickness,
        'stroke-linejoin': 'round', 'data-kind': line.type === 1 ? 'loop' : 'line',
      }));
    }
    for (const disc of all('cylinders')) {
      const {x, y} = disc.pose.position;
      point(x, y);
      this.root.append(el('circle', {
        cx: x, cy: -y, r: disc.size.x / 2, fill: rgba(disc.color), 'data-kind': 'disc',
      }));
    }
    for (const arrow of all('arrows')) {
      const {x, y} = arrow.pose.position;
      const angle = yaw(arrow.pose.orientation);
      const length = arrow.shaft_length + arrow.head_length;
      const at = (along, across) => point(x + along * Math.cos(angle) - across * Math.sin(angle),
                                          y + along * Math.sin(angle) + across * Math.cos(angle));
      const half = arrow.head_diameter / 2;
      this.root.append(el('polyline', {
        points: `${at(0, 0)} ${at(arrow.shaft_length, 0)}`, stroke: rgba(arrow.color),
        'stroke-width': arrow.shaft_diameter, fill: 'none', 'data-kind': 'arrow',
      }));
      this.root.append(el('polygon', {
        points: `${at(arrow.shaft_length, half)} ${at(length, 0)} ${at(arrow.shaft_length, -half)}`,
        fill: rgba(arrow.color),
      }));
    }
    for (const text of all('texts')) {
      const {x, y} = text.pose.position;
      point(x, y);
      const node = el('text', {
        x, y: -y, 'font-size': text.font_size, fill: rgba(text.color), 'text-anchor': 'middle',
        'dominant-baseline': 'middle', 'data-kind': 'text',
      });
      node.textContent = text.text;
      this.root.append(node);
    }
    this.fit(seen);
    // What did not fit in the step's room is said, not silently left out.
    const dropped = update.entities[0]?.metadata.find((m) => m.key === 'dropped');
    this.panel.querySelector('small').textContent =
        dropped ? `${dropped.value} primitives dropped this step` : 'as the plugins drew it';
    this.panel.classList.toggle('dropped', !!dropped);
  }

  fit(points) {
    if (!points.length) return;
    const xs = points.map((p) => p[0]);
    const ys = points.map((p) => p[1]);
    const b = this.bounds;
    this.bounds = {
      left: Math.min(b ? b.left : Infinity, ...xs), right: Math.max(b ? b.right : -Infinity, ...xs),
      bottom: Math.min(b ? b.bottom : Infinity, ...ys), top: Math.max(b ? b.top : -Infinity, ...ys),
    };
    const {left, right, bottom, top} = this.bounds;
    this.root.setAttribute('viewBox', `${left - MARGIN} ${-top - MARGIN} ${right - left + 2 * MARGIN} ${top - bottom + 2 * MARGIN}`);
  }
}
