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
from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import (
    GraphvisionError,
    InputError,
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
from graphvision.execution.sweep_grid import (
    MAX_COMBINATIONS,
    checked_combinations,
    compile_combination,
    grid_values,
)
from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry

__all__ = [
    "MAX_COMBINATIONS",
    "SweepInterrupted",
    "SweepResult",
    "sweep",
]


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
        from graphvision.nodes.plugins import discover_for, warn_of_failed_plugins

        registry = discover_for(graph)
        warn_of_failed_plugins(registry)
    keys = list(grid)
    values = grid_values(graph, grid, keys)
    base, wanted = checked_combinations(graph, registry, keys, values, inputs, outputs)
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
            compile_combination(graph, registry, combo, inputs),
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


def scalar_outputs_of(compiled: CompiledGraph, names: Sequence[str]) -> list[str]:
    """The outputs among ``names`` a sweep tabulates and plots: numbers, booleans, text."""
    return [
        name
        for name in names
        if compiled.output_type(name).type_name() in ("Float", "Int", "Bool", "Text")
    ]
