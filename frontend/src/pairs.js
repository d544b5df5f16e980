// Two images side by side, with what joins them: matches (inliers and outliers in two
// colours) and epipolar lines. The geometry is pure (tested in node); the viewer is an
// ImageViewer over the pair, each kind of line an overlay that can be toggled.
import { ImageViewer } from "./viewers.js";

export const PAIR_GAP = 8; // pixels between the two images
export const MATCH_COLOURS = { inliers: "#22c55e", outliers: "#ef4444", matches: "#ff66ff",
  epipolar: "#facc15", points: "#38bdf8" };

// Segments joining matched keypoints, image b shifted right by `offset` pixels.
// all, inliers: {a: [...], b: [...]} (keypoint indices, one per match); kpA, kpB: {x, y}.
// Returns {inliers, outliers} (or {matches} when no inlier set is given), each
// {x0, y0, x1, y1} columns.
export function matchSegments(all, inliers, kpA, kpB, offset) {
  const kept = inliers ? new Set(inliers.a.map((a, k) => `${a},${inliers.b[k]}`)) : null;
  const groups = kept ? { inliers: seg(), outliers: seg() } : { matches: seg() };
  all.a.forEach((i, k) => {
    const j = all.b[k];
    if (kpA.x[i] === undefined || kpB.x[j] === undefined) return;
    const name = kept ? (kept.has(`${i},${j}`) ? "inliers" : "outliers") : "matches";
    const g = groups[name];
    g.x0.push(kpA.x[i]); g.y0.push(kpA.y[i]); g.x1.push(kpB.x[j] + offset); g.y1.push(kpB.y[j]);
  });
  return groups;
}

const seg = () => ({ x0: [], y0: [], x1: [], y1: [] });

// The epipolar line of point p: in image b, l' = F p (p in image a, toB true);
// in image a, l = Fᵀ p (p in image b). F row-major, 9 numbers. Returns [a, b, c]
// with a x + b y + c = 0.
export function epipolarLine(F, p, toB) {
  const [x, y] = p;
  if (toB) return [0, 1, 2].map((r) => F[3 * r] * x + F[3 * r + 1] * y + F[3 * r + 2]);
  return [0, 1, 2].map((c) => F[c] * x + F[3 + c] * y + F[6 + c]);
}

// The part of line [a, b, c] inside the image [0, w] × [0, h], or null.
export function clipLine([a, b, c], w, h) {
  const found = [];
  const add = (x, y) => {
    if (x >= -1e-9 && x <= w + 1e-9 && y >= -1e-9 && y <= h + 1e-9 &&
      !found.some(([u, v]) => Math.abs(u - x) < 1e-9 && Math.abs(v - y) < 1e-9)) found.push([x, y]);
  };
  if (Math.abs(b) > 1e-12) { add(0, -c / b); add(w, -(c + a * w) / b); }
  if (Math.abs(a) > 1e-12) { add(-c / a, 0); add(-(c + b * h) / a, h); }
  return found.length >= 2 ? [found[0], found[1]] : null;
}

// At most `most` items of `list`, evenly spread (all when there are fewer).
export function spread(list, most) {
  if (list.length <= most) return list;
  return Array.from({ length: most }, (_, i) => list[Math.floor((i * list.length) / most)]);
}

// Epipolar lines of the points of each view (at most `most`, evenly spread) drawn in the
// other view of the pair (image b shifted right by `offset`): {inB, inA} segments, and
// the points themselves.
export function epipolarSegments(F, allA, allB, sizeA, sizeB, offset, most = 30) {
  const inB = seg(), inA = seg(), points = { x: [], y: [], scale: [] };
  const pointsA = spread(allA, most), pointsB = spread(allB, most);
  const push = (g, s, dx) => { g.x0.push(s[0][0] + dx); g.y0.push(s[0][1]); g.x1.push(s[1][0] + dx); g.y1.push(s[1][1]); };
  for (const p of pointsA) {
    const s = clipLine(epipolarLine(F, p, true), sizeB[0], sizeB[1]);
    if (s) push(inB, s, offset);
    points.x.push(p[0]); points.y.push(p[1]); points.scale.push(1);
  }
  for (const p of pointsB) {
    const s = clipLine(epipolarLine(F, p, false), sizeA[0], sizeA[1]);
    if (s) push(inA, s, 0);
    points.x.push(p[0] + offset); points.y.push(p[1]); points.scale.push(1);
  }
  return { inB, inA, points };
}

// One canvas holding image a and image b side by side (each a canvas or null). The same
// two pictures (a run's images, fetched once per cache key) give the same canvas: a
// repaint of the matches for every change of a parameter does not compose it again.
const composed = new WeakMap();
export function sideBySide(a, b) {
  if (!a || !b) return compose(a, b);
  if (!composed.has(a)) composed.set(a, new WeakMap());
  const byB = composed.get(a);
  if (!byB.has(b)) byB.set(b, compose(a, b));
  return byB.get(b);
}

function compose(a, b) {
  const wa = a ? a.width : 0, wb = b ? b.width : 0;
  const canvas = document.createElement("canvas");
  canvas.width = wa + PAIR_GAP + wb;
  canvas.height = Math.max(a ? a.height : 0, b ? b.height : 0, 1);
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "#222";
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  if (a) ctx.drawImage(a, 0, 0);
  if (b) ctx.drawImage(b, wa + PAIR_GAP, 0);
  return canvas;
}

// A viewer of the pair with its overlays: `layers` {name: [kind, columns, colour]}.
export function pairViewer(container, a, b, layers, label = "") {
  const both = sideBySide(a, b);
  const viewer = new ImageViewer(container, { width: both.width, height: both.height, label });
  viewer.root.classList.add("gv-pair");
  viewer.setSource(both);
  for (const [name, [kind, columns, colour]] of Object.entries(layers)) {
    viewer.addOverlay(name, kind, columns, colour);
  }
  return viewer;
}
