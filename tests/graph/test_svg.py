"""The graph drawing: well-formed SVG, edges pointing right, no overlapping boxes."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from itertools import pairwise
from pathlib import Path

import pytest

import graphvision as gv
from graphvision.graph.svg import STATUS_COLOURS, graph_svg

PIPELINES = sorted(Path(__file__).parents[2].joinpath("pipelines").glob("*.yaml"))
SVG = "{http://www.w3.org/2000/svg}"


def _boxes(root: ET.Element) -> dict[str, tuple[int, float, float, float, float, str]]:
    """name → (layer, left, top, right, bottom, fill) of every drawn vertex."""
    boxes = {}
    for group in root.iter(f"{SVG}g"):
        rect = group.find(f"{SVG}rect")
        if rect is None:
            continue
        left, top = float(rect.get("x", 0)), float(rect.get("y", 0))
        right = left + float(rect.get("width", 0))
        bottom = top + float(rect.get("height", 0))
        layer = int(group.get("data-layer", -1))
        boxes[group.get("data-name", "")] = (layer, left, top, right, bottom, rect.get("fill", ""))
    return boxes


@pytest.mark.parametrize("path", PIPELINES, ids=lambda p: p.stem)
def test_every_pipeline_draws_with_edges_left_to_right_and_no_overlap(path: Path) -> None:
    graph = gv.load_pipeline(path)
    root = ET.fromstring(graph_svg(graph))
    boxes = _boxes(root)
    expected = {*graph.inputs, *graph.nodes, *(f"output:{name}" for name in graph.outputs)}
    assert set(boxes) == expected
    edges = [g for g in root.iter(f"{SVG}g") if g.get("class") == "edge"]
    connections = sum(len(n.inputs) for n in graph.nodes.values()) + len(graph.outputs)
    assert len(edges) == connections
    for edge in edges:
        source, target = boxes[edge.get("data-source", "")], boxes[edge.get("data-target", "")]
        assert source[0] < target[0] and source[3] < target[1]  # layer and x both increase
    listed = sorted(boxes.values())
    for a, b in pairwise(listed):
        if a[0] == b[0]:  # same column: stacked, not overlapping
            assert a[4] <= b[2] or b[4] <= a[2]


def test_status_colours_times_and_escaping() -> None:
    graph = gv.Graph("a<b>&c")
    x = graph.input("x", "Float", default=1.0)
    y = graph.add("y", "bench.inc", x=x)
    z = graph.add("z", "bench.inc", x=y)
    graph.output("out", z)
    svg = graph_svg(graph, status={"y": "cached", "z": "failed"}, seconds={"y": 0.0125, "z": 2.5})
    boxes = _boxes(ET.fromstring(svg))  # parses: the title's < and & are escaped
    assert boxes["y"][5] == STATUS_COLOURS["cached"] and boxes["z"][5] == STATUS_COLOURS["failed"]
    assert "12.5 ms" in svg and "2.50 s" in svg
    assert graph._repr_svg_() == graph_svg(graph)


def test_a_cycle_still_draws() -> None:
    """An invalid graph (a cycle) is drawn, so it can be looked at; the layout terminates."""
    graph = gv.Graph("loop")
    graph.input("x", "Float")
    graph.add("a", "bench.inc", x="b")
    graph.add("b", "bench.inc", x="a")
    boxes = _boxes(ET.fromstring(graph_svg(graph)))
    assert {"a", "b", "x"} <= set(boxes)


def test_a_long_edge_is_routed_between_columns() -> None:
    """x feeds the first and the last node of a chain: its edge passes every column."""
    graph = gv.Graph("skip")
    x = graph.input("x", "Float")
    previous = x
    for i in range(4):
        previous = graph.add(f"n{i}", "bench.inc", x=previous)
    graph.add("last", "metrics.sum", a=previous, b=x)
    root = ET.fromstring(graph_svg(graph))
    skip = next(
        g
        for g in root.iter(f"{SVG}g")
        if g.get("data-source") == "x" and g.get("data-target") == "last"
    )
    path = skip.find(f"{SVG}path")
    assert path is not None and path.get("d", "").count("C") == 5  # one curve per column crossed
