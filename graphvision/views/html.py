"""``report.html``: one self-contained page to look at a run.

The page holds the graph drawn as SVG (each node coloured by what happened to
it, with its time), a picture of every output (each port type's
``preview``: images as images, masks and labels coloured, point sets drawn),
tables as tables and scalars as numbers, the node table (time, computed or
cached, bytes) and the run's provenance. Pictures are inline PNG
(``data:`` URLs) and the page loads nothing from the network, so the one
file can be mailed, archived or opened offline.
"""

from __future__ import annotations

import base64
import dataclasses
import json
from collections.abc import Mapping, Sequence
from html import escape
from pathlib import Path
from typing import Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph
from graphvision.execution.record import RunRecord
from graphvision.values.ports import PortType
from graphvision.values.scalars import TablePort, _ScalarPort

__all__ = ["batch_page", "html_report", "picture_html", "value_html", "write_html_report"]

_TABLE_ROWS = 50
_STYLE = """
body { font-family: sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; }
.summary { color: #555; } .failed { color: #b71c1c; }
.graph { overflow-x: auto; border: 1px solid #eee; padding: 0.5em; }
.outputs { display: flex; flex-wrap: wrap; gap: 1.5em; }
.output { max-width: 520px; overflow-x: auto; }
.output.wide { flex-basis: 100%; max-width: none; }
.output img { max-width: 512px; image-rendering: pixelated; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border: 1px solid #ddd; padding: 0.2em 0.6em; text-align: right; }
th { background: #f5f5f5; } td.text { text-align: left; }
.value { font-size: 1.6em; font-weight: bold; }
"""


def picture_html(picture: np.ndarray, alt: str) -> str:
    """An ``<img>`` holding ``picture`` (a [0, 1] array) as an inline PNG thumbnail."""
    from graphvision.values.pictures import png_bytes, thumbnail

    data = base64.b64encode(png_bytes(thumbnail(picture))).decode("ascii")
    return f'<img alt="{escape(alt)}" src="data:image/png;base64,{data}">'


def value_html(kind: type[PortType], value: Any, name: str) -> str:
    """How a value of port type ``kind`` is shown: a picture, a table, a number or its summary."""
    if issubclass(kind, _ScalarPort):
        shown = f"{value:.6g}" if isinstance(value, float) else str(value)
        return f'<div class="value">{escape(shown)}</div>'
    if issubclass(kind, TablePort):
        return _table_html(value)
    parts = [f"<p>{escape(kind.summary(value))}</p>"]
    picture = kind.preview(value)
    if picture is not None:
        parts.append(picture_html(picture, name))
    elif isinstance(value, np.ndarray) and value.size <= 16:  # a homography, a camera matrix
        parts.append(f"<pre>{escape(np.array2string(value, precision=6))}</pre>")
    return "".join(parts)


def _table_html(table: Mapping[str, np.ndarray]) -> str:
    columns = list(table)
    count = len(next(iter(table.values()))) if columns else 0
    head = "".join(f"<th>{escape(c)}</th>" for c in columns)
    rows = []
    for i in range(min(count, _TABLE_ROWS)):
        cells = []
        for column in columns:
            item = table[column][i]
            text = f"{item:.4g}" if isinstance(item, float | np.floating) else str(item)
            cells.append(f"<td>{escape(text)}</td>")
        rows.append(f"<tr>{''.join(cells)}</tr>")
    more = f"<p>{count - _TABLE_ROWS} more rows in the CSV</p>" if count > _TABLE_ROWS else ""
    return f"<table><tr>{head}</tr>{''.join(rows)}</table>{more}"


def html_report(
    compiled: CompiledGraph,
    outputs: Mapping[str, Any],
    record: RunRecord,
    *,
    intermediates: Mapping[str, tuple[type[PortType], Any]] | None = None,
    failures: Mapping[str, str] | None = None,
) -> str:
    """The report page as a string.

    Parameters
    ----------
    compiled : CompiledGraph
        The graph that ran.
    outputs : mapping
        Output name → value (outputs that were not produced are listed as such).
    record : RunRecord
        What happened to each node, and the run's provenance.
    intermediates : mapping, optional
        Node output (``node`` or ``node.port``) → (port type, value): shown as
        thumbnails when their type has a picture.
    failures : mapping, optional
        Node name → error message.
    """
    from graphvision.graph.svg import graph_svg

    graph = compiled.graph
    status = {node.name: node.status for node in record.nodes}
    seconds = {node.name: node.seconds for node in record.nodes if node.status == "computed"}
    failures = dict(failures or {})
    failures.update({node.name: node.error for node in record.nodes if node.error})
    counts = ", ".join(
        f"{record.count(s)} {s}"
        for s in ("computed", "cached", "failed", "skipped")
        if record.count(s)
    )
    body = [
        f"<h1>{escape(graph.name)}</h1>",
        f"<p>{escape(graph.description.strip())}</p>" if graph.description else "",
        f'<p class="summary">{escape(counts or "nothing ran")} in {record.seconds:.3f} s '
        f"({escape(record.executor)})</p>",
    ]
    if failures:
        items = "".join(
            f"<li><b>{escape(name)}</b>: {escape(message)}</li>"
            for name, message in failures.items()
        )
        body.append(f'<ul class="failed">{items}</ul>')
    body += ["<h2>Graph</h2>", f'<div class="graph">{graph_svg(graph, status, seconds)}</div>']
    body.append("<h2>Outputs</h2>")
    sections = []
    for name in compiled.outputs:
        kind = compiled.output_type(name)
        shown = (
            value_html(kind, outputs[name], name)
            if name in outputs
            else '<p class="failed">not produced</p>'
        )
        wide = " wide" if issubclass(kind, TablePort) else ""
        title = f"{escape(name)} <small>{escape(kind.type_name())}</small>"
        sections.append(f'<div class="output{wide}"><h3>{title}</h3>{shown}</div>')
    body.append(f'<div class="outputs">{"".join(sections)}</div>')
    if intermediates:
        thumbs = [
            f'<div class="output"><h3>{escape(where)}</h3>{picture_html(picture, where)}</div>'
            for where, (kind, value) in intermediates.items()
            if (picture := kind.preview(value)) is not None
        ]
        body += ["<h2>Intermediate values</h2>", f'<div class="outputs">{"".join(thumbs)}</div>']
    body += ["<h2>Nodes</h2>", _nodes_html(record), "<h2>Provenance</h2>", _provenance_html(record)]
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{escape(graph.name)}: graphvision report</title><style>{_STYLE}</style></head>"
        f"<body>{''.join(body)}</body></html>\n"
    )


def _nodes_html(record: RunRecord) -> str:
    rows = "".join(
        f'<tr><td class="text">{escape(n.name)}</td><td class="text">{escape(n.op)}</td>'
        f'<td class="text">{escape(n.status)}</td><td>{n.seconds * 1e3:.1f}</td>'
        f"<td>{n.output_bytes}</td></tr>"
        for n in record.nodes
    )
    head = "".join(f"<th>{h}</th>" for h in ("node", "op", "status", "ms", "bytes"))
    return f"<table><tr>{head}</tr>{rows}</table>"


def _provenance_html(record: RunRecord) -> str:
    """Every field of the record but its nodes and outputs, as a two-column table."""
    fields = {
        f.name: getattr(record, f.name)
        for f in dataclasses.fields(record)
        if f.name not in ("nodes", "outputs")
    }
    rows = "".join(
        f'<tr><th>{escape(key)}</th><td class="text"><code>'
        f"{escape(value if isinstance(value, str) else json.dumps(value, default=str))}"
        "</code></td></tr>"
        for key, value in fields.items()
    )
    return f"<table>{rows}</table>"


def write_html_report(
    compiled: CompiledGraph,
    outputs: Mapping[str, Any],
    record: RunRecord,
    directory: Path,
    **options: Any,
) -> Path:
    """Write ``report.html`` into ``directory`` (see :func:`html_report`); return its path."""
    path = directory / "report.html"
    path.write_text(html_report(compiled, outputs, record, **options), encoding="utf-8")
    return path


def batch_page(items: Sequence[Any], out_dir: Path) -> str:
    """``batch.html``: one card per file, with its first picture, status, time and error.

    Pictures are linked from the item folders (a batch of thousands stays a
    small page); each card links to that item's own ``report.html``.
    """
    cards = []
    for item in items:
        folder = Path(item.output_dir)
        pictures = sorted(folder.glob("*.png")) if folder.is_dir() else []
        page = folder / "report.html"
        image = (
            f'<img loading="lazy" alt="{escape(pictures[0].name)}" '
            f'src="{escape(_relative(pictures[0], out_dir))}">'
            if pictures
            else '<div class="none">no picture</div>'
        )
        error = f'<div class="failed">{escape(item.error)}</div>' if item.error else ""
        body = (
            f"{image}<div>{escape(Path(item.file).name)}</div>"
            f"<small>{escape(item.status)}, {item.seconds:.2f} s</small>{error}"
        )
        kind = "ok" if item.status == "ok" else "bad"
        if page.is_file():  # a failed or interrupted file has no page to link to
            href = escape(_relative(page, out_dir))
            cards.append(f'<a class="card {kind}" href="{href}">{body}</a>')
        else:
            cards.append(f'<div class="card {kind}">{body}</div>')
    failed = sum(item.status != "ok" for item in items)
    style = (
        "body{font-family:sans-serif;margin:2em} .grid{display:flex;flex-wrap:wrap;gap:1em}"
        ".card{width:180px;color:inherit;text-decoration:none;border:1px solid #ddd;"
        "padding:.4em} .card img{width:100%} .card.bad{border-color:#b71c1c}"
        ".failed{color:#b71c1c;font-size:.8em} .none{height:120px;background:#eee}"
    )
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>batch: {len(items)} files</title><style>{style}</style></head><body>"
        f"<h1>{len(items) - failed} of {len(items)} files succeeded</h1>"
        f'<div class="grid">{"".join(cards)}</div></body></html>\n'
    )


def _relative(path: Path, start: Path) -> str:
    """``path`` as a relative URL from ``start``: percent-encoded, starting ``./`` or
    ``../``, so no file name can become a scheme (``javascript:``), a query or a fragment."""
    import os
    from urllib.parse import quote

    relative = Path(os.path.relpath(path, start)).as_posix()
    url = quote(relative, safe="/")
    return url if url.startswith("../") else f"./{url}"
