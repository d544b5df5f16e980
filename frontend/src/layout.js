// Layered layout of a pipeline graph (dagre: Sugiyama-style ranks, crossing reduction,
// coordinate assignment). Pure: graph JSON in, boxes and edge routes out; no DOM.
import dagre from "@dagrejs/dagre";

export const CHAR = 7.4; // width of one character of the 12 px monospace node font
export const LINE = 16; // height of one line of text in a node box

// The size of a node's box: its name, its op (or input type), a status line.
export function nodeSize(node) {
  const lines = [node.id, node.op || node.type || "", "computed 000.0 s"];
  const longest = Math.max(...lines.map((t) => t.length));
  return { width: Math.ceil(longest * CHAR + 20), height: 3 * LINE + 10 };
}

// The size of an edge's label (the port it feeds, and the port it comes from).
export function edgeLabel(edge) {
  const from = edge.from_port && edge.from_port !== "out" ? edge.from_port + "→" : "";
  return from + edge.port;
}

export function layoutGraph(graph, options = {}) {
  const g = new dagre.graphlib.Graph({ multigraph: true });
  g.setGraph({
    rankdir: options.rankdir || "LR",
    nodesep: 18,
    ranksep: 46,
    edgesep: 10,
    marginx: 12,
    marginy: 12,
  });
  g.setDefaultEdgeLabel(() => ({}));
  for (const node of graph.nodes) g.setNode(node.id, { ...nodeSize(node) });
  graph.edges.forEach((edge, i) => {
    const text = edgeLabel(edge);
    g.setEdge(edge.from, edge.to, {
      width: Math.ceil(text.length * 6.2 + 6),
      height: 14,
      labelpos: "c",
      minlen: 1,
      text,
    }, "e" + i);
  });
  dagre.layout(g);
  const nodes = {};
  for (const id of g.nodes()) {
    const n = g.node(id);
    nodes[id] = { x: n.x - n.width / 2, y: n.y - n.height / 2, width: n.width, height: n.height };
  }
  const edges = graph.edges.map((edge, i) => {
    const e = g.edge(edge.from, edge.to, "e" + i);
    return {
      ...edge,
      points: e.points,
      label: { text: e.text, x: e.x - e.width / 2, y: e.y - e.height / 2, width: e.width,
               height: e.height },
    };
  });
  const size = g.graph();
  return { nodes, edges, width: size.width, height: size.height };
}

// Pairs of boxes that overlap (for tests): [{a, b}] by the keys of `boxes`.
export function overlaps(boxes) {
  const names = Object.keys(boxes);
  const found = [];
  for (let i = 0; i < names.length; i++) {
    for (let j = i + 1; j < names.length; j++) {
      const a = boxes[names[i]], b = boxes[names[j]];
      if (a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height &&
          b.y < a.y + a.height) {
        found.push({ a: names[i], b: names[j] });
      }
    }
  }
  return found;
}

// Node names downstream of `start` (itself included), from the graph's edges.
export function downstream(graph, start) {
  const seen = new Set([start]);
  const queue = [start];
  while (queue.length) {
    const here = queue.shift();
    for (const e of graph.edges) {
      if (e.from === here && !seen.has(e.to)) {
        seen.add(e.to);
        queue.push(e.to);
      }
    }
  }
  return seen;
}
