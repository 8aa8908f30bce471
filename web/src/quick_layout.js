// A first drawing of a layer, to show while ELK's workers start. ELK's first layouts in a page
// are its slowest (its 1.6 MB script loaded and compiled, then its code run cold: some 250 ms of
// CPU in each worker for a page of 200 behaviours), so a page opened on a graph the browser has
// not laid out before shows this one at once and ELK's when it comes (graph.js, draw()).
//
// It places boxes as ELK's layered algorithm does with the options graph.js gives it, in the
// simple cases that most layers are: each connected group of behaviours on its own, inhibitors a
// row above what they inhibit (the longest path from a behaviour no inhibition reaches), a row's
// behaviours in execution order; the groups packed into rows as ELK packs them. For a layer whose
// inhibitions each join a behaviour to one in the next row, no two from one behaviour, it is
// ELK's layout to the pixel (a browser test checks it), and ELK's drawing moves no box. The
// inhibitions run in right angles, through the gaps between the rows, and one that skips a row
// down a lane right of its group's boxes: none crosses a box.
const NODE_GAP = 20;      // 'elk.spacing.nodeNode'
const ROW_GAP = 34;       // 'elk.layered.spacing.nodeNodeBetweenLayers'
const GROUP_GAP = 20;     // ELK's default 'elk.spacing.componentComponent'
const EDGE_GAP = 14;      // 'elk.spacing.edgeNode'
const LANE_GAP = 10;      // 'elk.spacing.edgeEdge'
const ASPECT_RATIO = 1.6;  // ELK's default 'elk.aspectRatio'

/**
 * The layout of `graph` (an ELK graph: children with width and height, edges with one source and
 * one target), in the shape of ELK's result: {width, height, children: [{id, x, y, width,
 * height}], edges: [{id, sections: [{startPoint, bendPoints, endPoint}]}]}.
 */
export function quickLayout(graph) {
  const nodes = graph.children;
  const indexOf = new Map(nodes.map((node, index) => [node.id, index]));
  const edges = graph.edges.map((edge) => ({id: edge.id, from: indexOf.get(edge.sources[0]), to: indexOf.get(edge.targets[0])}))
      .filter((edge) => edge.from !== undefined && edge.to !== undefined && edge.from !== edge.to);

  // Rows: the longest path to each behaviour, in an order that puts inhibitors first (Kahn's); a
  // cycle, which a validated config has not, leaves the rest of its behaviours in row 0.
  const row = new Array(nodes.length).fill(0);
  const into = new Array(nodes.length).fill(0);
  const outOf = nodes.map(() => []);
  for (const edge of edges) {
    ++into[edge.to];
    outOf[edge.from].push(edge.to);
  }
  const ready = [];
  for (let i = 0; i < nodes.length; ++i) if (!into[i]) ready.push(i);
  for (let next = 0; next < ready.length; ++next) {
    const from = ready[next];
    for (const to of outOf[from]) {
      row[to] = Math.max(row[to], row[from] + 1);
      if (--into[to] === 0) ready.push(to);
    }
  }

  // The connected groups, each in the execution order of its first behaviour.
  const group = nodes.map((_, i) => i);
  const find = (i) => (group[i] === i ? i : (group[i] = find(group[i])));
  for (const edge of edges) group[find(edge.from)] = find(edge.to);
  const groups = new Map();  // root -> {members, skipping: the inhibitions that skip a row}
  nodes.forEach((_, i) => {
    const root = find(i);
    if (!groups.has(root)) groups.set(root, {members: [], skipping: []});
    groups.get(root).members.push(i);
  });
  for (const edge of edges) if (row[edge.to] > row[edge.from] + 1) groups.get(find(edge.from)).skipping.push(edge);

  // Each group laid out at (0, 0): its rows stacked, each centred on the widest; an inhibition that
  // skips a row runs down a lane of its own right of the group's boxes.
  const x = new Array(nodes.length).fill(0);
  const y = new Array(nodes.length).fill(0);
  const rowBottom = new Array(nodes.length).fill(0);  // the bottom of each behaviour's row
  const lane = new Map();  // edge -> its lane's x, for those that skip a row
  const laidGroups = [...groups.values()].map(({members, skipping}) => {
    const rows = [];
    for (const i of members) (rows[row[i]] ??= []).push(i);
    const widths = rows.map((r) => r.reduce((sum, i) => sum + nodes[i].width, 0) + NODE_GAP * (r.length - 1));
    let width = Math.max(...widths);
    rows.forEach((r, k) => {
      let left = (width - widths[k]) / 2;
      for (const i of r) {
        x[i] = left;
        left += nodes[i].width + NODE_GAP;
      }
    });
    let top = 0;
    rows.forEach((r, k) => {
      if (k > 0) top += ROW_GAP;
      const height = Math.max(...r.map((i) => nodes[i].height));
      for (const i of r) {
        y[i] = top;
        rowBottom[i] = top + height;
      }
      top += height;
    });
    skipping.forEach((edge, k) => lane.set(edge, width + EDGE_GAP + LANE_GAP * k));
    if (skipping.length) width += EDGE_GAP + LANE_GAP * (skipping.length - 1);
    return {members, skipping, width, height: top};
  });

  // The groups packed left to right, the smallest first (by area; in execution order among equals),
  // into rows no wider than the aspect ratio asks of their area.
  laidGroups.sort((a, b) => a.width * a.height - b.width * b.height);
  const area = laidGroups.reduce((sum, g) => sum + g.width * g.height, 0);
  const widest = Math.max(0, ...laidGroups.map((g) => g.width));
  const maxWidth = Math.max(widest, Math.sqrt(area) * ASPECT_RATIO);
  let left = 0;
  let top = 0;
  let rowHeight = 0;
  let width = 0;
  for (const g of laidGroups) {
    if (left > 0 && left + g.width > maxWidth) {
      left = 0;
      top += rowHeight + GROUP_GAP;
      rowHeight = 0;
    }
    for (const i of g.members) {
      x[i] += left;
      y[i] += top;
      rowBottom[i] += top;
    }
    for (const edge of g.skipping) lane.set(edge, lane.get(edge) + left);
    width = Math.max(width, left + g.width);
    rowHeight = Math.max(rowHeight, g.height);
    left += g.width + GROUP_GAP;
  }

  const centre = (i) => x[i] + nodes[i].width / 2;
  return {
    id: graph.id,
    width,
    height: laidGroups.length ? top + rowHeight : 0,
    children: nodes.map((node, i) => ({id: node.id, x: x[i], y: y[i], width: node.width, height: node.height})),
    edges: edges.map((edge) => {
      const {id, from, to} = edge;
      const startPoint = {x: centre(from), y: y[from] + nodes[from].height};
      const endPoint = {x: centre(to), y: y[to]};
      const above = y[to] - ROW_GAP / 2;  // in the gap above the inhibited's row
      let bendPoints = [];
      if (lane.has(edge)) {
        const below = rowBottom[from] + ROW_GAP / 2;
        const at = lane.get(edge);
        bendPoints = [{x: startPoint.x, y: below}, {x: at, y: below}, {x: at, y: above}, {x: endPoint.x, y: above}];
      } else if (startPoint.x !== endPoint.x) {
        bendPoints = [{x: startPoint.x, y: above}, {x: endPoint.x, y: above}];
      }
      return {id, sections: [{startPoint, bendPoints, endPoint}]};
    }),
  };
}
