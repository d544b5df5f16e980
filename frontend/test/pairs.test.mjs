// Matches, epipolar lines, cloud colours, confusion shares and axis ticks, on the built
// bundle (what ships): node --test test/
import { test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";

const bundle = readFileSync(new URL("../../graphvision/studio/static/viewers.js", import.meta.url), "utf8");
// eslint-disable-next-line no-new-func -- the bundle is an IIFE script defining one global
const V = new Function(`${bundle}\nreturn GraphvisionViewers;`)();

test("matches split into inliers and outliers, image b shifted right by the offset", () => {
  const kpA = { x: [1, 2, 3], y: [10, 20, 30] }, kpB = { x: [5, 6, 7], y: [50, 60, 70] };
  const all = { a: [0, 1, 2], b: [2, 0, 1] };
  const inliers = { a: [0, 2], b: [2, 1] };
  const g = V.matchSegments(all, inliers, kpA, kpB, 100);
  assert.deepEqual(g.inliers, { x0: [1, 3], y0: [10, 30], x1: [107, 106], y1: [70, 60] });
  assert.deepEqual(g.outliers, { x0: [2], y0: [20], x1: [105], y1: [50] });
  assert.deepEqual(Object.keys(V.matchSegments(all, null, kpA, kpB, 0)), ["matches"]);
});

test("epipolar lines: x_bᵀ F x_a = 0 for a point on the line, both ways", () => {
  // a pure horizontal translation: F = [t]x with t = (1, 0, 0): lines are rows y = y_a
  const F = [0, 0, 0, 0, 0, -1, 0, 1, 0];
  const inB = V.epipolarLine(F, [12, 34], true);
  assert.ok(Math.abs(inB[0] * 99 + inB[1] * 34 + inB[2]) < 1e-12);
  const inA = V.epipolarLine(F, [5, 7], false);
  assert.ok(Math.abs(inA[0] * 3 + inA[1] * 7 + inA[2]) < 1e-12);
  // a general F built by the test: F = [e']x A; a point x_a and x_b = A x_a + k e' satisfy it
  const F2 = [0, -1, 2, 1, 0, -3, -2, 3, 0].map((v, i) => v); // [e']x with e' = (3, 2, 1), A = I
  const xa = [4, 5], xb = [4 + 3 * 2, 5 + 2 * 2]; // A x_a + 2 e' (in homogeneous: w = 1 + 2)
  const l = V.epipolarLine(F2, xa, true);
  assert.ok(Math.abs(l[0] * xb[0] + l[1] * xb[1] + l[2] * 3) < 1e-9);
});

test("a line is clipped to the image rectangle", () => {
  assert.deepEqual(V.clipLine([0, 1, -5], 10, 8), [[0, 5], [10, 5]]);
  const diag = V.clipLine([1, -1, 0], 10, 10);
  assert.deepEqual(diag, [[0, 0], [10, 10]]);
  assert.equal(V.clipLine([0, 1, -50], 10, 8), null);
});

test("cloud colours: image colours as 0-255, or viridis over Z", () => {
  const points = [[0, 0, 1], [0, 0, 3]];
  assert.deepEqual(V.cloudColours(points, "image", [[1, 0, 0.5], [0, 1, 0]]), [[255, 0, 128], [0, 255, 0]]);
  assert.deepEqual(V.cloudColours(points, "depth", [[1, 0, 0], [0, 1, 0]]), [[68, 1, 84], [253, 231, 37]]);
  assert.deepEqual(V.cloudColours(points, "image", null)[1], [253, 231, 37]);
});

test("confusion shares per row and accuracy from the diagonal", () => {
  const c = V.confusionShares([[3, 1], [0, 0]]);
  assert.deepEqual(c.rows, [[0.75, 0.25], [0, 0]]);
  assert.equal(c.right, 3);
  assert.equal(c.accuracy, 0.75);
});

test("axis ticks are round numbers inside the range", () => {
  assert.deepEqual(V.niceTicks(0, 1, 5), [0, 0.2, 0.4, 0.6, 0.8, 1]);
  assert.deepEqual(V.niceTicks(1, 15, 6), [5, 10, 15]);
  assert.deepEqual(V.niceTicks(0.13, 2.31, 4), [0.5, 1, 1.5, 2]);
});

test("at most n items, evenly spread, and all when fewer", () => {
  assert.deepEqual(V.spread([0, 1, 2, 3, 4, 5, 6, 7, 8, 9], 5), [0, 2, 4, 6, 8]);
  assert.deepEqual(V.spread([1, 2], 5), [1, 2]);
  const F = [0, 0, 0, 0, 0, -1, 0, 1, 0];
  const many = Array.from({ length: 100 }, (_, i) => [i, i]);
  const found = V.epipolarSegments(F, many, [], [200, 200], [200, 200], 210, 10);
  assert.equal(found.inB.x0.length, 10);
  assert.deepEqual(found.inB.y0, [0, 10, 20, 30, 40, 50, 60, 70, 80, 90]);
  assert.equal(found.inB.x0[0], 210);
});
