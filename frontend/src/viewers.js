// Viewers for values, one per kind of port (shared by the studio and report.html).
// Each takes a container element and a description (see graphvision/studio/payload.py).
import { autoRange, colourise, finiteRange, labelColour, ticks, viridis } from "./colormap.js";

const el = (tag, attrs = {}, ...children) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
};
export { el };

const OVERLAY_COLOURS = { keypoints: "#ffd000", boxes: "#00e5ff", lines: "#ff4d4d",
  circles: "#7CFC00", matches: "#ff66ff" };

// An image with zoom (wheel), pan (drag), fit (double click), the value under the cursor,
// and overlays drawn in image coordinates.
export class ImageViewer {
  constructor(container, { width, height, label = "" }) {
    this.width = width;
    this.height = height;
    this.canvas = el("canvas", { class: "gv-canvas" });
    this.status = el("div", { class: "gv-status" }, label);
    this.tools = el("div", { class: "gv-tools" });
    this.root = el("div", { class: "gv-image" }, this.tools, this.canvas, this.status);
    container.append(this.root);
    this.overlays = [];
    this.values = null;
    this.scale = 1;
    this.tx = 0;
    this.ty = 0;
    this.source = null;
    this._events();
    new ResizeObserver(() => this.resize()).observe(this.root);
  }

  setSource(source) {
    this.source = source;
    this.redraw();
  }

  // One redraw at the next frame for any number of overlays added now (a pair viewer adds
  // hundreds of lines in a few layers): the picture itself is drawn at once (setSource).
  later() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => { this.pending = false; this.redraw(); });
  }

  setValues(values, shape) {
    this.values = values;
    this.shape = shape;
  }

  addOverlay(name, kind, columns, colour = null) {
    const entry = { name, kind, columns, colour, visible: true };
    this.overlays.push(entry);
    const box = el("input", { type: "checkbox", "data-overlay": name });
    box.checked = true;
    box.addEventListener("change", () => { entry.visible = box.checked; this.redraw(); });
    const swatch = el("span", { class: "gv-swatch" });
    swatch.style.background = colour || OVERLAY_COLOURS[kind] || "#ff0";
    this.tools.append(el("label", { class: "gv-toggle" }, box, swatch, " " + name));
    this.later();
    return entry;
  }

  // A picture (canvas) drawn over the image with an opacity, toggled, with an alpha slider.
  addLayer(name, picture, alpha = 0.5) {
    const entry = { name, picture, alpha, visible: true };
    this.layers = [...(this.layers || []), entry];
    const box = el("input", { type: "checkbox", "data-layer": name });
    box.checked = true;
    box.addEventListener("change", () => { entry.visible = box.checked; this.redraw(); });
    const slider = el("input", { type: "range", min: 0, max: 1, step: 0.05, "data-alpha": name, class: "gv-alpha" });
    slider.value = alpha;
    slider.addEventListener("input", () => { entry.alpha = Number(slider.value); this.redraw(); });
    this.tools.append(el("label", { class: "gv-toggle" }, box, " " + name), el("label", { class: "gv-toggle" }, "alpha ", slider));
    this.later();
    return entry;
  }

  resize() {
    const w = this.root.clientWidth || 400;
    const h = Math.max(200, Math.min(600, Math.round((w * this.height) / this.width)));
    // the observer also reports a box that did not change size (observed, moved in the
    // page): setting the canvas's size would clear it and draw it all again for nothing
    if (this.fitted && this.canvas.width === w && this.canvas.height === h) return;
    this.canvas.width = w;
    this.canvas.height = h;
    if (!this.fitted) this.fit();
    this.redraw();
  }

  fit() {
    const w = this.canvas.width || 400, h = this.canvas.height || 300;
    this.scale = Math.min(w / this.width, h / this.height);
    this.tx = (w - this.width * this.scale) / 2;
    this.ty = (h - this.height * this.scale) / 2;
    this.fitted = true;
    this.redraw();
  }

  redraw() {
    const ctx = this.canvas.getContext("2d");
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = "#222";
    ctx.fillRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.setTransform(this.scale, 0, 0, this.scale, this.tx, this.ty);
    ctx.imageSmoothingEnabled = this.scale < 1;
    if (this.source) ctx.drawImage(this.source, 0, 0, this.width, this.height);
    for (const layer of this.layers || []) {
      if (!layer.visible) continue;
      ctx.globalAlpha = layer.alpha;
      ctx.drawImage(layer.picture, 0, 0, this.width, this.height);
      ctx.globalAlpha = 1;
    }
    for (const o of this.overlays) if (o.visible) drawOverlay(ctx, o, this.scale);
  }

  _events() {
    const c = this.canvas;
    c.addEventListener("wheel", (ev) => {
      ev.preventDefault();
      // from a quarter of the fitted size down to a pixel a sixth of the canvas wide
      const fitted = Math.min((c.width || 400) / this.width, (c.height || 300) / this.height);
      const wanted = this.scale * Math.exp(-ev.deltaY * 0.0015);
      const f = Math.min(Math.max(wanted, fitted / 4), Math.max(fitted, (c.width || 400) / 6)) / this.scale;
      const r = c.getBoundingClientRect();
      const x = ev.clientX - r.left, y = ev.clientY - r.top;
      this.tx = x - (x - this.tx) * f;
      this.ty = y - (y - this.ty) * f;
      this.scale *= f;
      this.redraw();
    }, { passive: false });
    let drag = null;
    c.addEventListener("mousedown", (ev) => { drag = [ev.clientX, ev.clientY]; });
    window.addEventListener("mouseup", () => { drag = null; });
    c.addEventListener("mousemove", (ev) => {
      if (drag) {
        this.tx += ev.clientX - drag[0];
        this.ty += ev.clientY - drag[1];
        drag = [ev.clientX, ev.clientY];
        this.redraw();
      }
      const r = c.getBoundingClientRect();
      const x = Math.floor((ev.clientX - r.left - this.tx) / this.scale);
      const y = Math.floor((ev.clientY - r.top - this.ty) / this.scale);
      this.status.textContent = this.describe(x, y);
    });
    c.addEventListener("dblclick", () => this.fit());
  }

  describe(x, y) {
    if (x < 0 || y < 0 || x >= this.width || y >= this.height) return "";
    let text = `x ${x}, y ${y}`;
    if (this.values && this.shape) {
      const ch = this.shape.length === 3 ? this.shape[2] : 1;
      const i = (y * this.width + x) * ch;
      const v = Array.from(this.values.subarray(i, i + ch), (a) => fmt(a));
      text += ` · value ${ch > 1 ? "(" + v.join(", ") + ")" : v[0]}`;
    }
    return text;
  }
}

function fmt(v) {
  if (!Number.isFinite(v)) return String(v);
  return Number.isInteger(v) ? String(v) : v.toPrecision(4);
}

export function drawOverlay(ctx, overlay, scale) {
  const c = overlay.columns;
  ctx.strokeStyle = overlay.colour || OVERLAY_COLOURS[overlay.kind] || "#ff0";
  ctx.lineWidth = 1.5 / scale;
  ctx.beginPath();
  if (overlay.kind === "keypoints") {
    c.x.forEach((x, i) => {
      const r = Math.max(2 / scale, (c.scale[i] || 1) * 1.5);
      ctx.moveTo(x + r, c.y[i]);
      ctx.arc(x, c.y[i], r, 0, 2 * Math.PI);
    });
  } else if (overlay.kind === "boxes") {
    c.x0.forEach((x0, i) => ctx.rect(x0, c.y0[i], c.x1[i] - x0, c.y1[i] - c.y0[i]));
  } else if (overlay.kind === "circles") {
    c.x.forEach((x, i) => { ctx.moveTo(x + c.radius[i], c.y[i]); ctx.arc(x, c.y[i], c.radius[i], 0, 2 * Math.PI); });
  } else if (overlay.kind === "segments") {
    c.x0.forEach((x0, i) => { ctx.moveTo(x0, c.y0[i]); ctx.lineTo(c.x1[i], c.y1[i]); });
  } else if (overlay.kind === "lines") {
    const big = 1e5;
    c.rho.forEach((rho, i) => {
      const t = c.theta[i], x0 = rho * Math.cos(t), y0 = rho * Math.sin(t);
      ctx.moveTo(x0 + big * Math.sin(t), y0 - big * Math.cos(t));
      ctx.lineTo(x0 - big * Math.sin(t), y0 + big * Math.cos(t));
    });
  }
  ctx.stroke();
  if (overlay.kind === "boxes" && c.score) {
    ctx.fillStyle = OVERLAY_COLOURS.boxes;
    ctx.font = `${12 / scale}px monospace`;
    c.x0.forEach((x0, i) => ctx.fillText(fmt(c.score[i]), x0, c.y0[i] - 2 / scale));
  }
}

// RGBA of a mask or label map (row-major values) tinted for drawing over its image:
// a mask's nonzero pixels in `colour`, a label map's labels in their distinct colours;
// the background (0) transparent.
export function tint(values, labels = false, colour = [255, 0, 0]) {
  const out = new Uint8ClampedArray(values.length * 4);
  for (let i = 0; i < values.length; i++) {
    const v = values[i];
    if (!v || !Number.isFinite(v)) continue;
    const c = labels ? labelColour(v) : colour;
    out[4 * i] = c[0];
    out[4 * i + 1] = c[1];
    out[4 * i + 2] = c[2];
    out[4 * i + 3] = 255;
  }
  return out;
}

export function canvasOf(rgba, width, height) {
  const canvas = document.createElement("canvas");
  canvas.width = width;
  canvas.height = height;
  canvas.getContext("2d").putImageData(new ImageData(rgba, width, height), 0, 0);
  return canvas;
}

// A float map through viridis with its colour bar, auto range or a fixed one.
export function floatMapViewer(container, desc, values) {
  const [h, w] = desc.shape;
  const viewer = new ImageViewer(container, { width: w, height: h, label: desc.summary });
  viewer.setValues(values, desc.shape);
  const bar = el("div", { class: "gv-colourbar" });
  const lo = el("input", { type: "number", step: "any", class: "gv-range", title: "low end" });
  const hi = el("input", { type: "number", step: "any", class: "gv-range", title: "high end" });
  const auto = el("button", { type: "button" }, "auto range");
  viewer.root.append(bar, el("div", { class: "gv-rangebox" }, "range ", lo, " – ", hi, " ", auto));
  const paint = (a, b) => {
    const canvas = document.createElement("canvas");
    canvas.width = w;
    canvas.height = h;
    canvas.getContext("2d").putImageData(new ImageData(colourise(values, a, b), w, h), 0, 0);
    viewer.setSource(canvas);
    drawColourBar(bar, a, b, `${desc.type}${desc.units ? " (" + desc.units + ")" : ""}`);
    lo.value = fmt(a);
    hi.value = fmt(b);
  };
  const [a, b] = autoRange(values);
  paint(a, b);
  const fixed = () => {  // the ends typed the wrong way round are taken the right way round
    const [a, b] = [Number(lo.value), Number(hi.value)];
    paint(Math.min(a, b), Math.max(a, b));
  };
  lo.addEventListener("change", fixed);
  hi.addEventListener("change", fixed);
  auto.addEventListener("click", () => paint(a, b));
  return viewer;
}

export function drawColourBar(container, lo, hi, title) {
  container.replaceChildren();
  const canvas = el("canvas", { width: 256, height: 12, class: "gv-bar" });
  const ctx = canvas.getContext("2d");
  for (let i = 0; i < 256; i++) {
    const [r, g, b] = viridis(i / 255);
    ctx.fillStyle = `rgb(${r},${g},${b})`;
    ctx.fillRect(i, 0, 1, 12);
  }
  const scale = el("div", { class: "gv-ticks" });
  for (const t of ticks(lo, hi)) scale.append(el("span", {}, t.text));
  container.append(el("div", { class: "gv-bartitle" }, title), canvas, scale);
}

// The colour of each point: by depth (viridis over the finite range of Z) or by the
// image's colour (`colours`, N×3 in [0, 1]); 0-255 RGB triples.
export function cloudColours(points, mode, colours = null) {
  if (mode === "image" && colours && colours.length === points.length) {
    return colours.map((c) => c.map((v) => Math.round(Math.min(1, Math.max(0, v)) * 255)));
  }
  const [zlo, zhi] = finiteRange(points.map((p) => p[2]));
  return points.map((p) => viridis((p[2] - zlo) / (zhi - zlo || 1)));
}

// A point cloud, turned by dragging, coloured by depth or by image colour (`colours`,
// N×3 in [0, 1], one per point) with a switch between the two when colours are given.
export function pointCloudViewer(container, points, colours = null) {
  const canvas = el("canvas", { width: 480, height: 360, class: "gv-cloud" });
  const tools = el("div", { class: "gv-tools" });
  const root = el("div", { class: "gv-cloudbox" }, tools, canvas, el("div", { class: "gv-status" },
    `${points.length} points · drag to turn, wheel to zoom`));
  container.append(root);
  let mode = colours ? "image" : "depth";
  let shown = cloudColours(points, mode, colours);
  if (colours) {
    const menu = el("select", { "data-cloud-colour": "1" }, el("option", { value: "image" }, "image colour"),
      el("option", { value: "depth" }, "depth"));
    menu.value = mode;
    menu.addEventListener("change", () => { mode = menu.value; shown = cloudColours(points, mode, colours); root.dataset.colour = mode; draw(); });
    tools.append(el("label", { class: "gv-toggle" }, "colour by ", menu));
  }
  root.dataset.colour = mode;
  const n = points.length;
  const mean = [0, 1, 2].map((k) => points.reduce((s, p) => s + (p[k] || 0), 0) / (n || 1));
  // the 95th percentile distance from the centre: a few far points do not shrink the rest
  const distances = points.map((p) => Math.hypot(p[0] - mean[0], p[1] - mean[1], p[2] - mean[2])).sort((a, b) => a - b);
  const radius = Math.max(1e-9, distances[Math.floor(0.95 * (distances.length - 1))] || 0);
  let yaw = 0, pitch = 0, zoom = 1;
  const draw = () => {
    const ctx = canvas.getContext("2d");
    ctx.fillStyle = "#111";
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    const s = (Math.min(canvas.width, canvas.height) / 2.2 / radius) * zoom;
    const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    const order = points.map((p, i) => {
      const x = p[0] - mean[0], y = p[1] - mean[1], z = p[2] - mean[2];
      const x1 = cy * x + sy * z, z1 = -sy * x + cy * z;
      const y1 = cp * y - sp * z1, z2 = sp * y + cp * z1;
      return [x1, y1, z2, i];
    }).sort((a, b) => b[2] - a[2]);
    for (const [x, y, , i] of order) {
      const c = shown[i];
      ctx.fillStyle = `rgb(${c[0]},${c[1]},${c[2]})`;
      ctx.fillRect(Math.round(canvas.width / 2 + x * s), Math.round(canvas.height / 2 + y * s), 2, 2);
    }
  };
  let drag = null;
  canvas.addEventListener("mousedown", (e) => { drag = [e.clientX, e.clientY]; });
  window.addEventListener("mouseup", () => { drag = null; });
  canvas.addEventListener("mousemove", (e) => {
    if (!drag) return;
    yaw += (e.clientX - drag[0]) * 0.01;
    pitch += (e.clientY - drag[1]) * 0.01;
    drag = [e.clientX, e.clientY];
    draw();
  });
  canvas.addEventListener("wheel", (e) => { e.preventDefault(); zoom *= Math.exp(-e.deltaY * 0.0015); draw(); }, { passive: false });
  draw();
  return root;
}

// A number with its history across runs, as a small line chart.
export function scalarViewer(container, value, history = []) {
  const shown = typeof value === "number" ? fmt(value) : String(value);
  container.append(el("div", { class: "gv-scalar" }, shown));
  const numbers = history.filter((h) => typeof h.value === "number");
  if (numbers.length < 2) return;
  const [lo, hi] = finiteRange(numbers.map((h) => h.value));
  const W = 240, H = 60;
  const pts = numbers.map((h, i) => {
    const x = 6 + (i * (W - 12)) / (numbers.length - 1);
    const y = H - 6 - ((h.value - lo) / (hi - lo || 1)) * (H - 12);
    return `${x.toFixed(1)},${y.toFixed(1)}`;
  });
  const svg = `<svg class="gv-history" width="${W}" height="${H}"><polyline fill="none" stroke="#3b82f6" stroke-width="1.5" points="${pts.join(" ")}"/>` +
    numbers.map((h, i) => `<circle cx="${pts[i].split(",")[0]}" cy="${pts[i].split(",")[1]}" r="2.5" fill="#3b82f6"><title>run ${h.run}: ${fmt(h.value)}</title></circle>`).join("") + "</svg>";
  const holder = el("div", { class: "gv-historybox" });
  holder.innerHTML = svg;
  container.append(el("div", { class: "gv-caption" }, `history over ${numbers.length} runs (${fmt(lo)} – ${fmt(hi)})`), holder);
}

// A table of columns (the first 200 rows). `first`: the rows made at once, the rest when
// the table is first scrolled (the studio redraws its tables at every run: a table shows
// about a dozen rows before it scrolls, and 200 rows cost its page a long layout each time).
export function tableViewer(container, columns, total, first = 200) {
  const names = Object.keys(columns);
  const rows = names.length ? columns[names[0]].length : 0;
  const table = el("table", { class: "gv-table" });
  table.append(el("tr", {}, ...names.map((n) => el("th", {}, n))));
  const shown = Math.min(rows, 200);
  const add = (from, to) => {
    for (let i = from; i < to; i++) table.append(el("tr", {}, ...names.map((n) => el("td", {}, cell(columns[n][i])))));
  };
  add(0, Math.min(shown, first));
  const box = el("div", { class: "gv-tablebox" }, table);
  if (first < shown) box.addEventListener("scroll", () => add(first, shown), { once: true });
  const note = total !== undefined && total > rows ? `${rows} of ${total} rows` : `${rows} rows`;
  container.append(el("div", { class: "gv-caption" }, note), box);
}

function cell(v) {
  if (v === null || v === undefined) return "–";
  if (typeof v === "number") return fmt(v);
  return Array.isArray(v) ? JSON.stringify(v) : String(v);
}
