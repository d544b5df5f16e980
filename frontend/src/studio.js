// graphvision studio: the page. Graph, inspector with parameter widgets, outputs, runs.
import { GraphView } from "./graphview.js";
import { downstream } from "./layout.js";
import { docHtml } from "./tex.js";
import { classifierPanel, cloudPanel, curvesPanel, epipolarPanel, maskLayer, matchesPanel } from "./panels.js";
import { el, floatMapViewer, ImageViewer, scalarViewer, tableViewer } from "./viewers.js";
import { changeText, readValue, widgetSpec } from "./widgets.js";

const S = { graph: null, view: null, selected: null, latest: 0, shown: 0, runs: {}, states: {},
  timers: {}, showing: new Set(), queued: {}, repainting: new Map() };
const $ = (sel) => document.querySelector(sel);

async function api(path, body) {
  const init = body === undefined ? {} : { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) };
  const response = await fetch(path, init);
  const data = response.headers.get("content-type")?.includes("json") ? await response.json() : null;
  return { ok: response.ok, status: response.status, data };
}

function setNodeState(id, state, seconds) {
  S.states[id] = { state, seconds, since: state === "running" ? performance.now() : null };
  const text = seconds !== undefined && (state === "computed" || state === "cached" || state === "failed")
    ? `${state} ${(seconds).toFixed(seconds < 10 ? 2 : 1)} s` : state;
  S.view.setState(id, state, text);
  clearInterval(S.timers[id]);
  if (state === "running") {
    S.timers[id] = setInterval(() => {
      const s = (performance.now() - S.states[id].since) / 1000;
      S.view.setState(id, "running", `running ${s.toFixed(1)} s`);
    }, 100);
  }
}

function onEvent(event) {
  if (event.event === "run") {
    S.runs[event.run] = { ...(S.runs[event.run] || {}), ...event, id: event.run };
    if (event.status === "running") {
      S.latest = Math.max(S.latest, event.run);
      showRunning(event.run);
      if (event.diff && Object.keys(event.diff).length) followParams(event.run, event.diff);
    } else if (event.run === S.latest) {
      showStatus(event);
      if (event.status === "done" || event.status === "failed") showRun(event.run);
      if (event.status === "cancelled") for (const [id, s] of Object.entries(S.states)) if (s.state === "running" || s.state === "queued") setNodeState(id, "stale");
    }
    if (event.status !== "running" && event.seconds !== undefined) refreshRuns(false);
    return;
  }
  if (event.run < S.latest) return; // a superseded run: never mixed with the newer one
  if (event.event === "queued") {
    S.queued[event.run] = new Set(event.nodes);
    for (const id of event.nodes) setNodeState(id, "queued");
    for (const card of document.querySelectorAll("[data-producer]")) {
      if (event.nodes.includes(card.dataset.producer)) card.classList.add("gv-stale");
    }
  }
  if (event.event === "node") {
    setNodeState(event.node, event.status, event.seconds);
    // the descriptions the page asked for before ride the event: none is asked for again
    for (const [port, d] of Object.entries(event.values || {})) pushed(event.run, event.node, port, d);
    if (event.value) repaintNode(event.run, event.node);
  }
}

// Another tab's change (or this one's) started a run: the widgets show the session's values
// from now on, so that no tab shows one run's pictures beside another run's parameters. The
// run's diff holds the new values; only a value set back to the file's is asked of the server.
async function followParams(run, diff) {
  let nodes = S.graph.nodes;
  if (Object.values(diff).some(([, now]) => now === null)) {
    const found = await api("api/graph");
    if (!found.ok) return;
    nodes = found.data.nodes;
  }
  if (run < S.latest) return;  // a newer run follows with its own values
  for (const n of nodes) for (const p of n.params || []) if (diff[p.key] && diff[p.key][1] !== null) p.value = diff[p.key][1];
  S.graph.nodes = nodes;
  const shown = $("#inspector").firstElementChild;
  const node = nodes.find((n) => n.id === shown?.dataset.inspect);
  for (const p of node?.params || []) {
    if (!(p.key in diff)) continue;
    for (const input of shown.querySelectorAll(`.gv-param[data-param="${p.name}"] :is(input, select)`)) {
      if (input.type === "checkbox") input.checked = Boolean(p.value);
      else if (input.classList.contains("gv-text") && p.value !== null && typeof p.value === "object") input.value = JSON.stringify(p.value);
      else input.value = p.value ?? "";
    }
  }
}

function showRunning(id) {
  $("#run-status").textContent = `run ${id} running`;
  $("#run-status").dataset.status = "running";
  $("#cancel").disabled = false;
}

// The latest run's end in the header: how it ended, in how long, and why it failed.
function showStatus(run) {
  $("#run-status").textContent = `run ${run.id ?? run.run} ${run.status}` +
    (run.seconds ? ` in ${(run.seconds * 1000).toFixed(0)} ms` : "") + (run.error ? `: ${whyFailed(run)}` : "");
  $("#run-status").dataset.status = run.status;
  $("#cancel").disabled = true;
}

// What made a run fail, in the command line's words: each failed node's error (naming the
// node: a node that raised, a worker that died), else the run's (an input file deleted).
function whyFailed(event) {
  const nodes = Object.values(event.nodes || {}).filter((n) => n.error && n.status === "failed");
  return nodes.length ? nodes.map((n) => n.error).join("; ") : event.error;
}

// What the page knows of the runs, from the server's list (api/runs, api/graph). A run's
// status only moves forward: running, then how it ended. A list asked for while a run was
// running can arrive after the run's end came by the event stream (another connection):
// it is older than what the page knows and never puts an ended run back to running. A run
// the list names that the page never heard start (the stream reconnected) becomes the latest.
const ENDED = new Set(["done", "failed", "cancelled", "superseded"]);
function learnRuns(runs) {
  for (const r of runs) {
    const known = S.runs[r.id];
    const older = known && ENDED.has(known.status) && !ENDED.has(r.status);
    S.runs[r.id] = older ? { ...r, ...known } : { ...known, ...r };  // (older: its diff only)
    S.latest = Math.max(S.latest, r.id);
  }
}

async function showRun(id) {
  if (!S.runs[id]?.nodes || S.runs[id].kept === undefined) {
    const found = await api("api/runs");
    if (!found.ok) return;
    learnRuns(found.data);
  }
  const run = S.runs[id];
  if (!run || !run.kept) return;
  if (id <= S.shown || S.showing.has(id)) return;
  S.showing.add(id);
  S.shown = id;
  for (const [name, n] of Object.entries(run.nodes)) setNodeState(name, n.status, n.seconds);
  document.body.dataset.shownRun = String(id);
  // a node's repaint still under way swaps its cards in (streamed): they are kept, not
  // fetched and drawn a second time
  await Promise.all([...S.repainting].filter(([k]) => k.startsWith(`${id}/`)).map(([, p]) => p));
  await Promise.all([renderOutputs(), S.selected ? renderInspector(S.selected, false) : null]);
  document.body.dataset.paintedRun = String(id);
  window.dispatchEvent(new CustomEvent("gv-painted", { detail: { run: id } }));
}

function history(node, port) {
  return Object.values(S.runs).filter((r) => r.metrics).map((r) => {
    const name = Object.entries(S.graph.outputs).find(([, src]) => src[0] === node && src[1] === port)?.[0];
    return { run: r.id, value: name ? r.metrics[name] : undefined };
  }).filter((h) => h.value !== undefined);
}

// A value's picture as RGBA bytes (no PNG to encode or decode), made ready to draw off
// the main thread (createImageBitmap); null when it has none. Asked for once per run,
// port and step: every panel showing it (the outputs, the inspector, a pair viewer)
// shares the one request and the one bitmap.
const pictures = new Map();
function fetchPicture(base, step = 1) {
  const id = `${base}?step=${step}`;
  if (!pictures.has(id)) {
    pictures.set(id, loadPicture(base, step).then((p) => { if (!p) pictures.delete(id); return p; },
      (error) => { pictures.delete(id); throw error; }));
    while (pictures.size > 24) pictures.delete(pictures.keys().next().value);
  }
  return pictures.get(id);
}

async function loadPicture(base, step) {
  const r = await fetch(`api/rgba/${base}?step=${step}`);
  if (!r.ok) return null;
  const [ph, pw] = r.headers.get("X-Shape").split(",").map(Number);
  const data = new ImageData(new Uint8ClampedArray(await r.arrayBuffer()), pw, ph);
  return typeof createImageBitmap === "function" ? createImageBitmap(data) : pictureCanvas(data);
}

function pictureCanvas(data) {
  const canvas = document.createElement("canvas");
  canvas.width = data.width;
  canvas.height = data.height;
  canvas.getContext("2d").putImageData(data, 0, 0);
  return canvas;
}

// The rows of a table made at once (the rest as it is scrolled): more than its box shows.
const TABLE_ROWS = 24;

// The image viewer drawing on each canvas (to know at what zoom a picture is shown).
const viewerOf = new WeakMap();

// How many times smaller than the picture a first preview can be, shown where `canvas`
// is: the viewer's zoom shows 1/scale picture pixels per canvas pixel (1: no preview).
function previewStep(canvas) {
  const scale = viewerOf.get(canvas)?.scale;
  return scale > 0 ? Math.max(1, Math.min(16, Math.floor(1 / scale))) : 1;
}

// A run's values for the viewers that draw one value with others (panels.js). A value
// whose cache key is known is fetched once (the images and keypoints a change downstream
// of them leaves alone are not sent again for every run).
const fetched = new Map();
// The cache key of a node's output in a run; while the run streams (its keys not known
// yet), that of the latest run which knows it, when this run did not queue the node.
function keyIn(run, node, port) {
  const known = S.runs[run]?.nodes?.[node]?.keys?.[port];
  if (known !== undefined || !S.queued[run] || S.queued[run].has(node)) return known;
  for (let r = run - 1; r > 0; r--) {
    const key = S.runs[r]?.nodes?.[node]?.keys?.[port];
    if (key !== undefined) return key;
  }
  return undefined;
}

function remembered(kind, run, node, port, get) {
  const key = keyIn(run, node, port);
  if (key === undefined) return get();
  const id = `${kind}/${node}/${port}/${key}`;
  if (!fetched.has(id)) {
    fetched.set(id, get().then((value) => { if (value === null) fetched.delete(id); return value; }));
    while (fetched.size > 48) fetched.delete(fetched.keys().next().value);
  }
  return fetched.get(id);
}

function sourceOf(run) {
  const fresh = freshSource(run);
  return Object.fromEntries(Object.entries(fresh).map(([kind, get]) =>
    [kind, (node, port) => remembered(kind, run, node, port, () => get(node, port))]));
}

function freshSource(run) {
  return {
    value: async (node, port) => { const r = await describe(run, node, port); return r.ok ? r.data : null; },
    raw: async (node, port) => {
      const r = await fetch(`api/raw/${run}/${node}/${port}`);
      return r.ok ? { values: new Float32Array(await r.arrayBuffer()), shape: r.headers.get("X-Shape").split(",").map(Number) } : null;
    },
    picture: (node, port) => fetchPicture(`${run}/${node}/${port}`),
  };
}

// A value's description, asked for once per run and port: the outputs and the inspector
// showing the same port (and the overlays drawn over an image) share one request, so
// that a node's repaint does not queue a second copy of each before the pictures.
const described = new Map();
function describe(run, node, port) {
  const id = `${run}/${node}/${port}`;
  if (!described.has(id)) keep(id, api(`api/value/${id}`).then((r) => { if (!r.ok) described.delete(id); return r; }));
  return described.get(id);
}

function keep(id, promise) {
  described.set(id, promise);
  while (described.size > 64) described.delete(described.keys().next().value);
}

// A description the server pushed with its node's event, as if asked for.
function pushed(run, node, port, d) {
  const id = `${run}/${node}/${port}`;
  if (!described.has(id)) keep(id, Promise.resolve({ ok: true, status: 200, data: d }));
}

// `picture`: `{ step, promise }` of the picture's request, when the caller started it
// already (a repaint of a card that showed one), so that it travels while the value's
// description is asked for. A preview (step > 1) is drawn first, the picture after it.
async function renderValue(container, run, node, port, picture = null) {
  const found = await describe(run, node, port);
  if (!found.ok) { container.append(el("div", { class: "gv-error" }, found.data?.error || "no value")); return null; }
  const d = found.data;
  const base = `${run}/${node}/${port}`;
  container.append(el("div", { class: "gv-caption" }, d.summary));
  if (["image", "labels", "mask"].includes(d.view) || (d.view === "summary" && d.png && d.shape?.length >= 2 && d.shape[0] > 8)) {
    // a summary's picture (a scatter of points, a mosaic) has its own size, not the value's
    const own = d.view === "summary" ? await sourceOf(run).picture(node, port) : null;
    const [h, w] = own ? [own.height, own.width] : d.shape;
    const viewer = new ImageViewer(container, { width: w, height: h, label: "" });
    Object.assign(viewer.canvas.dataset, { value: base, picture: "rgba", view: d.view, shape: String(d.shape) });
    viewer.canvas.addEventListener("mouseenter", async () => {
      const shown = viewer.canvas.dataset.value;  // the run shown now (repainted in place)
      if (viewer.asked === shown) return;
      viewer.asked = shown;
      const r = await fetch(`api/raw/${shown}`);
      if (r.ok && viewer.canvas.dataset.value === shown) viewer.setValues(new Float32Array(await r.arrayBuffer()), r.headers.get("X-Shape").split(",").map(Number));
    });
    viewerOf.set(viewer.canvas, viewer);
    const first = picture || { step: 1, promise: own ? Promise.resolve(own) : fetchPicture(base) };
    const [bitmap] = await Promise.all([first.promise, addOverlays(viewer, run, node, port)]);
    // a mask or label map is tinted over the image behind it (its own picture when none)
    const tinted = d.over && ["mask", "labels"].includes(d.view) && await maskLayer(viewer, d, sourceOf(run));
    if (bitmap && !tinted) showPicture(viewer, base, first.step, bitmap);
    if (tinted) viewer.canvas.dataset.tinted = "1";
  } else if (d.view === "floatmap") {
    const r = await fetch(`api/raw/${base}`);
    const values = new Float32Array(await r.arrayBuffer());
    const viewer = floatMapViewer(container, d, values);
    viewer.canvas.dataset.value = base;
    await addOverlays(viewer, run, node, port);
  } else if (d.view === "scalar" || d.view === "text") {
    scalarViewer(container, d.value, history(node, port));
  } else if (d.view === "points3d") {
    await cloudPanel(container, d, sourceOf(run));
  } else if (["table", "keypoints", "boxes", "matches", "lines", "circles"].includes(d.view)) {
    if (d.view === "matches" && d.pair) await matchesPanel(container, d, sourceOf(run));
    if (d.confusion) await classifierPanel(container, d, sourceOf(run));
    if (d.over) container.append(el("div", { class: "gv-caption" }, `drawn over ${d.over[0]} (toggle it there)`));
    tableViewer(container, d.columns, d.count ?? d.rows, TABLE_ROWS);
  } else if (d.view === "fundamental" || d.view === "matrix") {
    if (d.view === "fundamental" && d.pair) await epipolarPanel(container, d, sourceOf(run));
    const rows = d.shape.length === 2 ? d.shape[0] : 1, cols = d.value.length / rows;
    const columns = {};
    for (let j = 0; j < cols; j++) columns[`[${j}]`] = Array.from({ length: rows }, (_, i) => d.value[i * cols + j]);
    tableViewer(container, columns, undefined, TABLE_ROWS);
  } else if (d.png) {
    container.append(el("img", { src: `api/png/${base}`, class: "gv-preview" }));
  }
  if (d.curves) curvesPanel(container, d);
  return d;
}

// A picture drawn on its viewer: a preview (step > 1) first; the picture itself once the
// viewer is zoomed in past what the preview holds (more than one canvas pixel per preview
// pixel), unless the viewer shows another run's value by then. At the zoom the picture
// is shown, the preview has all it shows: a change costs the server, the connection and
// the page the preview alone (a quarter of the bytes at step 2), not the full picture too.
function showPicture(viewer, base, step, bitmap) {
  viewer.setSource(bitmap);
  viewer.full = null;
  if (step <= 1) { delete viewer.canvas.dataset.preview; return; }
  viewer.canvas.dataset.preview = String(step);
  viewer.full = { base, step };
  if (!viewer.zoomWatched) {
    viewer.zoomWatched = true;  // after the viewer's own wheel handler: its new scale
    viewer.canvas.addEventListener("wheel", () => sharpen(viewer));
  }
  sharpen(viewer);
}

function sharpen(viewer) {
  const want = viewer.full;
  if (!want || viewer.scale * want.step <= 1) return;
  viewer.full = null;
  fetchPicture(want.base).then((full) => {
    if (!full || viewer.canvas.dataset.value !== want.base) return;
    viewer.setSource(full);
    delete viewer.canvas.dataset.preview;
  });
}

// Keypoints, boxes, lines and circles found in this image are drawn over it.
async function addOverlays(viewer, run, node, port) {
  const readers = S.graph.edges.filter((e) => e.from === node && (e.from_port || "out") === (port || "out"));
  for (const e of readers) {
    const target = S.graph.nodes.find((n) => n.id === e.to);
    for (const [out, type] of Object.entries(target.outputs || {})) {
      if (!["Keypoints", "Boxes", "Lines", "Circles"].includes(type)) continue;
      const found = await describe(run, target.id, out);
      if (found.ok && found.data.over && found.data.over[0] === node) {
        viewer.addOverlay(`${target.id}.${out}`, found.data.view, found.data.columns);
      }
    }
  }
}

// A node's outputs repainted as soon as it finishes (before its run ends).
async function repaintNode(run, node) {
  const id = `${run}/${node}`;
  const done = repaintCards(run, node);
  S.repainting.set(id, done);
  try { await done; } finally { S.repainting.delete(id); }
  window.dispatchEvent(new CustomEvent("gv-node-painted", { detail: { run, node } }));
}

async function repaintCards(run, node) {
  const cards = [...document.querySelectorAll(`[data-producer="${node}"]`)];
  await Promise.all(cards.map(async (card) => {
    const fresh = card.cloneNode(false);
    fresh.classList.remove("gv-stale");
    fresh.dataset.streamed = String(run);
    fresh.append(card.querySelector("h4").cloneNode(true));
    const base = `${run}/${node}/${card.dataset.portName}`;
    const shown = card.querySelector("canvas[data-picture]");
    const step = shown ? previewStep(shown) : 1;
    const picture = shown ? { step, promise: fetchPicture(base, step) } : null;
    const kept = shown && await repaintInPlace(card, shown, run, node, card.dataset.portName, picture);
    const d = kept || await renderValue(fresh, run, node, card.dataset.portName, picture);
    if (run !== S.latest) return;
    if (!kept) card.replaceWith(fresh);
    const shape = card.dataset.port && document.querySelector(`[data-inspect="${node}"] [data-shape="${card.dataset.portName}"]`);
    if (shape) shape.textContent = d?.shape ? d.shape.join("×") : "";
  }));
}

// A picture shown alone (no overlay, no tint) whose new value has the same view and shape
// keeps its card and viewer: the new picture is drawn on the same canvas, at the zoom the
// user left it (no new card to lay out, no canvas made again). The description, or null
// when the card has to be made again.
async function repaintInPlace(card, canvas, run, node, port, picture) {
  const viewer = viewerOf.get(canvas);
  if (!viewer || viewer.overlays.length || viewer.layers?.length || canvas.dataset.tinted) return null;
  const found = await describe(run, node, port);
  const d = found.ok ? found.data : null;
  if (!d || d.over || d.view !== canvas.dataset.view || String(d.shape) !== canvas.dataset.shape) return null;
  const bitmap = await picture.promise;
  if (!bitmap || run !== S.latest) return run !== S.latest ? d : null;
  const base = `${run}/${node}/${port}`;
  canvas.dataset.value = base;
  viewer.values = null;  // the values under the cursor are the new run's, asked for again
  showPicture(viewer, base, picture.step, bitmap);
  card.querySelector(".gv-caption").textContent = d.summary;
  card.classList.remove("gv-stale");
  card.dataset.streamed = String(run);
  return d;
}

function keyOf(run, node, port) {
  return JSON.stringify(S.runs[run]?.nodes?.[node]?.keys?.[port] ?? `${run}`);
}

// Outputs whose cache key is unchanged keep their viewer (same value); the others are
// fetched and drawn at once, in parallel, then swapped in together.
async function renderOutputs() {
  const box = $("#outputs");
  const run = S.shown;
  const cards = await Promise.all(Object.entries(S.graph.outputs).map(async ([name, [node, port]]) => {
    const key = keyOf(run, node, port || "out");
    const old = box.querySelector(`[data-output="${name}"]`);
    if (old && (old.dataset.key === key || old.dataset.streamed === String(run))) {
      old.dataset.key = key;
      old.classList.remove("gv-stale");
      return old;
    }
    const card = el("div", { class: "gv-output", "data-output": name, "data-key": key,
      "data-producer": node, "data-port-name": port || "out" }, el("h4", {}, name));
    await renderValue(card, run, node, port || "out");
    return card;
  }));
  if (run === S.shown) box.replaceChildren(...cards);
}

function widget(param) {
  const spec = widgetSpec(param.schema, param.value);
  const message = el("div", { class: "gv-invalid" });
  const send = async (value) => {
    message.textContent = "";
    markStale(S.selected);
    const result = await api("api/change", { overrides: { [param.key]: value } });
    if (!result.ok) {
      message.textContent = (result.data?.problems || []).map((p) => p.message).join("; ") || "refused";
      refreshStates();
    }
  };
  let control;
  if (spec.kind === "menu") {
    control = el("select", {}, ...spec.options.map((o) => el("option", { value: o }, String(o))));
    control.value = param.value;
    control.addEventListener("change", () => send(control.value));
  } else if (spec.kind === "switch") {
    control = el("input", { type: "checkbox", class: "gv-switch" });
    control.checked = Boolean(param.value);
    control.addEventListener("change", () => send(control.checked));
  } else if (spec.kind === "slider") {
    const range = el("input", { type: "range", min: spec.min, max: spec.max, step: spec.step || "any" });
    // a text box: a number box empties itself when it cannot hold what was typed (1e400)
    const number = el("input", { type: "text", class: "gv-number" });
    range.value = number.value = param.value;
    const go = (text) => {
      const read = readValue(spec, text);
      if (read.error) { message.textContent = read.error; return; }
      range.value = number.value = read.value;
      send(read.value);
    };
    range.addEventListener("input", () => go(range.value));
    number.addEventListener("change", () => go(number.value));
    number.addEventListener("keydown", (event) => {  // the arrows step as a number box's do
      const by = { ArrowUp: 1, ArrowDown: -1 }[event.key];
      const now = Number(number.value);
      if (!by || number.value.trim() === "" || !Number.isFinite(now)) return;
      event.preventDefault();
      go(String(Number((now + by * spec.step).toPrecision(12))));
    });
    control = el("span", { class: "gv-slider" }, range, number);
  } else {
    const json = spec.kind === "json";
    control = el("input", { type: "text", class: "gv-text" });
    control.value = json ? JSON.stringify(param.value) : param.value ?? "";
    control.addEventListener("change", () => {
      const read = readValue(spec, control.value);
      if (read.error) message.textContent = read.error; else send(read.value);
    });
  }
  control.dataset.param = param.name;
  const title = param.schema.description || param.schema.title || param.name;
  return el("div", { class: "gv-param", "data-param": param.name },
    el("label", { title }, param.name + (param.key.startsWith("params.") ? ` (${param.key})` : "")), control, message);
}

function markStale(id) {
  if (!id) return;
  for (const n of downstream(S.graph, id)) setNodeState(n, "stale");
}

async function refreshStates() {
  const run = S.runs[S.shown];
  if (run) for (const [name, n] of Object.entries(run.nodes)) setNodeState(name, n.status, n.seconds);
}

async function renderInspector(id, force = true) {
  const node = S.graph.nodes.find((n) => n.id === id);
  const keys = JSON.stringify(S.runs[S.shown]?.nodes?.[id] ?? {});
  const current = $("#inspector").firstElementChild;
  if (!force && current && current.dataset.inspect === id && current.dataset.keys === keys) return;
  const run = S.runs[S.shown];
  const record = run?.nodes?.[id] || {};
  if (!force && current && current.dataset.inspect === id && streamedIn(current, S.shown) && !record.error) {
    current.dataset.keys = keys;  // its values are this run's already: its status and keys only
    const [meta, key] = nodeMeta(record);
    current.querySelector(".gv-meta").replaceWith(meta);
    current.querySelector(".gv-key").replaceWith(key);
    return;
  }
  const panel = el("div", { "data-inspect": id, "data-keys": keys });
  if (node.kind === "input") {
    const box = el("input", { type: "text", class: "gv-text", "data-input": id });
    box.value = node.value ?? "";
    const message = el("div", { class: "gv-invalid" });
    box.addEventListener("change", async () => {
      markStale(id);
      const r = await api("api/change", { inputs: { [id]: box.value } });
      if (!r.ok) message.textContent = (r.data?.problems || []).map((p) => p.message).join("; ");
    });
    panel.append(el("h3", {}, id), el("div", { class: "gv-op" }, `input · ${node.type}`),
      el("label", {}, "value (path, sample:NAME or a literal)"), box, message);
  } else {
    const doc = el("div", { class: "gv-doc" });
    doc.innerHTML = docHtml(node.doc);
    const summary = el("div", { class: "gv-summary" });
    summary.innerHTML = docHtml(node.summary);
    panel.append(el("h3", {}, id), el("div", { class: "gv-op" }, `${node.op} · version ${node.version}`), summary,
      el("details", {}, el("summary", {}, "documentation"), doc));
    const ports = el("table", { class: "gv-ports" }, el("tr", {}, el("th", {}, "port"), el("th", {}, "type"), el("th", {}, "shape")));
    for (const [p, t] of Object.entries(node.inputs)) ports.append(el("tr", {}, el("td", {}, "in " + p), el("td", {}, t), el("td", {}, "")));
    const shapes = {};
    for (const [p, t] of Object.entries(node.outputs)) {
      shapes[p] = el("td", { "data-shape": p }, "");
      ports.append(el("tr", {}, el("td", {}, "out " + p), el("td", {}, t), shapes[p]));
    }
    panel.append(ports);
    panel.append(...nodeMeta(record));
    if (record.error) panel.append(el("pre", { class: "gv-error", "data-error": id }, record.error));
    if (node.params.length) {
      panel.append(el("h4", {}, "parameters"));
      for (const p of node.params) panel.append(widget(p));
    }
    const values = el("div", { class: "gv-values" });
    panel.append(el("h4", {}, "outputs"), values);
    $("#inspector").replaceChildren(panel);
    await Promise.all(Object.keys(node.outputs).map(async (port) => {
      const box = el("div", { class: "gv-output", "data-port": `${id}.${port}`, "data-producer": id,
        "data-port-name": port }, el("h4", {}, port));
      values.append(box);
      if (S.shown) {
        const d = await renderValue(box, S.shown, id, port);
        if (d && d.shape) shapes[port].textContent = d.shape.join("×");
      }
    }));
    return;
  }
  $("#inspector").replaceChildren(panel);
}

// A node's status, time and cache keys in the inspector.
function nodeMeta(record) {
  const keys = Object.entries(record.keys || {}).map(([p, k]) => `${p}: ${k}`).join("\n");
  return [el("div", { class: "gv-meta" }, `status ${record.status || "–"} · ${record.seconds !== undefined ? (record.seconds * 1000).toFixed(1) + " ms" : "–"}`),
    el("pre", { class: "gv-key", title: "cache key" }, keys || "cache key: –")];
}

// Whether every output shown in an inspector panel was repainted for `run` as it streamed.
function streamedIn(panel, run) {
  const boxes = [...panel.querySelectorAll(".gv-values > .gv-output")];
  return boxes.length > 0 && boxes.every((b) => b.dataset.streamed === String(run));
}

async function select(id) {
  S.selected = id;
  S.view.select(id);
  await renderInspector(id);
}

// The runs table. A run's end redraws it from the runs' own events (each run's last one
// carries its status, time, metrics and nodes; its first its changes); the list is asked
// for when the tab (re)connects, or when this tab missed a run's events.
async function refreshRuns(ask = true) {
  const ids = Array.from({ length: S.latest }, (_, i) => i + 1);
  if (ask || !ids.every((id) => S.runs[id]?.diff && S.runs[id].metrics && S.runs[id].kept !== undefined)) {
    const found = await api("api/runs");
    if (!found.ok) return;
    learnRuns(found.data);
  }
  const runs = Object.values(S.runs).filter((r) => r.id).sort((a, b) => b.id - a.id);
  const table = el("table", { class: "gv-runs" }, el("tr", {}, ...["A", "B", "run", "status", "ms", "changes", "metrics"].map((h) => el("th", {}, h))));
  for (const r of runs) {
    const a = el("input", { type: "radio", name: "cmp-a", value: r.id });
    const b = el("input", { type: "radio", name: "cmp-b", value: r.id });
    if (!r.kept) { a.disabled = b.disabled = true; }
    const diff = Object.entries(r.diff || {}).map(([k, pair]) => changeText(k, pair, r.file)).join("; ");
    const metrics = Object.entries(r.metrics || {}).map(([k, v]) => `${k} ${typeof v === "number" ? Number(v.toPrecision(4)) : v}`).join(", ");
    if (r.kept && r.id === S.latest && r.status !== "running" && r.id > S.shown) showRun(r.id);
    if (r.id === S.latest) {  // a start or an end this tab missed (it opened meanwhile)
      if (r.status !== "running") showStatus(r);
      else showRunning(r.id);
    }
    table.append(el("tr", { "data-run": r.id }, el("td", {}, a), el("td", {}, b), el("td", {}, String(r.id)), el("td", {}, r.status),
      el("td", {}, ((r.seconds || 0) * 1000).toFixed(0)), el("td", {}, diff || "–"), el("td", {}, metrics || "–")));
  }
  $("#runs").replaceChildren(table);
}

async function compare() {
  const a = Number(document.querySelector("input[name=cmp-a]:checked")?.value);
  const b = Number(document.querySelector("input[name=cmp-b]:checked")?.value);
  const box = $("#compare");
  box.replaceChildren();
  if (!a || !b) { box.append("pick run A and run B in the table"); return; }
  const ra = S.runs[a], rb = S.runs[b];
  const metrics = el("table", { class: "gv-runs" }, el("tr", {}, el("th", {}, "metric"), el("th", {}, `run ${a}`), el("th", {}, `run ${b}`)));
  for (const k of new Set([...Object.keys(ra.metrics || {}), ...Object.keys(rb.metrics || {})])) {
    metrics.append(el("tr", {}, el("td", {}, k), el("td", {}, String(ra.metrics?.[k] ?? "–")), el("td", {}, String(rb.metrics?.[k] ?? "–"))));
  }
  box.append(metrics);
  const node = S.graph.nodes.find((n) => n.id === S.selected && n.kind === "node") ||
    S.graph.nodes.find((n) => Object.values(n.outputs || {}).some((t) => /Image/.test(t)));
  const port = Object.keys(node.outputs).find((p) => /Image/.test(node.outputs[p])) || Object.keys(node.outputs)[0];
  const src = (run) => `api/png/${run}/${node.id}/${port}`;
  const side = el("div", { class: "gv-side" }, el("figure", {}, el("img", { src: src(a) }), el("figcaption", {}, `run ${a}`)),
    el("figure", {}, el("img", { src: src(b) }), el("figcaption", {}, `run ${b}`)));
  const top = el("img", { src: src(b), class: "gv-top" });
  const slider = el("input", { type: "range", min: 0, max: 100, value: 50 });
  slider.addEventListener("input", () => { top.style.clipPath = `inset(0 0 0 ${slider.value}%)`; });
  top.style.clipPath = "inset(0 0 0 50%)";
  const swipe = el("div", { class: "gv-swipe" }, el("img", { src: src(a) }), top);
  box.append(el("h4", {}, `${node.id}.${port}: side by side`), side, el("h4", {}, `swipe (run ${a} left, run ${b} right)`), swipe, slider);
}

async function main() {
  const found = await api("api/graph");
  S.graph = found.data;
  document.title = `${S.graph.name} · graphvision studio`;
  $("#title").textContent = S.graph.name;
  S.view = new GraphView($("#graph"), S.graph, { onSelect: select });
  S.view.fit();
  for (const n of S.graph.nodes) if (n.kind === "node") setNodeState(n.id, "queued");
  learnRuns(S.graph.runs);
  $("#fit").addEventListener("click", () => S.view.fit());
  $("#search").addEventListener("change", (e) => S.view.search(e.target.value));
  $("#cancel").addEventListener("click", () => api("api/cancel", {}));
  $("#compare-go").addEventListener("click", compare);
  $("#save").addEventListener("click", async () => {
    const r = await api("api/save", {});
    $("#notice").textContent = r.ok ? `saved to ${r.data.saved}` : r.data.error;
  });
  $("#save-as").addEventListener("click", async () => {
    const path = prompt("save the parameters into a new pipeline file:", S.graph.source.replace(/\.ya?ml$/, "") + "-tuned.yaml");
    if (!path) return;
    const r = await api("api/save", { path });
    $("#notice").textContent = r.ok ? `saved to ${r.data.saved}` : r.data.error;
  });
  $("#command").addEventListener("click", async () => {
    const r = await api("api/command");
    $("#notice").textContent = r.data.command;
    try { await navigator.clipboard.writeText(r.data.command); } catch (e) { /* shown instead */ }
  });
  const events = new EventSource("api/events");
  events.onmessage = (m) => onEvent(JSON.parse(m.data));
  events.onerror = () => { $("#run-status").textContent = "connection lost: reconnecting…"; };
  events.onopen = () => { refreshRuns(); };
  const last = S.graph.runs[S.graph.runs.length - 1];
  if (last) {
    S.latest = last.id;
    if (last.status !== "running") showRun(last.id);
    else showRunning(last.id);
  }
  const first = Object.values(S.graph.outputs)[0];
  if (first) select(first[0]);
  refreshRuns();
  document.body.dataset.ready = "1";
}

main();
