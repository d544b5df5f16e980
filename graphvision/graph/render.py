"""A graph as text or a picture: DOT (Graphviz), Mermaid, or SVG.

One walk over the graph gives its vertices (inputs, nodes, outputs) and
edges with their port labels; each format writes that same list its own way.
SVG needs no external program (:mod:`graphvision.graph.svg` lays it out).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

from graphvision.graph.model import Graph

__all__ = ["FORMATS", "render"]

FORMATS = ("dot", "mermaid", "svg")
Format = Literal["dot", "mermaid", "svg"]


def render(
    graph: Graph,
    format: Format = "svg",
    *,
    status: Mapping[str, str] | None = None,
    seconds: Mapping[str, float] | None = None,
) -> str:
    """The graph as DOT, Mermaid or SVG text.

    Parameters
    ----------
    graph : Graph
        The graph to draw.
    format : {"dot", "mermaid", "svg"}
        DOT for Graphviz, Mermaid for Markdown renderers, SVG to look at as it is.
    status, seconds : mapping, optional
        SVG only: node name → status (colours the box) and time.
    """
    if format == "svg":
        from graphvision.graph.svg import graph_svg

        return graph_svg(graph, status, seconds)
    if format not in FORMATS:
        raise ValueError(f"unknown format '{format}'; choose one of {', '.join(FORMATS)}")
    dot = format == "dot"
    lines = ["digraph pipeline {", "  rankdir=LR;"] if dot else ["flowchart LR"]
    for name, decl in graph.inputs.items():
        lines.append(
            f'  {name} [shape=ellipse, label="{name}\\n{decl.type}"];'
            if dot
            else f"  {name}([{name}: {decl.type}])"
        )
    for name, node in graph.nodes.items():
        lines.append(
            f'  {name} [shape=box, label="{name}\\n{node.op}"];'
            if dot
            else f'  {name}["{name}<br/>{node.op}"]'
        )
    for name, node in graph.nodes.items():
        for port, ref in node.inputs.items():
            label = f"{ref.port or ''}→{port}"
            lines.append(
                f'  {ref.node} -> {name} [label="{label}"];'
                if dot
                else f"  {ref.node} -->|{label}| {name}"
            )
    for name, ref in graph.outputs.items():
        lines.append(
            f'  out_{name} [shape=note, label="{name}"];\n  {ref.node} -> out_{name};'
            if dot
            else f"  {ref.node} --> out_{name}[/{name}/]"
        )
    if dot:
        lines.append("}")
    return "\n".join(lines)
