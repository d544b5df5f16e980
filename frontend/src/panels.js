// Viewers that draw a value with others of the same run (see graphvision/views/pairing.py):
// matches over their image pair, epipolar lines, masks tinted over their image, clouds in
// their image's colours, a classifier's confusion matrix and samples, training curves.
// `source` fetches a run's values: {value(node, port) → description or null,
// raw(node, port) → {values, shape} or null, picture(node, port) → canvas or null}.
import { confusionViewer, curvesViewer, samplesRow } from "./charts.js";
import { MATCH_COLOURS, PAIR_GAP, epipolarSegments, matchSegments, pairViewer } from "./pairs.js";
import { canvasOf, el, pointCloudViewer, tint } from "./viewers.js";

const sameRef = (r, node, port) => r && r[0] === node && r[1] === port;
const indices = (d) => ({ a: d.columns.a, b: d.columns.b });

export async function matchesPanel(container, d, source) {
  const p = d.pair;
  const [all, inliers, kpA, kpB, imA, imB] = await Promise.all([
    sameRef(p.all, d.node, d.port) ? d : source.value(...p.all),
    !p.inliers ? null : sameRef(p.inliers, d.node, d.port) ? d : source.value(...p.inliers),
    source.value(...p.a.keypoints), source.value(...p.b.keypoints),
    p.a.image ? source.picture(...p.a.image) : null, p.b.image ? source.picture(...p.b.image) : null,
  ]);
  if (!all || !kpA || !kpB) return null;
  const offset = (imA ? imA.width : Math.max(...kpA.columns.x, 0) + 1) + PAIR_GAP;
  const groups = matchSegments(indices(all), inliers ? indices(inliers) : null, kpA.columns, kpB.columns, offset);
  const layers = {};
  for (const [name, columns] of Object.entries(groups)) {
    layers[`${name} (${columns.x0.length})`] = ["segments", columns, MATCH_COLOURS[name]];
  }
  const where = `${p.a.image?.[0] ?? "?"} | ${p.b.image?.[0] ?? "?"}`;
  const viewer = pairViewer(container, imA, imB, layers, `matches over ${where}`);
  viewer.root.dataset.matches = JSON.stringify(Object.fromEntries(Object.entries(groups).map(([k, v]) => [k, v.x0.length])));
  return viewer;
}

export async function epipolarPanel(container, d, source) {
  const p = d.pair;
  const [ra, rb, imA, imB] = await Promise.all([source.raw(...p.a.points), source.raw(...p.b.points),
    source.picture(...p.a.image), source.picture(...p.b.image)]);
  if (!ra || !rb || !imA || !imB) return null;
  const rows = (r) => Array.from({ length: r.shape[0] }, (_, i) => [r.values[2 * i], r.values[2 * i + 1]]);
  const offset = imA.width + PAIR_GAP;
  const found = epipolarSegments(d.value, rows(ra), rows(rb), [imA.width, imA.height], [imB.width, imB.height], offset);
  const viewer = pairViewer(container, imA, imB, {
    [`epipolar lines in ${p.b.image[0]} (${found.inB.x0.length} of ${ra.shape[0]})`]: ["segments", found.inB, MATCH_COLOURS.epipolar],
    [`epipolar lines in ${p.a.image[0]} (${found.inA.x0.length} of ${rb.shape[0]})`]: ["segments", found.inA, "#fb923c"],
    [`points (${found.points.x.length})`]: ["keypoints", found.points, MATCH_COLOURS.points],
  }, `epipolar lines of ${p.a.points.join(".")} and ${p.b.points.join(".")}`);
  viewer.root.dataset.epipolar = String(found.inB.x0.length + found.inA.x0.length);
  return viewer;
}

// The mask (or label map) tinted over its image, with a toggle and an alpha slider.
export async function maskLayer(viewer, d, source) {
  const [base, raw] = await Promise.all([source.picture(...d.over), source.raw(d.node, d.port)]);
  if (!base || !raw || base.width !== d.shape[1] || base.height !== d.shape[0]) return false;
  viewer.setSource(base);
  const picture = canvasOf(tint(raw.values, d.view === "labels"), d.shape[1], d.shape[0]);
  viewer.addLayer(`${d.view} over ${d.over[0]}`, picture, 0.5);
  return true;
}

export async function cloudPanel(container, d, source) {
  let colours = null;
  if (d.colours) {
    const raw = await source.raw(...d.colours);
    if (raw) {
      const step = d.step || 1;
      colours = [];
      for (let i = 0; i < raw.shape[0]; i += step) colours.push([raw.values[3 * i], raw.values[3 * i + 1], raw.values[3 * i + 2]]);
    }
  }
  return pointCloudViewer(container, d.points, colours);
}

export async function classifierPanel(container, d, source) {
  confusionViewer(container, d.confusion);
  const samples = d.samples ? await source.value(...d.samples) : null;
  if (samples && samples.pixels) {
    samplesRow(container, `right: the first ${d.right.length} (true → predicted)`, samples, d.right, true);
    samplesRow(container, `wrong: the first ${d.wrong.length} (true → predicted)`, samples, d.wrong, false);
  } else if (d.wrong.length) {
    container.append(el("div", { class: "gv-caption" },
      `wrong rows (row: true → predicted): ${d.wrong.map(([i, a, b]) => `${i}: ${a} → ${b}`).join(", ")}`));
  }
}

export function curvesPanel(container, d) {
  container.append(el("div", { class: "gv-caption" }, "training curves"));
  return curvesViewer(container, d.curves);
}
