"""One page per combination of a sweep, ``sweep_run_<number>.html``, linked from its row of
``sweep.html``: the swept values, the status, the scalar outputs and what each node did
(computed or loaded from the cache, with its time), from the run's record. A sweep keeps
no other output of its runs: run the pipeline with those ``--set`` values to see them."""

from __future__ import annotations

import json
from html import escape

from graphvision.execution.sweep import SweepResult

__all__ = ["run_page", "run_page_name"]

_STYLE = (
    "body{font-family:sans-serif;margin:2em} table{border-collapse:collapse;margin-bottom:1em}"
    "td,th{border:1px solid #ddd;padding:.2em .6em;text-align:right} td.text{text-align:left}"
    "th{background:#f5f5f5} .failed{color:#b71c1c}"
)


def run_page_name(number: int) -> str:
    """The page of combination ``number`` (1-based)."""
    return f"sweep_run_{number:04d}.html"


def _cell(value: object) -> str:
    return escape(f"{value:.6g}" if isinstance(value, float) else str(value))


def run_page(result: SweepResult, number: int, title: str) -> str:
    """The page of combination ``number`` (1-based) of ``result``."""
    row, record = result.rows[number - 1], result.records[number - 1]
    swept = "".join(
        f"<tr><th>{escape(key)}</th><td>{_cell(row[key])}</td></tr>" for key in result.keys
    )
    scalars = "".join(
        f"<tr><th>{escape(name)}</th><td>{_cell(row.get(name, ''))}</td></tr>"
        for name in result.outputs
    )
    nodes = "".join(
        f'<tr><td class="text">{escape(n.name)}</td><td class="text">{escape(n.op)}</td>'
        f'<td class="text">{escape(n.status)}</td><td>{n.seconds * 1e3:.1f}</td></tr>'
        for n in record.nodes
    )
    status = str(row.get("status", ""))
    overrides = " ".join(f"--set {key}={json.dumps(row[key], default=str)}" for key in result.keys)
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{escape(title)}: sweep run {number}</title><style>{_STYLE}</style></head>"
        f'<body><p><a href="./sweep.html">sweep</a></p>'
        f"<h1>{escape(title)}: run {number} of {len(result.rows)}</h1>"
        f'<p class="{"" if status == "ok" else "failed"}">{escape(status)}, '
        f"{record.seconds:.3f} s, {record.count('computed')} computed, "
        f"{record.count('cached')} cached</p>"
        f"<h2>Swept values</h2><table>{swept}</table>"
        f"<h2>Outputs</h2><table>{scalars}</table>"
        "<h2>Nodes</h2><table><tr><th>node</th><th>op</th><th>status</th><th>ms</th></tr>"
        f"{nodes}</table><p>The same run alone: <code>graphvision run PIPELINE "
        f"{escape(overrides)}</code></p></body></html>\n"
    )
