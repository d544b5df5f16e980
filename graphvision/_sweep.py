"""Parameter sweeps: every combination of a grid of values, sharing what does not change.

A sweep runs the pipeline once per combination of the grid's values
(their Cartesian product) through one cache, so that a node upstream of
every swept parameter (SIFT of both images, when only the matcher's ratio and
RANSAC's threshold are swept) has the same cache key in every combination and
is computed once: the first run computes it, the others load it. Each run's
record says which nodes were computed and which were loaded.

Every combination is validated before anything runs, so a typo in a grid
key or a value of the wrong type stops the sweep at once, naming the key.
"""

from __future__ import annotations

import csv
import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from html import escape
from pathlib import Path
from typing import Any

from ._cache import Cache, MemoryStore
from ._compile import CompiledGraph, compile_graph
from ._errors import GraphvisionError, PipelineError, Problem, did_you_mean
from ._executors import Executor, make_executor
from ._graph import Graph
from ._registry import Registry
from ._run import RunRecord, run

__all__ = ["SweepInterrupted", "SweepResult", "sweep", "sweep_html", "sweep_plot_svg"]


@dataclass
class SweepResult:
    """One row per combination: the swept values, every scalar output, what ran.

    ``rows[i]`` maps each swept key (``node.param``) to its value, each
    scalar output to its value, ``status`` to ``ok`` or the failure, and
    ``computed`` / ``cached`` to how many nodes that run computed or loaded.
    """

    keys: list[str]
    outputs: list[str]
    rows: list[dict[str, Any]] = field(default_factory=list)
    records: list[RunRecord] = field(default_factory=list)

    def write_csv(self, path: str | Path) -> Path:
        """``sweep.csv``: one row per combination, columns in the order of :attr:`columns`."""
        path = Path(path)
        with path.open("w", newline="", encoding="utf-8") as stream:
            writer = csv.DictWriter(stream, fieldnames=self.columns)
            writer.writeheader()
            writer.writerows(self.rows)
        return path

    @property
    def columns(self) -> list[str]:
        return [*self.keys, *self.outputs, "status", "computed", "cached", "seconds"]


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C during a sweep. ``result`` holds the combinations done, the others
    marked ``not run`` (a re-run through the same cache recomputes only those)."""

    def __init__(self, result: SweepResult) -> None:
        super().__init__("sweep interrupted")
        self.result = result


def sweep(
    graph: Graph,
    grid: Mapping[str, Sequence[Any]],
    registry: Registry | None = None,
    *,
    inputs: dict[str, Any] | None = None,
    cache: Cache | None = None,
    executor: str | Executor = "threads",
    workers: int | None = None,
    keep_going: bool = False,
    on_row: Callable[[int, int, dict[str, Any]], None] | None = None,
) -> SweepResult:
    """Run ``graph`` for every combination of ``grid``'s values.

    Parameters
    ----------
    graph : Graph
        The pipeline.
    grid : mapping of ``"node.param"`` (or ``"params.name"``) to a sequence of values
        The values to try for each parameter; every combination runs.
    registry : Registry, optional
        Defaults to the installed plugins plus the graph's ``plugins:``.
    inputs : dict, optional
        Graph input values, as for :func:`graphvision.run`.
    cache : Cache, optional
        Shared by every run; a memory cache is used when none is given (the
        sharing needs one).
    executor, workers, keep_going
        As for :func:`graphvision.run`; one executor serves every run.
    on_row : callable, optional
        Called as ``on_row(number, total, row)`` as each combination finishes
        (``number`` is 1-based).

    Returns
    -------
    SweepResult
        One row per combination, in the grid's order (the last key varies fastest).

    Raises
    ------
    PipelineError
        A grid key names no node or parameter, a value is invalid, or the
        grid is empty: nothing ran.
    SweepInterrupted
        On Ctrl-C (a ``KeyboardInterrupt``), with the rows so far.
    """
    if registry is None:
        from ._plugins import discover

        registry = discover(graph.plugins)
    keys = list(grid)
    values = [list(grid[key]) for key in keys]
    problems = [
        Problem(0, f"grid {key}", "has no values")
        for key, options in zip(keys, values, strict=True)
        if not options
    ]
    for key in keys:
        target, _, param = key.partition(".")
        if not param:
            problems.append(Problem(0, f"grid {key}", "must be node.param or params.name"))
        elif target != "params" and target not in graph.nodes:
            hint = did_you_mean(target, graph.nodes)
            problems.append(Problem(0, f"grid {key}", f"no node '{target}'{hint}"))
    if not keys:
        problems.append(Problem(0, "grid", "the grid is empty: give at least one node.param"))
    if problems:
        raise PipelineError(problems, graph.source)
    combinations = [dict(zip(keys, combo, strict=True)) for combo in itertools.product(*values)]
    compiled = [_compile(graph, registry, combo, inputs) for combo in combinations]
    scalar_outputs = [
        name
        for name in compiled[0].outputs
        if compiled[0].output_type(name).type_name() in ("Float", "Int", "Bool", "Text")
    ]
    result = SweepResult(keys, scalar_outputs)
    cache = cache if cache is not None else Cache(MemoryStore())
    pool = make_executor(executor, workers) if isinstance(executor, str) else executor
    try:
        for combo, graph_of_combo in zip(combinations, compiled, strict=True):
            row: dict[str, Any] = dict(combo)
            try:
                outcome = run(
                    graph_of_combo,
                    registry,
                    inputs=inputs,
                    executor=pool,
                    cache=cache,
                    keep_going=keep_going,
                )
                record, produced, row["status"] = outcome.record, outcome.outputs, "ok"
            except GraphvisionError as error:
                record = getattr(error, "record", None) or RunRecord(graph.name, "")
                partial = getattr(error, "result", None)
                produced = partial.outputs if partial is not None else {}
                row["status"] = f"failed: {str(error).splitlines()[0]}"
            row.update({name: produced.get(name, "") for name in scalar_outputs})
            row["computed"], row["cached"] = record.count("computed"), record.count("cached")
            row["seconds"] = round(record.seconds, 4)
            result.rows.append(row)
            result.records.append(record)
            if on_row is not None:
                on_row(len(result.rows), len(combinations), row)
    except KeyboardInterrupt:
        blank = {name: "" for name in scalar_outputs}
        for combo in combinations[len(result.rows) :]:
            rest = {"status": "not run", "computed": 0, "cached": 0, "seconds": 0.0}
            result.rows.append({**combo, **blank, **rest})
        raise SweepInterrupted(result) from None
    finally:
        if isinstance(executor, str):
            pool.shutdown(wait=True)
    return result


def _compile(
    graph: Graph, registry: Registry, combo: dict[str, Any], inputs: dict[str, Any] | None
) -> CompiledGraph:
    """The graph with ``combo`` applied, validated; errors name the combination."""
    try:
        overridden = graph.with_overrides(combo)
        return compile_graph(overridden, registry, provided=set(inputs or {}))
    except PipelineError as error:
        shown = ", ".join(f"{k}={v!r}" for k, v in combo.items())
        problems = [
            Problem(p.line, p.where, f"{p.message} (grid combination {shown})", p.file)
            for p in error.problems
        ]
        raise PipelineError(problems, error.source) from None


def sweep_plot_svg(result: SweepResult, output: str) -> str:
    """``output`` against each swept parameter, one small chart per parameter, as SVG.

    Each chart has the parameter's values on x and ``output`` on y; one line
    per combination of the other parameters, so interactions show as lines
    that are not parallel. Values that are not numbers are placed evenly.
    """
    if output not in result.outputs:
        listing = ", ".join(result.outputs) or "none"
        message = f"no scalar output '{output}'{did_you_mean(output, result.outputs)}; "
        raise PipelineError([Problem(0, "plot", message + f"outputs: {listing}")])
    width, height, pad = 320.0, 220.0, 48.0
    charts = [_chart(result, output, key, width, height, pad) for key in result.keys]
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


def _chart(
    result: SweepResult, output: str, key: str, width: float, height: float, pad: float
) -> str:
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

    parts = [
        _line(pad, height - pad, width - pad / 2, height - pad),
        _line(pad, pad * 0.7, pad, height - pad),
        f'<text x="{width / 2:.0f}" y="{height - 8}" text-anchor="middle">{escape(key)}</text>',
        f'<text x="{pad}" y="{pad * 0.5:.0f}">{escape(output)}</text>',
    ]
    for level in levels:
        x = sx(position[level])
        tick = escape(str(level))
        parts.append(
            f'<text x="{x:.1f}" y="{height - pad + 14}" text-anchor="middle">{tick}</text>'
        )
    for y, label in ((y0, f"{y0:.3g}"), (y1, f"{y1:.3g}")):
        parts.append(f'<text x="{pad - 4}" y="{sy(y) + 4:.1f}" text-anchor="end">{label}</text>')
    groups: dict[tuple, list[tuple[float, float]]] = {}
    for x, y, group in points:
        groups.setdefault(group, []).append((x, y))
    for number, (group, line) in enumerate(sorted(groups.items(), key=lambda g: str(g[0]))):
        colour = _PALETTE[number % len(_PALETTE)]
        line.sort()
        path = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in line)
        others = ", ".join(
            f"{k}={v}" for k, v in zip([k for k in result.keys if k != key], group, strict=True)
        )
        parts.append(
            f'<polyline points="{path}" fill="none" stroke="{colour}">'
            f"<title>{escape(others)}</title></polyline>"
        )
        parts += [
            f'<circle cx="{sx(x):.1f}" cy="{sy(y):.1f}" r="3" fill="{colour}"/>' for x, y in line
        ]
    return "".join(parts)


def _line(x1: float, y1: float, x2: float, y2: float) -> str:
    return f'<line x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}" stroke="#333"/>'


def sweep_html(result: SweepResult, title: str, plots: Sequence[str] = ()) -> str:
    """``sweep.html``: the sweep's table (failures in red) and a chart per plotted output."""
    head = "".join(f"<th>{escape(column)}</th>" for column in result.columns)
    rows = []
    for row in result.rows:
        cells = []
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
        "tr.failed td{color:#b71c1c}</style></head>"
        f"<body><h1>{escape(title)}: {len(result.rows)} combinations</h1>"
        f"<table><tr>{head}</tr>{''.join(rows)}</table>{charts}</body></html>\n"
    )
