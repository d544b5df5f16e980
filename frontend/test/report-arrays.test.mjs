// report.html's arrays as its script decodes them (graphvision/views/page_arrays.py writes
// them), on the built bundle the report inlines: node --test test/
import { test } from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { deflateSync } from "node:zlib";

const bundle = readFileSync(new URL("../../graphvision/views/static/graph.js", import.meta.url), "utf8");
// eslint-disable-next-line no-new-func -- the bundle is an IIFE script defining one global
const G = new Function(`${bundle}\nreturn GraphvisionGraph;`)();

function entry(codes, extra) {  // uint16 codes, little-endian, sent plane by plane
  const bytes = Buffer.alloc(codes.length * 2);
  codes.forEach((c, i) => { bytes[i] = c & 255; bytes[codes.length + i] = c >> 8; });
  return { dtype: "uint16", shape: [codes.length], planes: 2, deflate: deflateSync(bytes).toString("base64"), ...extra };
}

test("16-bit codes decode to offset + code / scale, the nan code to NaN", async () => {
  const found = await G.decodeRaw(entry([0, 1, 65534, 65535, 300], { scale: 65534 / 64.5, offset: -3.5, nan: 65535 }));
  const want = [-3.5, -3.5 + 64.5 / 65534, 61, NaN, -3.5 + 300 * 64.5 / 65534];
  assert.equal(found.values.length, 5);
  want.forEach((w, i) => (Number.isNaN(w) ? assert.ok(Number.isNaN(found.values[i])) : assert.ok(Math.abs(found.values[i] - w) < 1e-5, `${i}`)));
});

test("exact codes (quarters) and 8-bit levels decode to their values, no offset", async () => {
  const quarters = await G.decodeRaw(entry([0, 1, 6, 65535], { scale: 4, nan: 65535 }));
  assert.deepEqual(Array.from(quarters.values.slice(0, 3)), [0, 0.25, 1.5]);
  assert.ok(Number.isNaN(quarters.values[3]));
  const bytes = deflateSync(Buffer.from([0, 255, 51])).toString("base64");
  const levels = await G.decodeRaw({ dtype: "uint8", shape: [3], scale: 255, deflate: bytes });
  assert.deepEqual(Array.from(levels.values), [0, 1, Math.fround(51 / 255)]);
});
