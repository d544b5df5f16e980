"""One file of a batch: run in this process (its folder written here), or as one task of
the executor that does the whole file there (:mod:`graphvision.execution.file_task`)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import InputError, RunError
from graphvision.execution.batch_files import BatchItem
from graphvision.execution.batch_write import failure_reason, finish_item
from graphvision.execution.executors import Executor, WorkerDiedError
from graphvision.execution.file_task import FileOutcome, run_file_task
from graphvision.execution.record import RunResult
from graphvision.execution.run import run
from graphvision.graph.model import Graph

__all__ = [
    "could_not_start",
    "failure_reason",
    "finish_item",
    "plain_graph",
    "run_file",
    "run_item",
]


def plain_graph(graph: Graph | CompiledGraph) -> Graph:
    return graph.graph if isinstance(graph, CompiledGraph) else graph


def run_item(
    graph: Graph | CompiledGraph, path: Path, folder: Path, run_options: dict[str, Any]
) -> tuple[BatchItem, RunResult | None]:
    """Run one file and write its folder; a failure is recorded in the item, not raised."""
    item = BatchItem(path, folder)
    began = time.perf_counter()
    result: RunResult | None = None
    try:
        result = run(graph, **run_options)
    except RunError as error:
        item.status = "failed"
        item.error = "; ".join(str(e).splitlines()[0] for e in error.failures.values())
        result = getattr(error, "result", None)
    except InputError as error:  # this file cannot be read; the others may
        item.status, item.error = "failed", str(error)
    item.seconds = time.perf_counter() - began
    return item, result


def run_file(
    pool: Executor, job: Any, path: Path, folder: Path
) -> tuple[FileOutcome, BaseException | None]:
    """One file as one task of the executor, which writes the file's folder there
    (:func:`~graphvision.execution.file_task.run_file_task`); ``job`` is the batch's
    :class:`~graphvision.execution.file_task.FileJob`, or the executor's handle on it. With
    the error when the task itself failed (a worker that died twice, ...): then the item's
    seconds are the task's, from when it was sent."""
    began = time.perf_counter()
    try:
        outcome: FileOutcome = pool.submit(run_file_task, job, str(path), str(folder)).result()
    except Exception as error:  # the task itself failed (a worker that died twice, ...)
        item = BatchItem(path, folder, "failed", error=f"{type(error).__name__}: {error}")
        item.seconds = time.perf_counter() - began
        return FileOutcome(item), error
    return outcome, None


def could_not_start(error: BaseException) -> bool:
    """Whether a task failed because no worker process could start (the fork server killed,
    say), not because its worker died running it: the file itself is not at fault."""
    return isinstance(error, WorkerDiedError) and "could start" in str(error)
