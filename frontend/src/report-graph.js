// The report's script: its graph laid out by the studio's layout (dagre), as a static SVG
// whose viewBox report.html's own zoom and fit drive, and its values drawn by the studio's
// viewers (viewers.js, pairs.js, charts.js, colormap.js, composed by panels.js) from the
// data the page holds (graphvision/views/scripted.py): images, float maps, label maps and
// masks too, with zoom to single pixels and the value under the cursor. Built by build.mjs into
// graphvision/views/static/graph.js (window.GraphvisionGraph) and inlined in each report:
// no network.
import { LINE, layoutGraph } from "./layout.js";
import { classifierPanel, cloudPanel, curvesPanel, epipolarPanel, maskLayer, matchesPanel } from "./panels.js";
import { ImageViewer, canvasOf, el, floatMapViewer, tint } from "./viewers.js";

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

// The report's values as the studio's viewers fetch a run's (panels.js `source`), from
// the page's JSON: {values: {"node.port": description}, raw: {"node.port": {dtype, shape,
// deflate}}, pictures: {"node.port": PNG data URL}}.
export function pageSource(data) {
  const pictures = new Map();
  const key = (node, port) => `${node}.${port}`;
  return {
    value: async (node, port) => data.values[key(node, port)] ?? null,
    raw: async (node, port) => decodeRaw(data.raw[key(node, port)]),
    picture: (node, port) => {
      const k = key(node, port);
      if (!pictures.has(k)) pictures.set(k, data.pictures[k] ? loadPicture(data.pictures[k]) : Promise.resolve(null));
      return pictures.get(k);
    },
  };
}

const ARRAYS = { uint8: Uint8Array, uint16: Uint16Array, int32: Int32Array, float32: Float32Array };

// An array of the page: base64 of its little-endian bytes, deflated (zlib). `planes`: the
// bytes were sent plane by plane (every value's first byte, then every second...);
// `scale`: codes standing for the real values offset + code / scale (an 8-bit image's
// levels: byte / 255; a float map's 16-bit codes over its range), the code `nan` for NaN.
export async function decodeRaw(entry) {
  if (!entry || !ARRAYS[entry.dtype]) return null;
  const packed = Uint8Array.from(atob(entry.deflate), (c) => c.charCodeAt(0));
  const stream = new Blob([packed]).stream().pipeThrough(new DecompressionStream("deflate"));
  let bytes = new Uint8Array(await new Response(stream).arrayBuffer());
  if (entry.planes) {
    const k = entry.planes, n = bytes.length / k, joined = new Uint8Array(bytes.length);
    for (let p = 0; p < k; p++) for (let i = 0; i < n; i++) joined[i * k + p] = bytes[p * n + i];
    bytes = joined;
  }
  const values = new ARRAYS[entry.dtype](bytes.buffer);
  if (!entry.scale) return { values, shape: entry.shape };
  const offset = entry.offset ?? 0, scale = entry.scale, nan = entry.nan;
  return { values: Float32Array.from(values, (v) => (v === nan ? NaN : offset + v / scale)), shape: entry.shape };
}

// RGBA of an image's values in [0, 1] (gray H×W or RGB H×W×3).
export function imageRgba(values, shape) {
  const n = shape[0] * shape[1], ch = shape.length === 3 ? shape[2] : 1;
  const out = new Uint8ClampedArray(4 * n);
  for (let i = 0; i < n; i++) {
    for (let k = 0; k < 3; k++) out[4 * i + k] = Math.round(255 * values[i * ch + (ch === 3 ? k : 0)]);
    out[4 * i + 3] = 255;
  }
  return out;
}

// The cursor of a map sent reduced (every `step`-th pixel) names the full map's pixel, and
// the page says that it was reduced.
function fullPixels(viewer, d, container) {
  if (!(d.step > 1)) return;
  const own = viewer.describe.bind(viewer);
  viewer.describe = (x, y) => own(x, y).replace(`x ${x}, y ${y}`, `x ${x * d.step}, y ${y * d.step}`);
  const nth = d.step === 2 ? "2nd" : d.step === 3 ? "3rd" : `${d.step}th`;
  container.append(el("div", { class: "gv-caption", "data-reduced": String(d.step) },
    `sent reduced: every ${nth} pixel on each axis (${d.shape[1]}×${d.shape[0]} of ${d.full[1]}×${d.full[0]}); ` +
    "x, y under the cursor are the full map's, the output's file has every pixel"));
}

// An image, float map, label map or mask with its values: zoom and pan to single pixels
// and the value under the cursor; a float map through viridis with its colour bar and
// range box, a label map in distinct colours, a mask white.
export async function mapPanel(container, d, source) {
  const raw = await source.raw(d.node, d.port);
  if (!raw) return false;
  const [h, w] = raw.shape;
  let viewer;
  if (d.view === "floatmap") {
    viewer = floatMapViewer(container, { ...d, shape: raw.shape }, raw.values);
  } else {
    viewer = new ImageViewer(container, { width: w, height: h, label: d.summary });
    const rgba = d.view === "image" ? imageRgba(raw.values, raw.shape) : tint(raw.values, d.view === "labels", [255, 255, 255]);
    viewer.setSource(canvasOf(rgba, w, h));
    viewer.setValues(raw.values, raw.shape);
  }
  viewer.root.dataset.map = d.view;
  fullPixels(viewer, d, container);
  return true;
}

async function loadPicture(url) {
  const image = new Image();
  image.src = url;
  await image.decode();
  const canvas = document.createElement("canvas");
  canvas.width = image.naturalWidth;
  canvas.height = image.naturalHeight;
  canvas.getContext("2d").drawImage(image, 0, 0);
  return canvas;
}

// One value's box: drawn by the viewer the studio draws it with; true when drawn.
export async function drawValue(box, d, source) {
  const drawn = el("div", { class: "gv-drawn" });
  let done = false;
  if ((d.view === "mask" || d.view === "labels") && d.over) {
    const viewer = new ImageViewer(drawn, { width: d.shape[1], height: d.shape[0], label: d.summary });
    box.prepend(drawn); // the viewer sizes its canvas to its box: in the page first
    done = await maskLayer(viewer, d, source);
    if (done) {
      viewer.setValues((await source.raw(d.node, d.port)).values, d.shape);
      fullPixels(viewer, d, drawn);
    }
  } else if (d.view === "mask" || d.view === "labels" || d.view === "image" || d.view === "floatmap") {
    box.prepend(drawn);
    done = await mapPanel(drawn, d, source);
  } else if (d.view === "table" && d.confusion) {
    await classifierPanel(drawn, d, source);
    done = true;
  } else if (d.view === "matches" || d.view === "fundamental") {
    box.prepend(drawn);
    done = !!(await (d.view === "matches" ? matchesPanel : epipolarPanel)(drawn, d, source));
  } else if (d.view === "points3d") {
    const raw = await source.raw(d.node, d.port);
    if (raw) {
      const points = Array.from({ length: raw.shape[0] }, (_, i) => Array.from(raw.values.subarray(3 * i, 3 * i + 3)));
      await cloudPanel(drawn, { ...d, points }, source);
      done = true;
    }
  } else if (d.curves) {
    curvesPanel(drawn, d);
    done = true;
  }
  if (!done) { drawn.remove(); return false; }
  if (d.keep) { box.append(drawn); box.dataset.keep = "1"; } else if (!drawn.parentNode) box.prepend(drawn);
  box.dataset.drawn = d.view;
  return true;
}

// Every value box of the page drawn from the JSON that follows it (a notebook may hold
// several reports, each with its own).
export async function showValues(root = document) {
  const stores = [...root.querySelectorAll("script[data-values]")];
  const boxes = [...root.querySelectorAll(".gv-view")];
  for (const store of stores) {
    const data = JSON.parse(store.textContent);
    const source = pageSource(data);
    const mine = boxes.filter((b) => !b.dataset.seen && (b.compareDocumentPosition(store) & Node.DOCUMENT_POSITION_FOLLOWING));
    await Promise.all(mine.map(async (box) => {
      box.dataset.seen = "1";
      const d = data.values[box.dataset.view];
      try {
        if (d && !(await drawValue(box, d, source))) box.dataset.skipped = "1";
      } catch (error) { // the page's own drawing stays
        box.dataset.error = String(error);
      }
    }));
  }
  document.documentElement.dataset.valuesShown = "1";
}
