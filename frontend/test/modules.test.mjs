// The page's pure modules, tested on the built bundle (what ships): node --test test/
import { test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";

const bundle = readFileSync(new URL("../../graphvision/studio/static/viewers.js", import.meta.url), "utf8");
// eslint-disable-next-line no-new-func -- the bundle is an IIFE script defining one global
const V = new Function(`${bundle}\nreturn GraphvisionViewers;`)();

const chain = {
  nodes: [{ id: "image", kind: "input", type: "Image" }, { id: "gray", op: "colour.to_gray" },
    { id: "blur", op: "filters.gaussian" }, { id: "edges", op: "edges.canny" }],
  edges: [{ from: "image", from_port: "", to: "gray", port: "image" },
    { from: "gray", from_port: "out", to: "blur", port: "image" },
    { from: "blur", from_port: "out", to: "edges", port: "image" },
    { from: "gray", from_port: "out", to: "edges", port: "mask" }],
};

test("layout: ranks follow the edges and no two boxes or labels overlap", () => {
  const laid = V.layoutGraph(chain);
  assert.ok(laid.nodes.image.x < laid.nodes.gray.x && laid.nodes.gray.x < laid.nodes.blur.x);
  const boxes = { ...laid.nodes };
  laid.edges.forEach((e, i) => { boxes["label" + i] = e.label; });
  assert.deepEqual(V.overlaps(boxes), []);
  assert.equal(laid.edges[3].label.text, "mask");
});

test("overlaps finds two boxes that share area, and not two that touch", () => {
  const found = V.overlaps({ a: { x: 0, y: 0, width: 10, height: 10 }, b: { x: 5, y: 5, width: 10, height: 10 },
    c: { x: 15, y: 0, width: 5, height: 5 } });
  assert.deepEqual(found.map((p) => [p.a, p.b]), [["a", "b"]]);
});

test("downstream of a node: itself and every reader, transitively", () => {
  assert.deepEqual([...V.downstream(chain, "blur")].sort(), ["blur", "edges"]);
  assert.deepEqual([...V.downstream(chain, "gray")].sort(), ["blur", "edges", "gray"]);
});

test("widgets: bounds, odd sizes step by two, enums, booleans, open ends", () => {
  const window = V.widgetSpec({ type: "integer", minimum: 3, maximum: 1001, "x-odd": true }, 51);
  assert.equal(window.kind, "slider");
  assert.equal(window.step, 2);
  assert.equal(window.min, 3);
  assert.equal(window.max, 1001);
  assert.equal(V.widgetSpec({ enum: ["a", "b"] }, "a").kind, "menu");
  assert.equal(V.widgetSpec({ type: "boolean" }, true).kind, "switch");
  const open = V.widgetSpec({ type: "number", exclusiveMinimum: 0 }, 3.0);
  assert.equal(open.min, 0);
  assert.equal(open.max, 12);
  assert.ok(open.soft);
  assert.equal(V.widgetSpec({ type: "object" }, {}).kind, "json");
});

test("widgets read what is typed, and refuse what is not a value", () => {
  const spec = V.widgetSpec({ type: "integer", minimum: 1 }, 5);
  assert.equal(V.readValue(spec, "7").value, 7);
  assert.match(V.readValue(spec, "7.5").error, /not a whole number/);
  assert.match(V.readValue(spec, "x").error, /not a number/);
  assert.deepEqual({ ...V.readValue({ kind: "json" }, "[1, 2]") }.value.length, 2);
});

test("a number beyond what the page can send is out of range, not 'not a number'", () => {
  const spec = V.widgetSpec({ type: "number" }, 0.5);
  assert.match(V.readValue(spec, "1e400").error, /^out of range: 1e400 is beyond ±1\.8e\+308/);
  assert.match(V.readValue(spec, " -1E400 ").error, /^out of range: -1E400 is beyond/);
  assert.match(V.readValue(spec, "1e-400").error, /^out of range: 1e-400 is closer to 0 than 5e-324/);
  assert.equal(V.readValue(spec, "0e-400").value, 0);  // zero written small is zero
  assert.equal(V.readValue(spec, "1e300").value, 1e300);
  assert.match(V.readValue(spec, "").error, /not a number: ''/);
  assert.match(V.readValue(spec, "Infinity").error, /not a number: 'Infinity'/);
  assert.match(V.readValue(spec, "0x10").error, /not a number: '0x10'/);  // a box of decimals
  assert.equal(V.readValue(spec, " -.5e1 ").value, -5);
  const whole = V.widgetSpec({ type: "integer" }, 5);
  assert.match(V.readValue(whole, "1e17").error, /^out of range: 1e17 is beyond ±9007199254740991/);
});

test("the runs table writes a change from the file's value as that value", () => {
  assert.equal(V.changeText("binary.k", [null, 0.5], { "binary.k": 0.2 }), "binary.k: 0.2 → 0.5");
  assert.equal(V.changeText("binary.k", [0.5, null], { "binary.k": 0 }), "binary.k: 0.5 → 0");
  assert.equal(V.changeText("coins.ranges", [null, { area: [1, null] }], { "coins.ranges": { area: [400, null] } }),
    'coins.ranges: {"area":[400,null]} → {"area":[1,null]}');
  assert.equal(V.changeText("binary.k", [null, 0.5]), "binary.k: file → 0.5");  // an older server
});

test("viridis runs dark purple to yellow; NaN is transparent", () => {
  assert.deepEqual(V.viridis(0), [68, 1, 84]);
  assert.deepEqual(V.viridis(1), [253, 231, 37]);
  const rgba = V.colourise(new Float32Array([0, NaN, 1]), 0, 1);
  assert.deepEqual([...rgba.slice(0, 4)], [68, 1, 84, 255]);
  assert.deepEqual([...rgba.slice(4, 8)], [0, 0, 0, 0]);
  assert.deepEqual(V.finiteRange([NaN, 2, -1, Infinity]), [-1, 2]);
  assert.deepEqual(V.ticks(0, 1, 3).map((t) => t.text), ["0", "0.5", "1"]);
});

test("a float map's auto range is its 1st to 99th percentile, as the report's picture", () => {
  // 0, 1, ..., 100 and one outlier, with NaN and inf left out:
  // numpy.percentile(list(range(101)) + [1e6], [1, 99]) gives [1.01, 99.99].
  const values = new Float32Array([...Array.from({ length: 101 }, (_, i) => i), 1e6, NaN, Infinity]);
  const [lo, hi] = V.autoRange(values);
  assert.ok(Math.abs(lo - 1.01) < 1e-9 && Math.abs(hi - 99.99) < 1e-9, `${lo} ${hi}`);
  // numpy.percentile([2] * 100 + [7], [1, 99]) gives [2, 2]: widened to the minimum and maximum.
  assert.deepEqual(V.autoRange(new Float32Array([...Array(100).fill(2), 7])), [2, 7]);
  assert.deepEqual(V.autoRange([NaN]), [0, 1]);
});

test("label colours are distinct and the background is black", () => {
  assert.deepEqual(V.labelColour(0), [0, 0, 0]);
  const colours = new Set(Array.from({ length: 50 }, (_, i) => V.labelColour(i + 1).join(",")));
  assert.equal(colours.size, 50);
});
