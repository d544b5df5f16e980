// The report's graph laid out by the studio's layout (dagre), as a static SVG whose viewBox
// report.html's own zoom and fit drive. Built by build.mjs into graphvision/views/static/
// (window.GraphvisionGraph) and inlined in each report: no network.
import { LINE, layoutGraph } from "./layout.js";

const NS = "http://www.w3.org/2000/svg";
export const STATUS_FILL = { computed: "#bbf7d0", cached: "#dbeafe", failed: "#fecaca",
  skipped: "#f5f5f4", input: "#ede9fe" };

const svgEl = (tag, attrs = {}, text) => {
  const e = document.createElementNS(NS, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
};

// graph: {nodes: [{id, kind, op|type, status, seconds}], edges: [{from, from_port, to, port}]}.
// Left to right or top to bottom: whichever shows larger in a width × height box.
export function reportSvg(graph, width = 1100, height = 660) {
  const across = layoutGraph(graph, { rankdir: "LR" });
  const down = layoutGraph(graph, { rankdir: "TB" });
  const scale = (l) => Math.min(width / l.width, height / l.height);
  const layout = scale(down) > scale(across) * 1.15 ? down : across;
  const svg = svgEl("svg", { viewBox: `0 0 ${layout.width} ${layout.height}`, "data-layout": "dagre",
    preserveAspectRatio: "xMidYMid meet", style: `max-width: ${Math.ceil(layout.width)}px`,
    role: "img", "aria-label": "the pipeline's graph" });
  const defs = svgEl("defs");
  const marker = svgEl("marker", { id: "gvr-arrow", viewBox: "0 0 10 10", refX: "10", refY: "5",
    markerWidth: "7", markerHeight: "7", orient: "auto-start-reverse" });
  marker.append(svgEl("path", { d: "M0,0 L10,5 L0,10 z", fill: "#6b7280" }));
  defs.append(marker);
  svg.append(defs);
  for (const e of layout.edges) {
    const d = e.points.map((p, i) => `${i ? "L" : "M"}${p.x.toFixed(1)},${p.y.toFixed(1)}`).join(" ");
    svg.append(svgEl("path", { d, fill: "none", stroke: "#9ca3af", "stroke-width": 1.3, "marker-end": "url(#gvr-arrow)" }));
  }
  for (const e of layout.edges) {
    const g = svgEl("g", { class: "edge-label" });
    g.append(svgEl("rect", { x: e.label.x, y: e.label.y, width: e.label.width, height: e.label.height, fill: "#fff", opacity: 0.9 }));
    g.append(svgEl("text", { x: e.label.x + e.label.width / 2, y: e.label.y + 11, "text-anchor": "middle",
      "font-size": 10, "font-family": "monospace", fill: "#4b5563" }, e.label.text));
    svg.append(g);
  }
  for (const node of graph.nodes) {
    const b = layout.nodes[node.id];
    const status = node.kind === "input" ? "input" : node.status || "";
    const g = svgEl("g", { class: "node", "data-node": node.id, "data-status": status });
    g.append(svgEl("rect", { x: b.x, y: b.y, width: b.width, height: b.height, rx: 6,
      fill: STATUS_FILL[status] || "#f3f4f6", stroke: "#6b7280" }));
    const time = node.seconds !== undefined && node.seconds !== null ? ` ${node.seconds.toFixed(node.seconds < 10 ? 2 : 1)} s` : "";
    [node.id, node.op || node.type || "", status + time].forEach((text, i) => {
      g.append(svgEl("text", { x: b.x + 10, y: b.y + 17 + i * LINE, "font-size": 12, "font-family": "monospace",
        "font-weight": i ? "normal" : "bold", fill: i ? "#374151" : "#111" }, text));
    });
    svg.append(g);
  }
  return svg;
}

// Every `.graph` box of the page with its graph's data: its drawn SVG replaced by the
// laid-out one.
export function layOutPage(root = document) {
  for (const box of root.querySelectorAll(".graph")) {
    const data = box.querySelector("script[data-graph]");
    const old = box.querySelector("svg");
    if (!data || !old || old.dataset.layout) continue;
    const width = box.clientWidth || 1100, height = 0.75 * (window.innerHeight || 880);
    old.replaceWith(reportSvg(JSON.parse(data.textContent), width, height));
  }
}
