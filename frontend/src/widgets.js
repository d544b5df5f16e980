// Parameter widgets from a parameter's JSON schema (pure: what to draw, how to read it).

// {kind: "slider"|"number"|"menu"|"switch"|"text"|"json", min, max, step, soft}
export function widgetSpec(schema, value) {
  if (schema.enum) return { kind: "menu", options: schema.enum };
  const type = schema.type || (schema.anyOf || []).map((s) => s.type).find((t) => t !== "null");
  if (type === "boolean") return { kind: "switch" };
  if (type === "string") return { kind: "text" };
  if (type === "integer" || type === "number") {
    const integer = type === "integer";
    const lo = schema.minimum ?? schema.exclusiveMinimum;
    const hi = schema.maximum ?? schema.exclusiveMaximum;
    let step = integer ? (schema["x-odd"] ? 2 : 1) : 0;
    const v = typeof value === "number" ? value : 0;
    // a side the schema leaves open gets a soft end (the box still takes any valid value)
    const min = lo ?? Math.min(0, v * 4);
    const max = hi ?? Math.max(lo !== undefined ? lo + 1 : 1, Math.abs(v) * 4 || 10);
    if (!integer) step = niceStep((max - min) / 200);
    const start = schema["x-odd"] && min % 2 === 0 ? min + 1 : min;
    return { kind: "slider", min: start, max, step, soft: lo === undefined || hi === undefined,
             integer, exclusiveMin: schema.exclusiveMinimum, exclusiveMax: schema.exclusiveMaximum };
  }
  return { kind: "json" };
}

function niceStep(raw) {
  if (!(raw > 0)) return 0.01;
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  return [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw);
}

// The value a widget's text means, or {error} before anything is sent.
export function readValue(spec, text) {
  if (spec.kind === "switch") return { value: Boolean(text) };
  if (spec.kind === "menu" || spec.kind === "text") return { value: text };
  if (spec.kind === "slider") {
    const typed = String(text).trim();
    if (!DECIMAL.test(typed)) return { error: `not a number: '${text}'` };
    const v = Number(typed);
    const range = outOfRange(typed, v);
    if (range) return { error: range };
    if (spec.integer && !Number.isInteger(v)) return { error: `not a whole number: ${text}` };
    if (spec.integer && !Number.isSafeInteger(v)) {
      return { error: `out of range: ${typed} is beyond ±${Number.MAX_SAFE_INTEGER}, the largest whole number sent exactly` };
    }
    return { value: v };
  }
  try {
    return { value: JSON.parse(text) };
  } catch (e) {
    return { error: `not JSON: ${e.message}` };
  }
}

// A number as a person writes one: digits, a point, an exponent (not hex, not Infinity).
const DECIMAL = /^[+-]?(\d+\.?\d*|\.\d+)(e[+-]?\d+)?$/i;

// Why a number written well (1e400, -1e-400) cannot be held: beyond ±1.8e308 it would be
// sent as infinity, closer to 0 than 5e-324 as 0. "" when it can be held.
function outOfRange(typed, v) {
  if (!Number.isFinite(v)) {
    return `out of range: ${typed} is beyond ±${Number.MAX_VALUE.toPrecision(2)}, the largest number the studio can send`;
  }
  if (v === 0 && /[1-9]/.test(typed.split(/e/i)[0])) {
    return `out of range: ${typed} is closer to 0 than ${Number.MIN_VALUE.toPrecision(1)}, the smallest number the studio can send (it would be sent as 0)`;
  }
  return "";
}

// A run's change of one parameter, as the runs table writes it: null (the pipeline file's
// value) is shown as that value, from the run's ``file`` ("0.2 → 0.5", not "file → 0.5").
export function changeText(key, [before, after], file = {}) {
  const shown = (v) => (v === null || v === undefined ? (key in file ? show(file[key]) : "file") : show(v));
  return `${key}: ${shown(before)} → ${shown(after)}`;
}

function show(value) {
  return value !== null && typeof value === "object" ? JSON.stringify(value) : String(value);
}
