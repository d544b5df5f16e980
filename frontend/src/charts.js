// A classifier's confusion matrix and right and wrong samples, and a trained network's
// training curves (loss and accuracy per epoch, with axes and their labels).
import { el } from "./viewers.js";

// Rows of a confusion matrix with each cell's share of its row (0 when the row is empty),
// and the count and share of right predictions (the diagonal).
export function confusionShares(counts) {
  const rows = counts.map((row) => {
    const total = row.reduce((a, b) => a + b, 0);
    return row.map((v) => (total ? v / total : 0));
  });
  const all = counts.flat().reduce((a, b) => a + b, 0);
  const right = counts.reduce((s, row, i) => s + (row[i] || 0), 0);
  return { rows, right, total: all, accuracy: all ? right / all : 0 };
}

export function confusionViewer(container, { classes, counts }) {
  const { rows, right, total, accuracy } = confusionShares(counts);
  const table = el("table", { class: "gv-confusion" });
  table.append(el("caption", {}, `confusion matrix: ${right} of ${total} right (${(100 * accuracy).toFixed(1)} %); rows true, columns predicted`));
  table.append(el("tr", {}, el("th", {}, "true \\ predicted"), ...classes.map((c) => el("th", {}, String(c)))));
  counts.forEach((row, i) => {
    table.append(el("tr", {}, el("th", {}, String(classes[i])), ...row.map((v, j) => {
      const td = el("td", { class: i === j ? "right" : "wrong" }, String(v));
      const rgb = i === j ? "46,125,50" : "183,28,28";
      td.style.background = `rgba(${rgb},${(rows[i][j] * 0.6).toFixed(3)})`;
      return td;
    })));
  });
  container.append(table);
  return table;
}

// A row of samples (items [row, label, predicted]), each framed green when right, red when
// wrong, captioned "true → predicted". samples: {side: [h, w], pixels: flat [0, 1]}.
export function samplesRow(container, title, samples, items, right) {
  const row = el("div", { class: "gv-samples", "data-samples": right ? "right" : "wrong" });
  const [h, w] = samples.side;
  for (const [i, label, guess] of items) {
    if ((i + 1) * h * w > samples.pixels.length) continue;
    const rgba = new Uint8ClampedArray(h * w * 4);
    for (let k = 0; k < h * w; k++) {
      const v = Math.round(samples.pixels[i * h * w + k] * 255);
      rgba[4 * k] = rgba[4 * k + 1] = rgba[4 * k + 2] = v;
      rgba[4 * k + 3] = 255;
    }
    const canvas = el("canvas", { width: w, height: h, class: right ? "gv-right" : "gv-wrong" });
    canvas.getContext("2d").putImageData(new ImageData(rgba, w, h), 0, 0);
    row.append(el("figure", {}, canvas, el("figcaption", {}, `${label} → ${guess}`)));
  }
  container.append(el("div", { class: "gv-caption" }, title), row);
  return row;
}

// "Nice" axis ticks: about n round numbers covering [lo, hi].
export function niceTicks(lo, hi, n = 5) {
  if (!(hi > lo)) return [lo];
  const raw = (hi - lo) / n;
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => (hi - lo) / s <= n + 0.5);
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Number(v.toPrecision(12)));
  return out;
}

// Training curves: one chart per quantity (loss, accuracy) against the epoch, with axes,
// ticks and labels. curves: {loss: [...], accuracy: [...]} (one value per epoch), or a
// quantity of several series drawn together with a legend: {accuracy: {training: [...],
// "held out": [...]}}.
export function curvesViewer(container, curves) {
  const box = el("div", { class: "gv-curves" });
  for (const [name, values] of Object.entries(curves)) {
    const series = Array.isArray(values) ? { [name]: values } : Object.fromEntries(
      Object.entries(values || {}).filter(([, v]) => Array.isArray(v) && v.length));
    if (!Object.values(series).some((v) => v && v.length)) continue;
    box.append(curveSvg(name, series, !Array.isArray(values)));
  }
  container.append(box);
  return box;
}

// the first series of a quantity in the colour the studio always drew it in
const seriesColour = (quantity, i) => (quantity === "accuracy"
  ? ["#16a34a", "#ea580c", "#9333ea", "#2563eb"] : ["#2563eb", "#ea580c", "#9333ea", "#16a34a"])[i % 4];

function curveSvg(name, series, legend) {
  const all = Object.values(series);
  const rows = legend ? all.length : 0; // a legend row per series under the axis's label
  const W = 300, H = 170 + 14 * rows, L = 50, R = 10, T = 20, B = 38 + 14 * rows;
  const finite = all.flat().filter((v) => Number.isFinite(v));
  let lo = Math.min(...finite), hi = Math.max(...finite);
  if (name === "accuracy") { lo = Math.min(lo, 0); hi = Math.max(hi, 1); }
  if (!(hi > lo)) { hi = lo + 1; }
  const n = Math.max(...all.map((v) => v.length));
  const x = (i) => L + (n > 1 ? ((i - 1) * (W - L - R)) / (n - 1) : (W - L - R) / 2);
  const y = (v) => T + (H - T - B) * (1 - (v - lo) / (hi - lo));
  const NS = "http://www.w3.org/2000/svg";
  const svg = document.createElementNS(NS, "svg");
  svg.setAttribute("width", W);
  svg.setAttribute("height", H);
  svg.setAttribute("class", "gv-curve");
  svg.dataset.curve = name;
  const add = (tag, attrs, text) => {
    const e = document.createElementNS(NS, tag);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
    if (text !== undefined) e.textContent = text;
    svg.append(e);
    return e;
  };
  add("line", { x1: L, y1: H - B, x2: W - R, y2: H - B, stroke: "#444" });
  add("line", { x1: L, y1: T, x2: L, y2: H - B, stroke: "#444" });
  for (const t of niceTicks(lo, hi, 4)) {
    add("line", { x1: L - 4, y1: y(t), x2: L, y2: y(t), stroke: "#444" });
    add("text", { x: L - 6, y: y(t) + 3, "text-anchor": "end", "font-size": 10 }, String(t));
  }
  for (const t of niceTicks(1, n, Math.min(n - 1 || 1, 6)).filter((t) => Number.isInteger(t))) {
    add("line", { x1: x(t), y1: H - B, x2: x(t), y2: H - B + 4, stroke: "#444" });
    add("text", { x: x(t), y: H - B + 14, "text-anchor": "middle", "font-size": 10 }, String(t));
  }
  add("text", { x: (L + W - R) / 2, y: legend ? H - B + 28 : H - 4, "text-anchor": "middle", "font-size": 11, class: "gv-axis-x" }, "epoch");
  add("text", { x: 12, y: (T + H - B) / 2, "text-anchor": "middle", "font-size": 11, class: "gv-axis-y",
    transform: `rotate(-90 12 ${(T + H - B) / 2})` }, name);
  const last = (values) => Number(values[values.length - 1]).toPrecision(4);
  const title = legend ? `${name} per epoch` : `${name} per epoch (last ${last(all[0])})`;
  add("text", { x: L, y: 12, "font-size": 11, "font-weight": "bold" }, title);
  Object.entries(series).forEach(([label, values], k) => {
    const colour = seriesColour(name, k);
    const drawn = values.map((v, i) => [i + 1, v]).filter(([, v]) => Number.isFinite(v));
    const pts = drawn.map(([i, v]) => `${x(i).toFixed(1)},${y(v).toFixed(1)}`).join(" ");
    add("polyline", { points: pts, fill: "none", stroke: colour, "stroke-width": 1.8, "data-series": label });
    drawn.forEach(([i, v]) => add("circle", { cx: x(i), cy: y(v), r: 2.5, fill: colour }));
    if (legend) { // under the axis's label: never over a curve
      const ly = H - B + 30 + 14 * (k + 1);
      add("line", { x1: L, y1: ly - 3, x2: L + 14, y2: ly - 3, stroke: colour, "stroke-width": 2 });
      add("text", { x: L + 18, y: ly, "font-size": 10, class: "gv-legend", "data-last": last(values) }, label);
      add("text", { x: L + 90, y: ly, "font-size": 10, fill: "#4b5563" }, `last ${last(values)}`);
    }
  });
  return svg;
}
