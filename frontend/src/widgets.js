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
    const v = Number(text);
    if (text === "" || !Number.isFinite(v)) return { error: `not a number: '${text}'` };
    if (spec.integer && !Number.isInteger(v)) return { error: `not a whole number: ${text}` };
    return { value: v };
  }
  try {
    return { value: JSON.parse(text) };
  } catch (e) {
    return { error: `not JSON: ${e.message}` };
  }
}
