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
import io
import itertools
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from graphvision.cache.memory_store import MemoryStore
from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph, compile_graph
from graphvision.errors import (
    GraphvisionError,
    InputError,
    PipelineError,
    Problem,
    did_you_mean,
)
from graphvision.execution.arguments import (
    graph_argument,
    mapping_argument,
    names_argument,
    run_arguments,
)
from graphvision.execution.executors import Executor, make_executor
from graphvision.execution.record import RunRecord
from graphvision.execution.run import run
from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry

__all__ = [
    "MAX_COMBINATIONS",
    "SweepInterrupted",
    "SweepResult",
    "sweep",
]

MAX_COMBINATIONS = 10_000
"""A larger grid is refused before anything runs (each combination is a whole run)."""


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
        path.write_text(self.csv_text(), encoding="utf-8", newline="")
        return path

    def csv_text(self) -> str:
        """The text of :meth:`write_csv`'s file."""
        stream = io.StringIO(newline="")
        writer = csv.DictWriter(stream, fieldnames=self.columns)
        writer.writeheader()
        writer.writerows(self.rows)
        return stream.getvalue()

    @property
    def columns(self) -> list[str]:
        return [*self.keys, *self.outputs, "status", "computed", "cached", "seconds"]


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C (or SIGTERM) during a sweep. ``result`` holds the ``done`` combinations done,
    the others marked ``not run`` (a re-run through the same cache recomputes only those);
    the interruption itself is the ``__cause__``."""

    def __init__(self, result: SweepResult, done: int = 0) -> None:
        super().__init__("sweep interrupted")
        self.result = result
        self.done = done


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
    backends: Sequence[str] | str | None = None,
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
    backends : sequence of str, optional
        The backend lookup order of every run, as for :func:`graphvision.run`.

    Returns
    -------
    SweepResult
        One row per combination, in the grid's order (the last key varies fastest).

    Raises
    ------
    InputError
        A graph input cannot be read (nothing is written: no combination could run).
    PipelineError
        A grid key names no node or parameter, an input or output no graph
        input or output, a value is invalid, a
        ``params.name`` key is shadowed by swept node parameters, the grid is
        empty or has more than :data:`MAX_COMBINATIONS`: nothing ran. Each
        value is checked once; values valid alone but not together fail their
        combination's row.
    SweepInterrupted
        On Ctrl-C (a ``KeyboardInterrupt``), with the rows so far.
    """
    run_arguments(cache, executor, workers)
    inputs = mapping_argument(inputs, "inputs")
    outputs = names_argument(outputs, "outputs")
    graph = _plain_graph(graph_argument(graph, backends))
    if not isinstance(grid, Mapping):
        raise TypeError(f"grid must be a dict from 'node.param' to a list of values, got {grid!r}")
    if registry is None:
        from graphvision.nodes.plugins import discover_for

        registry = discover_for(graph)
    keys = list(grid)
    values = _grid_values(graph, grid, keys)
    base, wanted = _checked_combinations(graph, registry, keys, values, inputs, outputs)
    total = math.prod(len(options) for options in values)
    scalar_outputs = scalar_outputs_of(base, wanted)
    result = SweepResult(keys, scalar_outputs)
    cache = cache if cache is not None else Cache(MemoryStore())
    combinations = (dict(zip(keys, combo, strict=True)) for combo in itertools.product(*values))
    own = isinstance(executor, str)
    pool = make_executor(executor, workers) if isinstance(executor, str) else executor
    running: list[dict[str, Any]] = []  # the combination that runs, until its row is in
    try:
        for combo in combinations:
            running[:] = [combo]
            row, record = _run_combination(
                graph, registry, combo, inputs, (wanted, scalar_outputs), pool, cache, keep_going
            )
            result.rows.append(row)
            result.records.append(record)
            running.clear()
            if on_row is not None:
                on_row(len(result.rows), total, row)
    except KeyboardInterrupt as stop:  # Ctrl-C or SIGTERM (the cause: the exit status)
        if own:  # the nodes still running are not waited for
            pool.shutdown(wait=False, cancel_futures=True)
            own = False
        done = len(result.rows)
        _not_run(result, itertools.chain(running, combinations), scalar_outputs)
        raise SweepInterrupted(result, done) from stop
    finally:
        if own:
            pool.shutdown(wait=True)
    return result


def _run_combination(
    graph: Graph,
    registry: Registry,
    combo: dict[str, Any],
    inputs: dict[str, Any] | None,
    outputs: tuple[list[str], list[str]],
    pool: Executor,
    cache: Cache,
    keep_going: bool,
) -> tuple[dict[str, Any], RunRecord]:
    """One combination's run: its row (the swept values, status, the scalar outputs, nodes
    computed and cached, seconds) and its record. ``outputs``: wanted, and scalar among them."""
    wanted, scalar_outputs = outputs
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
        record, produced, status = outcome.record, outcome.outputs, "ok"
    except InputError:  # the inputs are every combination's: none could run
        raise
    except GraphvisionError as error:
        record = getattr(error, "record", None) or RunRecord(graph.name, "")
        partial = getattr(error, "result", None)
        produced = partial.outputs if partial is not None else {}
        status = f"failed: {str(error).splitlines()[0]}"
    row["status"] = status
    row.update({name: produced.get(name, "") for name in scalar_outputs})
    row["computed"], row["cached"] = record.count("computed"), record.count("cached")
    row["seconds"] = round(record.seconds, 4)
    return row, record


def _plain_graph(given: Graph | CompiledGraph) -> Graph:
    return given.graph if isinstance(given, CompiledGraph) else given


def _not_run(
    result: SweepResult, combinations: Iterable[dict[str, Any]], scalar_outputs: list[str]
) -> None:
    """Rows for the combinations an interrupted sweep did not run."""
    blank = {name: "" for name in scalar_outputs}
    for rest in combinations:
        marks = {"status": "not run", "computed": 0, "cached": 0, "seconds": 0.0}
        result.rows.append({**rest, **blank, **marks})


def _grid_values(
    graph: Graph, grid: Mapping[str, Sequence[Any]], keys: list[str]
) -> list[list[Any]]:
    """Each key's values, or every problem of the grid's shape at once (PipelineError)."""
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
    return values


def _checked_combinations(
    graph: Graph,
    registry: Registry,
    keys: list[str],
    values: list[list[Any]],
    inputs: dict[str, Any] | None,
    outputs: Sequence[str] | None,
) -> tuple[CompiledGraph, list[str]]:
    """The first combination compiled, each other value checked once, and the outputs
    to produce; PipelineError naming every refused value, unknown output and input."""
    first = {key: options[0] for key, options in zip(keys, values, strict=True)}
    refused: dict[tuple[str, str], Problem] = {}  # a bad first value fails every check

    def compiled(combo: dict[str, Any]) -> CompiledGraph | None:
        try:
            return _compile(graph, registry, combo, inputs)
        except PipelineError as error:
            for p in error.problems:
                refused.setdefault((p.where, p.message.rsplit(" (grid combination", 1)[0]), p)
            return None

    base = compiled(first)
    for key, options in zip(keys, values, strict=True):  # each value checked once
        for value in options[1:]:
            compiled({**first, key: value})
    if base is None or refused:
        raise PipelineError(list(refused.values()), graph.source)
    wanted = list(outputs) if outputs is not None else list(base.outputs)
    listing, names = ", ".join(base.outputs), ", ".join(base.input_types) or "none"
    unknown = [
        *(Problem(0, "outputs", f"no output '{name}'; outputs: {listing}") for name in wanted
          if name not in base.outputs),
        *(Problem(0, "inputs", f"no input '{name}'; inputs: {names}") for name in inputs or {}
          if name not in base.input_types),
    ]  # fmt: skip
    if unknown:
        raise PipelineError(unknown, graph.source)
    return base, wanted


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
