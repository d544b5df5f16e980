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
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from html import escape
from pathlib import Path
from typing import Any

from ._cache import Cache, MemoryStore
from ._compile import CompiledGraph, compile_graph
from ._errors import GraphvisionError, OutputFolderError, PipelineError, Problem, did_you_mean
from ._executors import Executor, make_executor
from ._graph import Graph
from ._registry import Registry
from ._run import RunRecord, run

__all__ = [
    "MAX_COMBINATIONS",
    "SweepInterrupted",
    "SweepResult",
    "check_sweep_folder",
    "sweep",
    "sweep_html",
    "sweep_plot_svg",
    "write_sweep",
]

MAX_COMBINATIONS = 10_000
"""A larger grid is refused before anything runs (each combination is a whole run)."""

MANIFEST = "sweep.json"
"""The files a sweep wrote in its folder, so that the next one replaces those and no other."""


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
    outputs: Sequence[str] | None = None,
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
    executor, workers, keep_going, outputs
        As for :func:`graphvision.run`; one executor serves every run, and
        ``outputs`` limits each run to what those outputs need.
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
        A grid key names no node or parameter, a value is invalid, a
        ``params.name`` key is shadowed by swept node parameters, the grid is
        empty or has more than :data:`MAX_COMBINATIONS`: nothing ran. Each
        value is checked once; values valid alone but not together fail their
        combination's row.
    SweepInterrupted
        On Ctrl-C (a ``KeyboardInterrupt``), with the rows so far.
    """
    from ._arguments import graph_argument, mapping_argument, names_argument, run_arguments

    run_arguments(cache, executor, workers)
    inputs = mapping_argument(inputs, "inputs")
    outputs = names_argument(outputs, "outputs")
    given = graph_argument(graph)
    graph = given.graph if isinstance(given, CompiledGraph) else given
    if not isinstance(grid, Mapping):
        raise TypeError(f"grid must be a dict from 'node.param' to a list of values, got {grid!r}")
    if registry is None:
        from ._plugins import discover_for

        registry = discover_for(graph)
    keys = list(grid)
    for key in keys:
        if isinstance(grid[key], (str, bytes)) or not isinstance(grid[key], Sequence):
            raise PipelineError(
                [Problem(0, f"grid {key}", f"needs a list of values, got {grid[key]!r}")],
                graph.source,
            )
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
    problems += _shadowed(graph, keys)
    total = math.prod(len(options) for options in values)
    if total > MAX_COMBINATIONS:
        sizes = " × ".join(str(len(options)) for options in values)
        problems.append(
            Problem(
                0,
                "grid",
                f"{total:,} combinations ({sizes}); at most {MAX_COMBINATIONS:,}: "
                "sweep fewer values, or one parameter after another",
            )
        )
    if problems:
        raise PipelineError(problems, graph.source)
    first = {key: options[0] for key, options in zip(keys, values, strict=True)}
    base = _compile(graph, registry, first, inputs)
    for key, options in zip(keys, values, strict=True):  # each value checked once
        for value in options[1:]:
            _compile(graph, registry, {**first, key: value}, inputs)
    wanted = list(outputs) if outputs is not None else list(base.outputs)
    unknown = [name for name in wanted if name not in base.outputs]
    if unknown:
        listing = ", ".join(base.outputs)
        raise PipelineError(
            [Problem(0, "outputs", f"no output '{name}'; outputs: {listing}") for name in unknown],
            graph.source,
        )
    scalar_outputs = scalar_outputs_of(base, wanted)
    combinations = (dict(zip(keys, combo, strict=True)) for combo in itertools.product(*values))
    result = SweepResult(keys, scalar_outputs)
    cache = cache if cache is not None else Cache(MemoryStore())
    pool = make_executor(executor, workers) if isinstance(executor, str) else executor
    try:
        for combo in combinations:
            row: dict[str, Any] = dict(combo)
            try:
                outcome = run(
                    _compile(graph, registry, combo, inputs),
                    registry,
                    inputs=inputs,
                    outputs=wanted,
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
                on_row(len(result.rows), total, row)
    except KeyboardInterrupt:
        blank = {name: "" for name in scalar_outputs}
        for combo in combinations:  # the rest, not run
            rest = {"status": "not run", "computed": 0, "cached": 0, "seconds": 0.0}
            result.rows.append({**combo, **blank, **rest})
        raise SweepInterrupted(result) from None
    finally:
        if isinstance(executor, str):
            pool.shutdown(wait=True)
    return result


def scalar_outputs_of(compiled: CompiledGraph, names: Sequence[str]) -> list[str]:
    """The outputs among ``names`` a sweep tabulates and plots: numbers, booleans, text."""
    return [
        name
        for name in names
        if compiled.output_type(name).type_name() in ("Float", "Int", "Bool", "Text")
    ]


def _shadowed(graph: Graph, keys: list[str]) -> list[Problem]:
    """A swept ``params.name`` whose every use is itself swept would change nothing."""
    problems = []
    for key in keys:
        target, _, name = key.partition(".")
        if target != "params":
            continue
        reference = f"${{params.{name}}}"
        uses = [
            f"{node}.{param}"
            for node, decl in graph.nodes.items()
            for param, value in decl.params.items()
            if isinstance(value, str) and reference in value
        ]
        if uses and all(use in keys for use in uses):
            problems.append(
                Problem(
                    0,
                    f"grid {key}",
                    f"has no effect: every parameter that uses it ({', '.join(uses)}) is "
                    "swept itself",
                )
            )
    return problems


def _grid_named(where: str, combo: dict[str, Any]) -> str:
    """A problem's place as the user gave it: ``--grid key=value`` for a swept value."""
    for key, value in combo.items():
        where = where.replace(f"--set {key}={value!r}", f"--grid {key}={value!r}")
    return where


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
            Problem(
                p.line,
                _grid_named(p.where, combo),
                f"{p.message} (grid combination {shown})",
                p.file,
            )
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


def _is_sweep_file(name: str) -> bool:
    return name in ("sweep.csv", "sweep.html", MANIFEST) or (
        name.startswith("sweep_") and name.endswith(".svg")
    )


def check_sweep_folder(directory: Path) -> set[str]:
    """Refuse a folder where a sweep's files would replace files graphvision did not write;
    return the previous sweep's files there (its ``sweep.json``).

    Raises
    ------
    OutputFolderError
        The folder is a file, holds ``sweep.csv``, ``sweep.html``, ``sweep_*.svg`` or
        ``sweep.json`` that no sweep manifest there lists, or its ``sweep.json`` is
        not a graphvision manifest.
    """
    if directory.exists() and not directory.is_dir():
        raise OutputFolderError(f"output folder {directory} is a file")
    if not directory.is_dir():
        return set()
    owned: set[str] = set()
    manifest = directory / MANIFEST
    if manifest.is_file():
        try:
            content = json.loads(manifest.read_text(encoding="utf-8"))
            names = content["files"] if content.get("graphvision") == "sweep" else None
            if not isinstance(names, list) or not all(
                isinstance(n, str) and _is_sweep_file(n) and n == Path(n).name for n in names
            ):
                raise ValueError("not a sweep manifest")
            owned = {*names, MANIFEST}
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            raise OutputFolderError(
                f"{manifest} is not a graphvision sweep manifest, so which files there are a "
                "previous sweep's is unknown; choose another --output-dir or empty this one"
            ) from None
    for path in sorted(directory.iterdir()):
        if _is_sweep_file(path.name) and path.name not in owned:
            raise OutputFolderError(
                f"output folder {directory} holds {path.name}, which no graphvision sweep "
                "there wrote; the sweep would replace it: move it, or choose another "
                "--output-dir"
            )
    return owned


def write_sweep(
    result: SweepResult, directory: Path, name: str, plots: Sequence[str]
) -> list[Path]:
    """Write ``sweep.csv``, a chart per output in ``plots``, ``sweep.html`` and the
    manifest; remove what a previous sweep wrote there and this one did not.

    Returns the paths written (the manifest last, not listed).

    Raises
    ------
    OutputFolderError
        As :func:`check_sweep_folder`.
    """
    previous = check_sweep_folder(directory)
    directory.mkdir(parents=True, exist_ok=True)
    written = [result.write_csv(directory / "sweep.csv")]
    for output in plots:
        path = directory / f"sweep_{output}.svg"
        path.write_text(sweep_plot_svg(result, output), encoding="utf-8")
        written.append(path)
    page = directory / "sweep.html"
    page.write_text(sweep_html(result, name, list(plots)), encoding="utf-8")
    written.append(page)
    names = {path.name for path in written}
    for stale in sorted(previous - names - {MANIFEST}):
        (directory / stale).unlink(missing_ok=True)
    content = json.dumps({"graphvision": "sweep", "files": sorted(names)}, indent=1)
    (directory / MANIFEST).write_text(content + "\n", encoding="utf-8")
    return written
