// Small helpers for building the page's SVG and HTML.

export const SVG = 'http://www.w3.org/2000/svg';

/**
 * A new element with `attributes`, appended to `parent` if given; SVG unless `ns` is null.
 * @param {string} tag
 * @param {Record<string, string | number>} [attributes]
 * @param {Element | null} [parent]
 * @param {string | null} [ns]
 * @returns {Element}
 */
export function el(tag, attributes = {}, parent = null, ns = SVG) {
  const node = ns ? document.createElementNS(ns, tag) : document.createElement(tag);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, String(value));
  if (parent) parent.appendChild(node);
  return node;
}

/** An HTML element: el() without the SVG namespace. */
export function html(tag, attributes = {}, parent = null) {
  return el(tag, attributes, parent, null);
}

/** An SVG element holding `content` as its text. */
export function text(tag, attributes, content, parent) {
  const node = el(tag, attributes, parent);
  node.textContent = content;
  return node;
}

/** The fill of an activation level: pale at 0, dark blue at 1. */
export function colour(level) {
  const a = Math.max(0, Math.min(1, Number(level) || 0));
  return `hsl(210, ${30 + 55 * a}%, ${95 - 53 * a}%)`;
}

/** An actuator value as the page prints it: numbers to 3 decimals, vectors in brackets. */
export function formatValue(value) {
  if (Array.isArray(value)) return '[' + value.map(formatValue).join(', ') + ']';
  if (typeof value === 'number') return Number.isInteger(value) ? String(value) : value.toFixed(3);
  return JSON.stringify(value);
}
