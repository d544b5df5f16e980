"""The graph in a page: its SVG scaled to fit the page's width, with zoom and pan.

The drawing (:func:`graphvision.graph.svg.graph_svg`) keeps its ``viewBox``
and loses its fixed size, so that it scales to its container (never wider
than the page). A few lines of script, inline, zoom with the wheel or the
``+``/``−`` buttons, pan by dragging, and ``fit`` shows the whole graph
again; without script the graph still fits.

Given the graph's nodes and edges (:func:`graph_data`), the page lays it out
again with the studio's layered layout (dagre, bundled in ``static/graph.js``
by ``frontend/build.sh`` and inlined by :func:`layout_script`: no network), so
no two boxes or edge labels overlap; the drawn SVG stays as the page's look
without script.
"""

from __future__ import annotations

import functools
import json
import math
import re
import threading
import weakref
from collections.abc import Mapping
from html import escape
from pathlib import Path
from typing import Any

__all__ = [
    "GRAPH_SCRIPT",
    "GRAPH_STYLE",
    "graph_data",
    "graph_drawing",
    "graph_html",
    "graph_json",
    "layout_script",
]

_BUNDLE = Path(__file__).parent / "static" / "graph.js"

GRAPH_STYLE = """
.graph { border: 1px solid #eee; padding: 0.5em; }
.graph svg { display: block; width: 100%; height: auto; max-height: 75vh; cursor: grab;
             margin: 0 auto; }
.graph .zoom { text-align: right; }
.graph .zoom button { min-width: 2.2em; margin-left: 0.2em; }
"""

GRAPH_SCRIPT = """<script>
document.querySelectorAll(".graph").forEach(box => {
  const svg = box.querySelector("svg");
  if (!svg || box.dataset.zoom) return;  // (a notebook runs this once per shown page)
  box.dataset.zoom = "on";
  const whole = svg.viewBox.baseVal;
  const home = [whole.x, whole.y, whole.width, whole.height];
  let view = home.slice();
  const show = () => svg.setAttribute("viewBox", view.join(" "));
  const zoom = (factor, cx, cy) => {
    const w = view[2] * factor, h = view[3] * factor;
    if (w < home[2] / 20 || w > home[2] * 4) return;
    cx = cx ?? view[0] + view[2] / 2; cy = cy ?? view[1] + view[3] / 2;
    view = [cx - (cx - view[0]) * factor, cy - (cy - view[1]) * factor, w, h];
    show();
  };
  const point = e => {
    const r = svg.getBoundingClientRect();
    return [view[0] + (e.clientX - r.left) / r.width * view[2],
            view[1] + (e.clientY - r.top) / r.height * view[3]];
  };
  svg.addEventListener("wheel", e => {
    e.preventDefault(); zoom(e.deltaY < 0 ? 0.8 : 1.25, ...point(e));
  }, {passive: false});
  let drag = null;
  svg.addEventListener("pointerdown", e => {
    drag = point(e); svg.setPointerCapture(e.pointerId);
  });
  svg.addEventListener("pointermove", e => {
    if (!drag) return;
    const [x, y] = point(e);
    view[0] -= x - drag[0]; view[1] -= y - drag[1]; show();
  });
  svg.addEventListener("pointerup", () => { drag = null; });
  const act = {"+": () => zoom(0.8), "\u2212": () => zoom(1.25),
               "fit": () => { view = home.slice(); show(); }};
  box.querySelectorAll(".zoom button").forEach(
    b => b.addEventListener("click", act[b.textContent]));
});
</script>"""


@functools.cache
def layout_script() -> str:
    """The layout bundle and the calls that lay out every graph of the page and draw its
    values with the studio's viewers (:mod:`graphvision.views.scripted`), as an inline
    ``<script>`` (empty when the bundle was not built: the drawn SVG and pictures stay)."""
    if not _BUNDLE.is_file():
        return ""
    code = _BUNDLE.read_text(encoding="utf-8").replace("</script", "<\\/script")
    return (
        f"<script>{code}\nGraphvisionGraph.layOutPage();\n"
        "if (GraphvisionGraph.showValues) GraphvisionGraph.showValues();</script>"
    )


def graph_data(compiled: Any, status: dict[str, str], seconds: dict[str, float]) -> dict:
    """The graph's nodes (with what happened to each) and edges, for the page's layout."""
    graph = compiled.graph
    nodes: list[dict[str, Any]] = [
        {"id": name, "kind": "input", "type": decl.type} for name, decl in graph.inputs.items()
    ]
    edges = []
    for name, step in compiled.steps.items():
        nodes.append({"id": name, "kind": "node", "op": step.spec.id,
                      "status": status.get(name, ""), "seconds": seconds.get(name)})  # fmt: skip
        for port, (source, source_port) in step.inputs.items():
            edges.append({"from": source, "from_port": source_port, "to": name, "port": port})
    return {"nodes": nodes, "edges": edges}


def graph_html(svg: str, data: dict | str | None = None) -> str:
    """``svg`` (a graph drawing) made to shrink to its container (never enlarged beyond
    its own size), with zoom buttons; with ``data`` (:func:`graph_data`, or its JSON text:
    :func:`graph_json`) the page lays the graph out again (see the module)."""
    size = re.search(r'<svg[^>]*? width="([\d.]+)" height="[\d.]+"', svg)
    fitted = re.sub(r'(<svg[^>]*?) width="[\d.]+" height="[\d.]+"', r"\1", svg, count=1)
    largest = f' style="max-width: {size.group(1)}px"' if size else ""
    fitted = fitted.replace("<svg ", f'<svg preserveAspectRatio="xMidYMid meet"{largest} ', 1)
    buttons = "".join(f'<button type="button">{b}</button>' for b in ("+", "\u2212", "fit"))
    if data is None:
        return f'<div class="graph"><div class="zoom">{buttons}</div>{fitted}</div>'
    text = (data if isinstance(data, str) else json.dumps(data)).replace("</", "<\\/")
    return (
        f'<div class="graph"><div class="zoom">{buttons}</div>{fitted}'
        f'<script type="application/json" data-graph="1">{text}</script></div>'
    )


def graph_json(compiled: Any, status: Mapping[str, str], seconds: Mapping[str, float]) -> str:
    """``json.dumps(graph_data(compiled, status, seconds))``, the same text, from the
    graph's parts encoded once per compiled graph (:func:`_encoded_parts`): a batch's
    files have one graph, and only their nodes' states and times differ (``json``
    encoding the whole of it was a fifth of a count-only page's own Python, holding
    the GIL)."""
    inputs, nodes, edges = _encoded_parts(compiled)
    shown = [
        f"{head}{_json_scalar(status.get(name, ''))}, "
        f'"seconds": {_json_scalar(seconds.get(name))}}}'
        for name, head in nodes
    ]
    return f'{{"nodes": [{", ".join([*inputs, *shown])}], "edges": {edges}}}'


def _json_scalar(value: Any) -> str:
    """``json.dumps(value)``, a finite float and None written directly."""
    if value is None:
        return "null"
    if type(value) is float and math.isfinite(value):
        return float.__repr__(value)  # (as json writes a float)
    return json.dumps(value)


_KEPT = 8  # drawings kept (a batch draws one graph, a sweep a few)
_KEEPING = threading.Lock()

_PARTS: dict[int, tuple[weakref.ref[Any], tuple[list[str], list[tuple[str, str]], str]]] = {}


def _encoded_parts(compiled: Any) -> tuple[list[str], list[tuple[str, str]], str]:
    """:func:`graph_data` of ``compiled`` as JSON, in parts: its inputs' entries, each node's
    name and its entry's text up to its state (``..., "status": ``), and the edges; made
    once per compiled graph (kept while it lives, a few at a time)."""
    kept = _PARTS.get(id(compiled))
    if kept is not None and kept[0]() is compiled:
        return kept[1]
    data = graph_data(compiled, {}, {})
    inputs = [json.dumps(node) for node in data["nodes"] if node["kind"] == "input"]
    nodes = []
    for node in data["nodes"]:
        if node["kind"] != "input":
            fixed = {key: value for key, value in node.items() if key not in ("status", "seconds")}
            nodes.append((node["id"], f'{json.dumps(fixed)[:-1]}, "status": '))
    parts = (inputs, nodes, json.dumps(data["edges"]))
    with _KEEPING:
        while len(_PARTS) >= _KEPT:
            _PARTS.pop(next(iter(_PARTS)))
        _PARTS[id(compiled)] = (weakref.ref(compiled), parts)
    return parts


_DRAWINGS: dict[tuple[Any, ...], tuple[list[str], tuple[str, ...]]] = {}


def _drawn_key(graph: Any, status: Mapping[str, str], labels: Mapping[str, str]) -> tuple:
    """All that ``graph_svg``'s layout reads: the graph's name, inputs, nodes (op, inputs)
    and outputs, each node's status and the length of its time label (a box's width)."""
    nodes = tuple(
        (name, node.op, tuple((port, ref.node, ref.port) for port, ref in node.inputs.items()))
        for name, node in graph.nodes.items()
    )
    return (
        graph.name,
        tuple((name, decl.type) for name, decl in graph.inputs.items()),
        nodes,
        tuple((name, ref.node, ref.port) for name, ref in graph.outputs.items()),
        tuple(sorted(status.items())),
        tuple(sorted((name, len(label)) for name, label in labels.items())),
    )


def _label_cuts(svg: str, labels: Mapping[str, str]) -> list[str] | None:
    """``svg`` cut around each node's time label ``labels[name]`` (its box's last line), in
    the order of ``labels``: the text before the first, between each two, after the last
    (``svg`` is the cuts joined by the labels' texts); None when a box does not end with
    its label."""
    cuts, at = [], 0
    for name, label in labels.items():
        start = svg.find(f'<g class="node" data-name="{escape(name)}"', at)
        tail = f">{escape(label)}</text></g>"
        end = svg.find("</g>", start) + len("</g>") if start >= 0 else -1
        if start < 0 or not svg.startswith(tail, end - len(tail)):
            return None
        cuts.append(svg[at : end - len(tail)])
        at = end
    return [*cuts, svg[at:]]


def graph_drawing(graph: Any, status: Mapping[str, str], seconds: Mapping[str, float]) -> str:
    """:func:`~graphvision.graph.svg.graph_svg` of ``graph``, its layout made once per
    graph, nodes' states and lengths of their time labels: a batch's files draw the same
    graph with other times (2 ms a file's report), which only change the labels' text,
    written between the drawing's parts cut around them once (:func:`_label_cuts`)."""
    from graphvision.graph.svg import graph_svg, time_label

    labels = {name: time_label(s) for name, s in seconds.items() if name in graph.nodes}
    order = {name: labels[name] for name in graph.nodes if name in labels}  # as drawn
    key = _drawn_key(graph, status, order)
    kept = _DRAWINGS.get(key)
    if kept is not None:
        cuts, names = kept
        texts = [
            f">{escape(order[name])}</text></g>{cut}"
            for name, cut in zip(names, cuts[1:], strict=True)
        ]
        return cuts[0] + "".join(texts)
    svg = graph_svg(graph, status, seconds)
    made = _label_cuts(svg, order)
    if made is not None:  # its labels found where they are replaced
        with _KEEPING:  # a batch on threads writes reports at once
            while len(_DRAWINGS) >= _KEPT:
                _DRAWINGS.pop(next(iter(_DRAWINGS)))
            _DRAWINGS[key] = (made, tuple(order))
    return svg
