"""A sweep's folder: ``sweep.csv``, ``sweep.html``, a page per run, an SVG chart per
plotted output, listed with their digests in ``sweep.json`` so that the next sweep there
replaces its own files and refuses anyone else's
(:mod:`graphvision.execution.manifest`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from html import escape
from pathlib import Path
from typing import Any

from graphvision.errors import PipelineError, Problem, did_you_mean
from graphvision.execution.manifest import FolderFiles, check_folder_files, replace_folder_files
from graphvision.execution.sweep import SweepResult
from graphvision.views.sweep_runs import run_page, run_page_name

__all__ = [
    "SWEEP_FILES",
    "check_sweep_folder",
    "nice_ticks",
    "sweep_html",
    "sweep_plot_svg",
    "write_sweep",
]

MANIFEST = "sweep.json"


def sweep_plot_svg(result: SweepResult, output: str) -> str:
    """``output`` against each swept parameter, one small chart per parameter, as SVG.

    Each chart has the parameter's values on x (its axis labelled with the
    parameter) and ``output`` on y (labelled, with ticks); one line per
    combination of the other parameters, so interactions show as lines that
    are not parallel, named in the chart's legend. Values that are not
    numbers are placed evenly.
    """
    if output not in result.outputs:
        listing = ", ".join(result.outputs) or "none"
        message = f"no scalar output '{output}'{did_you_mean(output, result.outputs)}; "
        raise PipelineError([Problem(0, "plot", message + f"outputs: {listing}")])
    entries = max((len(_groups(result, key)) for key in result.keys), default=0)
    legend = min(entries, _LEGEND_ROWS + 1) if entries > 1 else 0
    width, pad = 340.0, 56.0
    height = 230.0 + _LEGEND_PITCH * legend
    charts = [_chart(result, output, key, (width, 230.0), pad) for key in result.keys]
    total = width * len(charts)
    body = "".join(
        f'<g transform="translate({i * width:.0f},0)">{chart}</g>' for i, chart in enumerate(charts)
    )
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {total:.0f} {height:.0f}" '
        f'width="{total:.0f}" height="{height:.0f}" font-family="sans-serif" font-size="11">'
        f"<title>{escape(output)} against {escape(', '.join(result.keys))}</title>{body}</svg>"
    )


_PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2")
_LEGEND_ROWS = 12  # legend entries shown under a chart; more are summed up in one line
_LEGEND_PITCH = 15.0


def _groups(result: SweepResult, key: str) -> list[tuple[Any, ...]]:
    """The combinations of the parameters other than ``key``: one line each."""
    others = [k for k in result.keys if k != key]
    return sorted({tuple(row[k] for k in others) for row in result.rows}, key=str)


def _chart(
    result: SweepResult, output: str, key: str, size: tuple[float, float], pad: float
) -> str:
    width, height = size
    levels = list(dict.fromkeys(row[key] for row in result.rows))
    numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in levels)
    position = {v: float(v) if numeric else float(i) for i, v in enumerate(levels)}
    points = [
        (position[row[key]], float(row[output]), tuple(row[k] for k in result.keys if k != key))
        for row in result.rows
        if isinstance(row.get(output), (int, float)) and math.isfinite(float(row[output]))
    ]
    if not points:
        return f'<text x="{pad}" y="{height / 2}">no finite values of {escape(output)}</text>'
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    x0, x1 = min(xs), max(xs) if max(xs) > min(xs) else min(xs) + 1
    y0, y1 = min(ys), max(ys) if max(ys) > min(ys) else min(ys) + 1

    def sx(x: float) -> float:
        return pad + (x - x0) / (x1 - x0) * (width - 1.5 * pad)

    def sy(y: float) -> float:
        return height - pad - (y - y0) / (y1 - y0) * (height - 1.7 * pad)

    parts = _axes((key, output), (width, height, pad), [sx(position[v]) for v in levels], levels)
    whole = all(float(y).is_integer() for y in ys)
    parts += [
        _line(pad - 3, sy(y), pad, sy(y))
        + f'<text x="{pad - 5}" y="{sy(y) + 4:.1f}" text-anchor="end">{y:.4g}</text>'
        for y in nice_ticks(y0, y1, whole=whole)
    ]
    groups: dict[tuple, list[tuple[float, float]]] = {}
    for x, y, group in points:
        groups.setdefault(group, []).append((x, y))
    others = [k for k in result.keys if k != key]
    for number, (group, line) in enumerate(sorted(groups.items(), key=lambda g: str(g[0]))):
        colour = _PALETTE[number % len(_PALETTE)]
        line.sort()
        path = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in line)
        named = ", ".join(f"{k}={v}" for k, v in zip(others, group, strict=True))
        parts.append(
            f'<polyline points="{path}" fill="none" stroke="{colour}">'
            f"<title>{escape(named)}</title></polyline>"
        )
        parts += [
            f'<circle cx="{sx(x):.1f}" cy="{sy(y):.1f}" r="3" fill="{colour}"/>' for x, y in line
        ]
        if others and number < _LEGEND_ROWS:
            parts.append(_legend_entry(number, colour, named, height))
    if others and len(groups) > _LEGEND_ROWS:
        y = height + _LEGEND_PITCH * _LEGEND_ROWS
        parts.append(f'<text x="12" y="{y:.0f}">and {len(groups) - _LEGEND_ROWS} more lines</text>')
    return "".join(parts)


def nice_ticks(low: float, high: float, *, whole: bool = False, count: int = 5) -> list[float]:
    """Round values from ``low`` to ``high``, as near ``count`` of them as round steps
    allow (more when tied): steps of 1, 2 or 5 times a power of ten (Heckbert's "nice
    numbers", Graphics Gems, 1990), and of at least 1 when the values are whole (a
    count is never labelled 20.5)."""
    if not high > low:
        return [low]
    power = 10.0 ** math.floor(math.log10((high - low) / count))
    steps = [m * power * 10.0**p for p in (-1, 0, 1) for m in (1, 2, 5)]
    steps = [step for step in steps if step >= 1 or not whole] or [1.0]
    candidates = [_ticks_at(low, high, step) for step in steps]
    return min(candidates, key=lambda ticks: (abs(len(ticks) - count), -len(ticks)))


def _ticks_at(low: float, high: float, step: float) -> list[float]:
    first = math.ceil(low / step - 1e-9)
    last = math.floor(high / step + 1e-9)
    return [float(f"{k * step:.12g}") for k in range(first, last + 1)]


def _axes(
    names: tuple[str, str], box: tuple[float, float, float], xs: list[float], levels: list[Any]
) -> list[str]:
    """The axes of a chart, labelled with the parameter (x) and the output (y), and the
    parameter's values under the x axis."""
    (key, output), (width, height, pad) = names, box
    parts = [
        _line(pad, height - pad, width - pad / 2, height - pad),
        _line(pad, pad * 0.7, pad, height - pad),
        f'<text class="x-label" x="{(width + pad / 2) / 2:.0f}" y="{height - pad + 32:.0f}" '
        f'text-anchor="middle" font-weight="bold">{escape(key)}</text>',
        f'<text class="y-label" transform="translate(9,{(height - pad / 3) / 2:.0f}) '
        f'rotate(-90)" text-anchor="middle" font-weight="bold">{escape(output)}</text>',
    ]
    parts += [
        f'<text x="{x:.1f}" y="{height - pad + 14}" text-anchor="middle">{escape(str(v))}</text>'
        for x, v in zip(xs, levels, strict=True)
    ]
    return parts


def _legend_entry(number: int, colour: str, named: str, top: float) -> str:
    y = top + _LEGEND_PITCH * number
    return (
        f'<g class="legend"><line x1="12" y1="{y - 4:.0f}" x2="32" y2="{y - 4:.0f}" '
        f'stroke="{colour}" stroke-width="2"/><text x="38" y="{y:.0f}">{escape(named)}</text></g>'
    )


def _line(x1: float, y1: float, x2: float, y2: float) -> str:
    return f'<line x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}" stroke="#333"/>'


def sweep_html(result: SweepResult, title: str, plots: Sequence[str] = ()) -> str:
    """``sweep.html``: the sweep's table (failures in red), each row linking the page of
    its run (:mod:`graphvision.views.sweep_runs`), and a chart per plotted output."""
    head = "<th>run</th>" + "".join(f"<th>{escape(column)}</th>" for column in result.columns)
    rows = []
    for number, row in enumerate(result.rows, start=1):
        cells = [
            f'<td><a href="./{run_page_name(number)}">{number}</a></td>'
            if number <= len(result.records)
            else f"<td>{number}</td>"
        ]
        for column in result.columns:
            value = row.get(column, "")
            text = f"{value:.6g}" if isinstance(value, float) else str(value)
            cells.append(f"<td>{escape(text)}</td>")
        style = "" if row.get("status") == "ok" else ' class="failed"'
        rows.append(f"<tr{style}>{''.join(cells)}</tr>")
    charts = "".join(f"<h2>{escape(o)}</h2>{sweep_plot_svg(result, o)}" for o in plots)
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{escape(title)}: sweep</title><style>"
        "body{font-family:sans-serif;margin:2em} table{border-collapse:collapse}"
        "td,th{border:1px solid #ddd;padding:.2em .6em;text-align:right}"
        "tr.failed td{color:#b71c1c} svg{max-width:100%;height:auto}</style></head>"
        f"<body><h1>{escape(title)}: {len(result.rows)} "
        f"combination{'' if len(result.rows) == 1 else 's'}</h1>"
        f"<table><tr>{head}</tr>{''.join(rows)}</table>{charts}</body></html>\n"
    )


def _is_sweep_file(name: str) -> bool:
    if name in ("sweep.csv", "sweep.html"):
        return True
    return (name.startswith("sweep_") and name.endswith(".svg")) or (
        name.startswith("sweep_run_") and name.endswith(".html")
    )


SWEEP_FILES = FolderFiles(MANIFEST, "sweep", _is_sweep_file)
"""A sweep's files, listed with their digests in ``sweep.json``."""


def check_sweep_folder(
    directory: Path, plots: Sequence[str] = (), combinations: int | None = None
) -> None:
    """Refuse a folder where a sweep's files would replace files graphvision did not write.

    Given the sweep's ``combinations`` (how many) and ``plots``, only the files it
    would write or remove count: a user's ``sweep_mine.svg`` beside them is left alone.

    Raises
    ------
    OutputFolderError
        The folder is a file, holds ``sweep.csv``, ``sweep.html``, ``sweep_*.svg`` or
        ``sweep_run_*.html`` that the sweep would write and no sweep manifest there lists
        (or that changed since, or is a link), or its ``sweep.json`` is not a graphvision
        manifest (:func:`~graphvision.execution.manifest.check_folder_files`).
    """
    writing = None if combinations is None else _sweep_names(plots, combinations)
    check_folder_files(directory, SWEEP_FILES, writing)


def _sweep_names(plots: Sequence[str], runs: int) -> set[str]:
    """The files a sweep of ``runs`` combinations plotting ``plots`` writes."""
    pages = (run_page_name(number) for number in range(1, runs + 1))
    return {"sweep.csv", "sweep.html", *(_plot_name(output) for output in plots), *pages}


def _plot_name(output: str) -> str:
    return f"sweep_{output}.svg"


def write_sweep(
    result: SweepResult, directory: Path, name: str, plots: Sequence[str]
) -> list[Path]:
    """Write ``sweep.csv``, a chart per output in ``plots``, a page per run, ``sweep.html``
    and the manifest; remove what a previous sweep wrote there and this one did not.

    Returns the paths written (not the manifest).

    Raises
    ------
    OutputFolderError
        As :func:`check_sweep_folder`.
    """
    contents = {"sweep.csv": result.csv_text()}
    for output in plots:
        contents[_plot_name(output)] = sweep_plot_svg(result, output)
    for number in range(1, len(result.records) + 1):
        contents[run_page_name(number)] = run_page(result, number, name)
    contents["sweep.html"] = sweep_html(result, name, list(plots))
    return replace_folder_files(directory, SWEEP_FILES, contents)
