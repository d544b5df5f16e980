// The laid-out pipeline drawn as SVG: pan (drag), zoom (wheel), fit, search, node states.
import { layoutGraph, LINE } from "./layout.js";

const NS = "http://www.w3.org/2000/svg";
export const STATE_COLOURS = {
  cached: "#dbeafe", queued: "#f3f4f6", running: "#fde68a", computed: "#bbf7d0",
  failed: "#fecaca", stale: "#e5e7eb", skipped: "#f5f5f4", pending: "#f3f4f6",
  superseded: "#e5e7eb", input: "#ede9fe",
};

const svgEl = (tag, attrs = {}) => {
  const e = document.createElementNS(NS, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  return e;
};

// Left to right or top to bottom: whichever the container shows larger when fitted.
function bestLayout(graph, container) {
  const w = container.clientWidth || 800, h = container.clientHeight || 600;
  const scale = (l) => Math.min(w / l.width, h / l.height);
  const across = layoutGraph(graph, { rankdir: "LR" }), down = layoutGraph(graph, { rankdir: "TB" });
  return scale(down) > scale(across) * 1.15 ? down : across;
}

export class GraphView {
  constructor(container, graph, { onSelect = () => {}, rankdir = "auto" } = {}) {
    this.graph = graph;
    this.layout = rankdir === "auto" ? bestLayout(graph, container) : layoutGraph(graph, { rankdir });
    this.onSelect = onSelect;
    this.svg = svgEl("svg", { class: "gv-graph", width: "100%", height: "100%" });
    this.view = svgEl("g");
    this.svg.append(this.view);
    container.append(this.svg);
    this.boxes = {};
    this._draw();
    this._events();
    this.view.setAttribute("transform", "translate(0,0) scale(1)");
    this.t = { x: 0, y: 0, k: 1 };
    this.touched = false; // fitted again when its box changes, until the user pans or zooms
    new ResizeObserver(() => { if (!this.touched) this.fit(); }).observe(this.svg);
  }

  _draw() {
    const defs = svgEl("defs");
    const marker = svgEl("marker", { id: "gv-arrow", viewBox: "0 0 10 10", refX: "10", refY: "5",
      markerWidth: "7", markerHeight: "7", orient: "auto-start-reverse" });
    marker.append(svgEl("path", { d: "M0,0 L10,5 L0,10 z", fill: "#6b7280" }));
    defs.append(marker);
    this.view.append(defs);
    for (const e of this.layout.edges) {
      const d = e.points.map((p, i) => `${i ? "L" : "M"}${p.x.toFixed(1)},${p.y.toFixed(1)}`).join(" ");
      this.view.append(svgEl("path", { d, class: "gv-edge", "marker-end": "url(#gv-arrow)" }));
    }
    for (const e of this.layout.edges) {
      const g = svgEl("g", { class: "gv-edge-label", "data-edge": `${e.from}->${e.to}.${e.port}` });
      g.append(svgEl("rect", { x: e.label.x, y: e.label.y, width: e.label.width, height: e.label.height, rx: 3 }));
      const t = svgEl("text", { x: e.label.x + e.label.width / 2, y: e.label.y + 11, "text-anchor": "middle" });
      t.textContent = e.label.text;
      g.append(t);
      this.view.append(g);
    }
    for (const node of this.graph.nodes) {
      const b = this.layout.nodes[node.id];
      const g = svgEl("g", { class: "gv-node", "data-node": node.id, tabindex: "0" });
      const rect = svgEl("rect", { x: b.x, y: b.y, width: b.width, height: b.height, rx: 6,
        fill: node.kind === "input" ? STATE_COLOURS.input : STATE_COLOURS.queued });
      const lines = [node.id, node.op || node.type, node.kind === "input" ? "input" : ""];
      g.append(rect);
      lines.forEach((text, i) => {
        const t = svgEl("text", { x: b.x + 10, y: b.y + 17 + i * LINE, class: i ? "gv-sub" : "gv-name" });
        t.textContent = text;
        g.append(t);
      });
      g.addEventListener("click", () => this.onSelect(node.id));
      this.view.append(g);
      this.boxes[node.id] = { g, rect, status: g.querySelectorAll("text")[2] };
    }
  }

  setState(id, state, text = state) {
    const box = this.boxes[id];
    if (!box) return;
    // only what changed: a text set again, even the same, lays the whole drawing out again
    const fill = STATE_COLOURS[state] || STATE_COLOURS.queued;
    if (box.rect.getAttribute("fill") !== fill) box.rect.setAttribute("fill", fill);
    if (box.g.dataset.state !== state) box.g.dataset.state = state;
    if (box.status.textContent !== text) box.status.textContent = text;
  }

  select(id) {
    for (const [name, box] of Object.entries(this.boxes)) box.g.classList.toggle("selected", name === id);
  }

  _apply() {
    this.view.setAttribute("transform", `translate(${this.t.x},${this.t.y}) scale(${this.t.k})`);
  }

  fit() {
    const r = this.svg.getBoundingClientRect();
    const k = Math.min(r.width / this.layout.width, r.height / this.layout.height, 1.5) || 1;
    this.t = { k, x: (r.width - this.layout.width * k) / 2, y: (r.height - this.layout.height * k) / 2 };
    this._apply();
  }

  focus(id) {
    const b = this.layout.nodes[id];
    if (!b) return false;
    const r = this.svg.getBoundingClientRect();
    this.t = { k: Math.max(this.t.k, 1), x: 0, y: 0 };
    this.t.x = r.width / 2 - (b.x + b.width / 2) * this.t.k;
    this.t.y = r.height / 2 - (b.y + b.height / 2) * this.t.k;
    this._apply();
    return true;
  }

  search(text) {
    const q = text.trim().toLowerCase();
    const found = this.graph.nodes.find((n) => n.id.toLowerCase().includes(q) ||
      (n.op || "").toLowerCase().includes(q));
    if (q && found) { this.focus(found.id); this.onSelect(found.id); }
    return found ? found.id : null;
  }

  _events() {
    this.svg.addEventListener("wheel", (ev) => {
      ev.preventDefault();
      const r = this.svg.getBoundingClientRect();
      const f = Math.exp(-ev.deltaY * 0.0015), x = ev.clientX - r.left, y = ev.clientY - r.top;
      this.touched = true;
      this.t = { k: this.t.k * f, x: x - (x - this.t.x) * f, y: y - (y - this.t.y) * f };
      this._apply();
    }, { passive: false });
    let drag = null;
    this.svg.addEventListener("mousedown", (ev) => { drag = [ev.clientX, ev.clientY]; });
    window.addEventListener("mouseup", () => { drag = null; });
    window.addEventListener("mousemove", (ev) => {
      if (!drag) return;
      this.touched = true;
      this.t.x += ev.clientX - drag[0];
      this.t.y += ev.clientY - drag[1];
      drag = [ev.clientX, ev.clientY];
      this._apply();
    });
  }
}
