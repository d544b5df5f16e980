// Colour maps for float maps (viridis, perceptually uniform), value range, colour bar.

// viridis at 9 stops (matplotlib's _viridis_data, every 32nd entry and the last).
const VIRIDIS = [
  [68, 1, 84], [71, 44, 122], [59, 81, 139], [44, 113, 142], [33, 144, 141],
  [39, 173, 129], [92, 200, 99], [170, 220, 50], [253, 231, 37],
];

export function viridis(t) {
  if (!Number.isFinite(t)) return [0, 0, 0];
  const x = Math.min(1, Math.max(0, t)) * (VIRIDIS.length - 1);
  const i = Math.min(VIRIDIS.length - 2, Math.floor(x));
  const f = x - i;
  return VIRIDIS[i].map((c, k) => Math.round(c + f * (VIRIDIS[i + 1][k] - c)));
}

// The finite range of `values` ([0, 1] when none is finite).
export function finiteRange(values) {
  let lo = Infinity, hi = -Infinity;
  for (const v of values) {
    if (Number.isFinite(v)) {
      if (v < lo) lo = v;
      if (v > hi) hi = v;
    }
  }
  return lo <= hi ? [lo, hi] : [0, 1];
}

// The range a float map is coloured over when it is auto: its finite values' 1st to
// 99th percentile (linear interpolation, as numpy.percentile), so that a few outliers
// do not wash the map out; their full range when those two are equal. The report's
// picture without script (graphvision/views/viewers.py, float_map_range) uses the same.
export function autoRange(values, low = 1, high = 99) {
  const finite = Float64Array.from(Array.prototype.filter.call(values, Number.isFinite));
  if (finite.length === 0) return [0, 1];
  finite.sort();
  const at = (q) => {
    const x = (q / 100) * (finite.length - 1);
    const i = Math.floor(x);
    const j = Math.min(i + 1, finite.length - 1);
    return finite[i] + (x - i) * (finite[j] - finite[i]);
  };
  const [lo, hi] = [at(low), at(high)];
  return hi > lo ? [lo, hi] : [finite[0], finite[finite.length - 1]];
}

// RGBA bytes of `values` (row-major, width × height) through viridis over [lo, hi];
// NaN and infinities are drawn transparent black.
export function colourise(values, lo, hi) {
  const out = new Uint8ClampedArray(values.length * 4);
  const span = hi > lo ? hi - lo : 1;
  const lut = Array.from({ length: 256 }, (_, i) => viridis(i / 255));
  for (let i = 0; i < values.length; i++) {
    const v = values[i];
    if (!Number.isFinite(v)) continue;
    const c = lut[Math.max(0, Math.min(255, Math.round(((v - lo) / span) * 255)))];
    out[4 * i] = c[0];
    out[4 * i + 1] = c[1];
    out[4 * i + 2] = c[2];
    out[4 * i + 3] = 255;
  }
  return out;
}

// Ticks of a colour bar: n values from lo to hi, formatted to 3 significant digits.
export function ticks(lo, hi, n = 5) {
  return Array.from({ length: n }, (_, i) => {
    const v = lo + ((hi - lo) * i) / (n - 1);
    return { value: v, text: Number(v.toPrecision(3)).toString() };
  });
}

// Distinct colours for labels (golden-angle hues); 0, the background, is black.
export function labelColour(label) {
  if (label === 0) return [0, 0, 0];
  const hue = (label * 137.508) % 360;
  const s = 0.75, l = 0.55;
  const k = (n) => (n + hue / 30) % 12;
  const a = s * Math.min(l, 1 - l);
  const f = (n) => l - a * Math.max(-1, Math.min(k(n) - 3, Math.min(9 - k(n), 1)));
  return [f(0), f(8), f(4)].map((v) => Math.round(v * 255));
}
