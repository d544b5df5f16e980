"""``report.html``: one self-contained page to look at a run.

The page holds the graph drawn as SVG, scaled to fit the page with zoom and
pan (each node coloured by what happened to it, with its time), every
output shown by its viewer (:mod:`graphvision.views.viewers`: float maps
with a colour bar, label maps in distinct colours, point clouds coloured by
depth, a classifier's confusion matrix; with script, images and float maps in
the pixel viewer of :mod:`graphvision.views.scripted`) with links to its files, the
intermediate values when they were kept, the node table (time, computed or
cached, bytes), the run's provenance and the folder's earlier runs, newest
first. Pictures are inline PNG (``data:`` URLs) and the page loads nothing
from the network, so the one file can be mailed, archived or opened offline.
"""

from __future__ import annotations

import dataclasses
import functools
import json
from collections.abc import Mapping, Sequence
from html import escape
from operator import attrgetter
from pathlib import Path
from typing import Any
from urllib.parse import quote

from graphvision.compiler.compile import CompiledGraph
from graphvision.execution.history import Earlier
from graphvision.execution.owned import write_file
from graphvision.execution.record import RunRecord
from graphvision.values.ports import PortType
from graphvision.values.scalars import TablePort
from graphvision.views.graph_view import (
    GRAPH_SCRIPT,
    GRAPH_STYLE,
    graph_drawing,
    graph_html,
    graph_json,
    layout_script,
)
from graphvision.views.linked import LINKED_STYLE, shown_html
from graphvision.views.pairing import outputs_by_ref
from graphvision.views.scripted import SCRIPTED_STYLE, PageValues
from graphvision.views.viewers import picture_html, value_html

__all__ = ["html_report", "picture_html", "value_html", "write_html_report"]

_STYLE = (
    """
body { font-family: sans-serif; margin: 2em auto; max-width: 1100px; color: #222;
       padding: 0 1em; }
h1 { margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; }
.summary { color: #555; } .failed { color: #b71c1c; }
.outputs { display: flex; flex-wrap: wrap; gap: 1.5em; }
.output { max-width: 520px; overflow-x: auto; }
.output.wide { flex-basis: 100%; max-width: none; }
.output img { max-width: 100%; image-rendering: pixelated; }
.files { font-size: 0.85em; } .files a { margin-right: 0.6em; }
.colourbar { margin: 0.3em 0; } .colourbar figcaption { font-size: 0.8em; color: #555; }
.range { font-size: 0.8em; color: #555; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border: 1px solid #ddd; padding: 0.2em 0.6em; text-align: right; }
th { background: #f5f5f5; } td.text { text-align: left; }
table.confusion { margin-bottom: 0.8em; } table.confusion caption { text-align: left; }
table.confusion td.right { background: rgba(46, 125, 50, calc(var(--share) * 0.6)); }
table.confusion td.wrong { background: rgba(183, 28, 28, calc(var(--share) * 0.6)); }
.value { font-size: 1.6em; font-weight: bold; }
"""
    + GRAPH_STYLE
    + LINKED_STYLE
    + SCRIPTED_STYLE
)


def html_report(
    compiled: CompiledGraph,
    outputs: Mapping[str, Any],
    record: RunRecord,
    *,
    intermediates: Mapping[str, tuple[type[PortType], Any]] | None = None,
    failures: Mapping[str, str] | None = None,
    earlier: Sequence[Earlier] = (),
) -> str:
    """The report page as a string.

    Parameters
    ----------
    compiled : CompiledGraph
        The graph that ran.
    outputs : mapping
        Output name → value (outputs that were not produced are listed as such).
    record : RunRecord
        What happened to each node, and the run's provenance; its ``files``
        (output name → file names in the run's folder) are linked.
    intermediates : mapping, optional
        Node output (``node`` or ``node.port``) → (port type, value): each
        shown by its viewer, as outputs are.
    failures : mapping, optional
        Node name → error message.
    earlier : sequence of Earlier, optional
        The folder's earlier runs, newest first (linked to their kept reports).
    """
    head, body = _page(compiled, outputs, record, intermediates, failures, earlier)
    return f"{head}{_STYLE}</style></head><body>{body}{_tail()}"


def _page(
    compiled: CompiledGraph,
    outputs: Mapping[str, Any],
    record: RunRecord,
    intermediates: Mapping[str, tuple[type[PortType], Any]] | None,
    failures: Mapping[str, str] | None,
    earlier: Sequence[Earlier],
) -> tuple[str, str]:
    """The page's own parts, around its constant ones (:func:`_tail` and the style): the
    head up to its ``<style>``, and the body up to the scripts every page has."""
    graph = compiled.graph
    status = {node.name: node.status for node in record.nodes}
    seconds = {node.name: node.seconds for node in record.nodes if node.status == "computed"}
    failures = dict(failures or {})
    failures.update({node.name: node.error for node in record.nodes if node.error})
    body = [_header_html(compiled, record)]
    if failures:
        items = "".join(
            f"<li><b>{escape(name)}</b>: {escape(message)}</li>"
            for name, message in failures.items()
        )
        body.append(f'<ul class="failed">{items}</ul>')
    drawn = graph_html(graph_drawing(graph, status, seconds), graph_json(compiled, status, seconds))
    body += ["<h2>Graph</h2>", drawn]
    found = outputs_by_ref(compiled, outputs, intermediates)
    page = PageValues(compiled, found)
    body += ["<h2>Outputs</h2>", _outputs_html(compiled, outputs, record.files, page)]
    if intermediates:
        body += ["<h2>Intermediate values</h2>", _intermediates_html(intermediates, page)]
    body += ["<h2>Nodes</h2>", _nodes_html(record), "<h2>Provenance</h2>", _provenance_html(record)]
    if earlier:
        body += ["<h2>Earlier runs (newest first)</h2>", _earlier_html(earlier)]
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>{escape(graph.name)}: graphvision report</title><style>",
        f"{''.join(body)}{page.script()}",
    )


def _intermediates_html(
    intermediates: Mapping[str, tuple[type[PortType], Any]], page: PageValues
) -> str:
    """Each intermediate value by its viewer; a table folded (its summary shows)."""
    shown = []
    compiled, found = page.compiled, page.found
    for where, (kind, value) in intermediates.items():
        node, _, port = where.partition(".")
        step = compiled.steps.get(node)
        port = port or (next(iter(step.outputs)) if step is not None else "")
        view = shown_html(compiled, found, (node, port), kind, value, where, page)
        if issubclass(kind, TablePort):
            view = f"<details><summary>{escape(kind.summary(value))}</summary>{view}</details>"
        shown.append(f'<div class="output"><h3>{escape(where)}</h3>{view}</div>')
    return f'<div class="outputs">{"".join(shown)}</div>'


def _header_html(compiled: CompiledGraph, record: RunRecord) -> str:
    """Title, description, what ran, and links to the run's own files when it has a folder."""
    graph = compiled.graph
    counts = ", ".join(
        f"{record.count(s)} {s}"
        for s in ("computed", "cached", "failed", "skipped")
        if record.count(s)
    )
    own = ""
    if record.files:
        own = (
            '<p class="files">'
            + "".join(_file_link(name) for name in ("record.json", "report.md"))
            + "</p>"
        )
    return (
        f"<h1>{escape(graph.name)}</h1>"
        + (f"<p>{escape(graph.description.strip())}</p>" if graph.description else "")
        + f'<p class="summary">{escape(counts or "nothing ran")} in {record.seconds:.3f} s '
        f"({escape(record.executor)}){', ' + escape(record.date) if record.date else ''}</p>" + own
    )


def _file_link(name: str, prefix: str = "") -> str:
    """A link to file ``name`` of the run's folder: relative, percent-encoded, so that
    no file name can become a scheme, a query or a fragment."""
    return f'<a href="./{escape(quote(prefix + name, safe="/"))}">{escape(name)}</a>'


def _outputs_html(
    compiled: CompiledGraph,
    outputs: Mapping[str, Any],
    files: Mapping[str, list[str]],
    page: PageValues,
) -> str:
    sections = []
    for name in compiled.outputs:
        kind = compiled.output_type(name)
        where = tuple(compiled.outputs[name])
        shown = (
            shown_html(compiled, page.found, where, kind, outputs[name], name, page)  # type: ignore[arg-type]
            if name in outputs
            else '<p class="failed">not produced</p>'
        )
        links = "".join(_file_link(file) for file in files.get(name, []))
        if links:
            shown += f'<p class="files">files: {links}</p>'
        wide = " wide" if issubclass(kind, TablePort) else ""
        title = f"{escape(name)} <small>{escape(kind.type_name())}</small>"
        sections.append(f'<div class="output{wide}"><h3>{title}</h3>{shown}</div>')
    return f'<div class="outputs">{"".join(sections)}</div>'


def _earlier_html(earlier: Sequence[Earlier]) -> str:
    """One row per earlier run: when, what ran, its overrides, links to its kept report."""
    rows = []
    for run in earlier:
        nodes = run.record.get("nodes") or []
        states = [n.get("status", "") for n in nodes if isinstance(n, dict)]
        ran = ", ".join(
            f"{states.count(s)} {s}" for s in ("computed", "cached", "failed") if states.count(s)
        )
        seconds = run.record.get("seconds")
        took = f"{seconds:.3f} s" if isinstance(seconds, int | float) else ""
        overrides = json.dumps(run.record.get("overrides") or {}, default=str)
        links = "".join(
            _file_link(name, run.folder + "/") for name in ("report.html", "record.json")
        )
        rows.append(
            f'<tr><td class="text">{escape(run.date or "?")}</td><td class="text">'
            f'{escape(ran)}</td><td>{took}</td><td class="text"><code>{escape(overrides)}'
            f'</code></td><td class="text files">{links}</td></tr>'
        )
    head = "".join(f"<th>{h}</th>" for h in ("date", "nodes", "time", "overrides", "kept"))
    return f'<table class="earlier"><tr>{head}</tr>{"".join(rows)}</table>'


def _nodes_html(record: RunRecord) -> str:
    rows = "".join(
        f'<tr><td class="text">{escape(n.name)}</td><td class="text">{escape(n.op)}</td>'
        f'<td class="text">{escape(n.status)}</td><td>{n.seconds * 1e3:.1f}</td>'
        f'<td>{n.output_bytes}</td><td class="text">{escape(n.backend)}</td></tr>'
        for n in record.nodes
    )
    head = "".join(f"<th>{h}</th>" for h in ("node", "op", "status", "ms", "bytes", "backend"))
    return f"<table><tr>{head}</tr>{rows}</table>"


_JSON_TEXT = json.JSONEncoder(default=str).encode
"""``json.dumps(value, default=str)``, its encoder made once (``dumps`` makes one per call
when given ``default``)."""


def _provenance_html(record: RunRecord) -> str:
    """Every field of the record but its nodes and outputs, as a two-column table."""
    rows = "".join(
        f"{head}{escape(value if isinstance(value, str) else _JSON_TEXT(value))}</code></td></tr>"
        for head, value in zip(_PROVENANCE_HEADS, attrgetter(*_PROVENANCE)(record), strict=True)
    )
    return f"<table>{rows}</table>"


_PROVENANCE = tuple(
    f.name for f in dataclasses.fields(RunRecord) if f.name not in ("nodes", "outputs")
)
"""The record's fields :func:`_provenance_html` shows, in their order."""

_PROVENANCE_HEADS = tuple(
    f'<tr><th>{escape(name)}</th><td class="text"><code>' for name in _PROVENANCE
)
"""Each of their rows up to its value (the same for every page)."""


def write_html_report(
    compiled: CompiledGraph,
    outputs: Mapping[str, Any],
    record: RunRecord,
    directory: Path,
    *,
    intermediates: Mapping[str, tuple[type[PortType], Any]] | None = None,
    failures: Mapping[str, str] | None = None,
    earlier: Sequence[Earlier] = (),
) -> Path:
    """Write ``report.html`` into ``directory`` (see :func:`html_report`, the same bytes as
    its text in UTF-8); return its path."""
    path = directory / "report.html"
    head, body = _page(compiled, outputs, record, intermediates, failures, earlier)
    style, tail = _encoded()
    write_file(path, b"".join((head.encode(), style, body.encode(), tail)))
    return path


def _tail() -> str:
    """The end of every page: the layout bundle (74 KB), the zoom script, the closing tags."""
    return f"{layout_script()}{GRAPH_SCRIPT}</body></html>\n"


@functools.cache
def _encoded() -> tuple[bytes, bytes]:
    """The style through ``<body>``, and :func:`_tail`, as UTF-8, encoded once: a batch
    wrote the same 78 KB (with a non-ASCII character, so as a copy of two bytes a
    character) into each file's page, joined and encoded again each time, about a third of
    a count-only page's CPU, all of it holding the GIL."""
    return f"{_STYLE}</style></head><body>".encode(), _tail().encode()
