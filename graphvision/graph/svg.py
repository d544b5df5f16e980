"""A graph drawn as a self-contained SVG: layered layout, no external binary.

The drawing is what ``graphvision graph --format svg``, the HTML report and a
notebook show. The layout is the classic layered one (Sugiyama, Tagawa and
Toda 1981), kept small:

1. **layers**: each vertex goes one layer right of its furthest predecessor
   (longest path from the graph inputs), so every edge points right;
2. **virtual vertices**: an edge spanning several layers is split by one
   invisible vertex per layer it crosses, so it is routed between boxes;
3. **ordering**: vertices in a layer are sorted by the mean position of their
   neighbours in the previous layer (the barycentre heuristic), sweeping
   right then left a few times to remove crossings;
4. **coordinates**: layers are columns as wide as their widest box, vertices
   are stacked in their order, each column centred vertically. A box is tall
   enough for its incoming edges to enter at least :data:`_LABEL_PITCH` apart,
   and the gap before a column wide enough for the longest edge label
   entering it, so that no two edge labels overlap, nor a label a box.

Boxes are coloured by a node's status when one is given (``computed``,
``cached``, ``failed``, ``skipped``, ``running``), with its time in the label.

References
----------
.. [1] K. Sugiyama, S. Tagawa, M. Toda, "Methods for visual understanding of
   hierarchical system structures", IEEE Trans. SMC 11(2), 1981.
.. [2] E. R. Gansner, E. Koutsofios, S. C. North, K.-P. Vo, "A technique for
   drawing directed graphs", IEEE Trans. Software Engineering 19(3), 1993.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from html import escape
from itertools import pairwise
from typing import Protocol

__all__ = ["STATUS_COLOURS", "Drawable", "graph_svg", "time_label"]


class _Reference(Protocol):
    @property
    def node(self) -> str: ...
    @property
    def port(self) -> str | None: ...


class _Declared(Protocol):
    @property
    def type(self) -> str: ...


class _Step(Protocol):
    @property
    def op(self) -> str: ...
    @property
    def inputs(self) -> Mapping[str, _Reference]: ...


class Drawable(Protocol):
    """What a drawing reads of a graph (:class:`graphvision.Graph` is one): the names of
    its inputs, its steps with their inputs, and its outputs."""

    @property
    def name(self) -> str: ...
    @property
    def inputs(self) -> Mapping[str, _Declared]: ...
    @property
    def nodes(self) -> Mapping[str, _Step]: ...
    @property
    def outputs(self) -> Mapping[str, _Reference]: ...


STATUS_COLOURS = {
    "computed": "#c8e6c9",
    "cached": "#bbdefb",
    "failed": "#ffcdd2",
    "skipped": "#eeeeee",
    "running": "#ffe0b2",
}
_INPUT_COLOUR = "#fff9c4"
_OUTPUT_COLOUR = "#e1bee7"
_CHAR_WIDTH = 7.0  # px per character at the 12 px font used
_BOX_HEIGHT = 40.0
_ROW_GAP = 18.0
_COLUMN_GAP = 60.0
_MARGIN = 12.0
_SWEEPS = 4
_LABEL_CHAR = 6.2  # px per character at the 10 px font of edge labels
_LABEL_PITCH = 15.0  # px between the ends of edges entering one side of a box (a label: 13)


@dataclass
class _Vertex:
    key: str
    lines: tuple[str, ...]
    kind: str  # "input", "node", "output" or "virtual"
    fill: str = "#ffffff"
    tooltip: str = ""
    layer: int = 0
    order: float = 0.0
    x: float = 0.0
    y: float = 0.0
    width: float = 0.0
    height: float = 0.0
    preds: list[str] = field(default_factory=list)
    label_width: float = 0.0  # of the longest label of an edge entering it


def graph_svg(
    graph: Drawable,
    status: Mapping[str, str] | None = None,
    seconds: Mapping[str, float] | None = None,
) -> str:
    """The graph as an SVG document (a string), laid out left to right.

    Parameters
    ----------
    graph : Drawable
        The graph to draw: its inputs, nodes and outputs.
    status : mapping, optional
        Node name → ``computed``, ``cached``, ``failed``, ``skipped`` or
        ``running``; colours the node's box.
    seconds : mapping, optional
        Node name → time it took; shown under the node's op.

    Returns
    -------
    svg : str
        A standalone ``<svg>`` element with a ``viewBox`` (scales to its container).
    """
    status, seconds = status or {}, seconds or {}
    vertices = _vertices(graph, status, seconds)
    edges = _edges(graph, vertices)
    _make_room_for_labels(vertices, edges)
    _assign_layers(vertices)
    routed = _split_long_edges(vertices, edges)
    layers = _order_layers(vertices)
    width, height = _place(vertices, layers)
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {width:.0f} {height:.0f}" '
        f'width="{width:.0f}" height="{height:.0f}" font-family="sans-serif" font-size="12">',
        f"<title>{escape(graph.name)}</title>",
        '<defs><marker id="arrow" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" '
        'markerHeight="7" orient="auto"><path d="M0,0 L10,5 L0,10 z" fill="#555"/></marker></defs>',
    ]
    ends = _edge_ends(vertices, routed)
    parts += [
        _edge_path(vertices, chain, label, end)
        for (chain, label), end in zip(routed, ends, strict=True)
    ]
    parts += [_box(v) for v in vertices.values() if v.kind != "virtual"]
    parts.append("</svg>")
    return "\n".join(parts)


def time_label(seconds: float) -> str:
    """A node's time as its box shows it under its op (``12.3 ms``, ``1.25 s``)."""
    return f"{seconds * 1e3:.1f} ms" if seconds < 1 else f"{seconds:.2f} s"


def _vertices(
    graph: Drawable, status: Mapping[str, str], seconds: Mapping[str, float]
) -> dict[str, _Vertex]:
    vertices: dict[str, _Vertex] = {}
    for name, decl in graph.inputs.items():
        vertices[name] = _Vertex(
            name, (name, decl.type), "input", _INPUT_COLOUR, f"graph input {name}: {decl.type}"
        )
    for name, node in graph.nodes.items():
        state = status.get(name, "")
        lines = [name, node.op]
        if name in seconds:
            lines.append(time_label(seconds[name]))
        tooltip = f"{name}: {node.op}" + (f" ({state})" if state else "")
        fill = STATUS_COLOURS.get(state, "#ffffff")
        vertices[name] = _Vertex(name, tuple(lines), "node", fill, tooltip)
    for name in graph.outputs:
        key = f"output:{name}"
        vertices[key] = _Vertex(key, (name,), "output", _OUTPUT_COLOUR, f"graph output {name}")
    for vertex in vertices.values():
        longest = max(len(line) for line in vertex.lines)
        vertex.width = max(60.0, longest * _CHAR_WIDTH + 20)
        vertex.height = _BOX_HEIGHT if len(vertex.lines) < 3 else _BOX_HEIGHT + 14
    return vertices


def _edges(graph: Drawable, vertices: dict[str, _Vertex]) -> list[tuple[str, str, str]]:
    """(source, target, label) for each connection whose ends exist."""
    edges = []
    for name, node in graph.nodes.items():
        for port, ref in node.inputs.items():
            if ref.node in vertices:
                label = port if len(node.inputs) > 1 else ""
                edges.append((ref.node, name, (f"{ref.port}→" if ref.port else "") + label))
    for name, ref in graph.outputs.items():
        if ref.node in vertices:
            edges.append((ref.node, f"output:{name}", ref.port or ""))
    for source, target, _ in edges:
        vertices[target].preds.append(source)
    return edges


def _make_room_for_labels(vertices: dict[str, _Vertex], edges: list[tuple[str, str, str]]) -> None:
    """Each box tall enough for its edges to meet each side :data:`_LABEL_PITCH` apart (a
    label sits just above its edge's end), and knowing how wide its entering labels are."""
    entering: dict[str, int] = {}
    leaving: dict[str, int] = {}
    for source, target, label in edges:
        entering[target] = entering.get(target, 0) + 1
        leaving[source] = leaving.get(source, 0) + 1
        width = len(label) * _LABEL_CHAR if label else 0.0
        vertices[target].label_width = max(vertices[target].label_width, width)
    for key, vertex in vertices.items():
        ends = max(entering.get(key, 0), leaving.get(key, 0))
        vertex.height = max(vertex.height, _LABEL_PITCH * (ends + 1) + 12)


def _assign_layers(vertices: dict[str, _Vertex]) -> None:
    """Longest path from the sources; a cycle (an invalid graph) is cut where it closes."""
    done: dict[str, int] = {}
    visiting: set[str] = set()
    for start in vertices:
        stack: list[tuple[str, int]] = [(start, 0)]
        while stack:
            key, index = stack.pop()
            if key in done:
                continue
            visiting.add(key)
            preds = vertices[key].preds
            if index < len(preds):
                stack.append((key, index + 1))
                pred = preds[index]
                if pred not in done and pred not in visiting:
                    stack.append((pred, 0))
                continue
            visiting.discard(key)
            done[key] = 1 + max((done[p] for p in preds if p in done), default=-1)
    for key, layer in done.items():
        vertices[key].layer = layer


def _split_long_edges(
    vertices: dict[str, _Vertex], edges: list[tuple[str, str, str]]
) -> list[tuple[list[str], str]]:
    """Each edge as the chain of vertices it passes, with virtual ones between layers."""
    routed = []
    for number, (source, target, label) in enumerate(edges):
        chain = [source]
        first, last = vertices[source].layer, vertices[target].layer
        for layer in range(first + 1, last):
            key = f"virtual:{number}:{layer}"
            vertices[key] = _Vertex(key, ("",), "virtual", layer=layer, width=1.0, height=1.0)
            vertices[key].preds.append(chain[-1])
            chain.append(key)
        if len(chain) > 1:
            target_preds = vertices[target].preds
            target_preds[target_preds.index(source)] = chain[-1]
        chain.append(target)
        routed.append((chain, label))
    return routed


def _order_layers(vertices: dict[str, _Vertex]) -> list[list[_Vertex]]:
    """Vertices per layer, ordered by barycentres over a few sweeps."""
    count = 1 + max((v.layer for v in vertices.values()), default=0)
    layers: list[list[_Vertex]] = [[] for _ in range(count)]
    for vertex in vertices.values():
        layers[vertex.layer].append(vertex)
    succs: dict[str, list[str]] = {key: [] for key in vertices}
    for vertex in vertices.values():
        for pred in vertex.preds:
            succs[pred].append(vertex.key)
    for layer in layers:
        for position, vertex in enumerate(layer):
            vertex.order = position
    for sweep in range(_SWEEPS):
        rightwards = sweep % 2 == 0
        sequence = layers[1:] if rightwards else layers[-2::-1]
        for layer in sequence:
            for vertex in layer:
                neighbours = vertex.preds if rightwards else succs[vertex.key]
                if neighbours:
                    vertex.order = sum(vertices[n].order for n in neighbours) / len(neighbours)
            layer.sort(key=lambda v: v.order)
            for position, vertex in enumerate(layer):
                vertex.order = position
    return layers


def _place(vertices: dict[str, _Vertex], layers: list[list[_Vertex]]) -> tuple[float, float]:
    """Column and row coordinates (box centres); the drawing's width and height."""
    heights = [sum(v.height + _ROW_GAP for v in layer) - _ROW_GAP for layer in layers]
    total_height = max(heights, default=0.0) + 2 * _MARGIN
    x = _MARGIN - _COLUMN_GAP
    for layer, height in zip(layers, heights, strict=True):
        labels = max((v.label_width for v in layer), default=0.0)
        x += _COLUMN_GAP if x < _MARGIN else max(_COLUMN_GAP, labels + 16)
        column = max((v.width for v in layer), default=0.0)
        y = (total_height - height) / 2
        for vertex in layer:
            vertex.x = x + column / 2
            vertex.y = y + vertex.height / 2
            y += vertex.height + _ROW_GAP
        x += column
    return x + _MARGIN, total_height


def _edge_ends(
    vertices: dict[str, _Vertex], routed: list[tuple[list[str], str]]
) -> list[tuple[float, float]]:
    """Where each edge leaves its source and enters its target (y of each), spread over the side.

    Edges that meet one side of a box are spread over its height in the order
    of the vertices at their other end, so that they neither cross at the box
    nor share one arrow head.
    """
    leaving: dict[str, list[int]] = {}
    entering: dict[str, list[int]] = {}
    for number, (chain, _) in enumerate(routed):
        leaving.setdefault(chain[0], []).append(number)
        entering.setdefault(chain[-1], []).append(number)
    ends = [(0.0, 0.0)] * len(routed)
    for side, groups in ((0, leaving), (1, entering)):
        for key, numbers in groups.items():
            box = vertices[key]
            other = 1 if side == 0 else -2  # the next vertex along the edge
            numbers.sort(key=lambda n: vertices[routed[n][0][other]].y)
            span = box.height - 12
            for rank, number in enumerate(numbers):
                y = box.y + (span * ((rank + 1) / (len(numbers) + 1) - 0.5))
                start, end = ends[number]
                ends[number] = (y, end) if side == 0 else (start, y)
    return ends


def _edge_path(
    vertices: dict[str, _Vertex], chain: list[str], label: str, ends: tuple[float, float]
) -> str:
    points = [(vertices[k].x, vertices[k].y) for k in chain]
    start, end = vertices[chain[0]], vertices[chain[-1]]
    points[0] = (start.x + start.width / 2, ends[0])
    points[-1] = (end.x - end.width / 2, ends[1])
    path = f"M{points[0][0]:.1f},{points[0][1]:.1f}"
    for (x0, y0), (x1, y1) in pairwise(points):
        middle = (x0 + x1) / 2
        path += f" C{middle:.1f},{y0:.1f} {middle:.1f},{y1:.1f} {x1:.1f},{y1:.1f}"
    text = ""
    if label:
        lx, ly = points[-1][0] - 6, points[-1][1] - 4
        text = (
            f'<text x="{lx:.1f}" y="{ly:.1f}" text-anchor="end" font-size="10" '
            f'fill="#555">{escape(label)}</text>'
        )
    tooltip = f"{chain[0]} → {chain[-1]}" + (f" ({label})" if label else "")
    return (
        f'<g class="edge" data-source="{escape(chain[0])}" data-target="{escape(chain[-1])}">'
        f"<title>{escape(tooltip)}</title>"
        f'<path d="{path}" fill="none" stroke="#555" marker-end="url(#arrow)"/>{text}</g>'
    )


def _box(vertex: _Vertex) -> str:
    left, top = vertex.x - vertex.width / 2, vertex.y - vertex.height / 2
    radius = vertex.height / 2 if vertex.kind in ("input", "output") else 6
    first_line = vertex.y - 7 * (len(vertex.lines) - 1) + 4
    styles = ['font-weight="bold"'] + ['fill="#333"'] * (len(vertex.lines) - 1)
    texts = "".join(
        f'<text x="{vertex.x:.1f}" y="{first_line + 14 * i:.1f}" text-anchor="middle" '
        f"{style}>{escape(line)}</text>"
        for i, (line, style) in enumerate(zip(vertex.lines, styles, strict=True))
    )
    return (
        f'<g class="{vertex.kind}" data-name="{escape(vertex.key)}" data-layer="{vertex.layer}">'
        f"<title>{escape(vertex.tooltip)}</title>"
        f'<rect x="{left:.1f}" y="{top:.1f}" width="{vertex.width:.1f}" '
        f'height="{vertex.height:.1f}" rx="{radius:.1f}" fill="{vertex.fill}" stroke="#333"/>'
        f"{texts}</g>"
    )
