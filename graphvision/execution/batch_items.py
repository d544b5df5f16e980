"""One file of a batch: run in this process, or as one task of the executor with the
shared values sent along; its folder written from the result."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from pathlib import Path
from typing import Any

from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import GraphvisionError, InputError, RunError
from graphvision.execution.batch_files import BatchItem
from graphvision.execution.executors import (
    Executor,
    executor_name,
)
from graphvision.execution.file_task import (
    file_outcome,
    local_plugin_paths,
    run_file_task,
)
from graphvision.execution.folders import (
    RunPage,
    owned_files,
    remove_owned_files,
    write_run,
)
from graphvision.execution.record import RunResult
from graphvision.execution.run import run
from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry

__all__ = [
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
    pool: Executor,
    graph: Graph,
    path: Path,
    folder: Path,
    compiled: CompiledGraph | None,
    registry: Registry,
    cache: Cache | None,
    task: tuple[Any, ...],
) -> tuple[BatchItem, RunResult | None]:
    """One file as one task of the executor (``file_task.run_file_task``)."""
    item = BatchItem(path, folder)
    began = time.perf_counter()
    result: RunResult | None
    result = _from_cache(graph, registry, cache, task, f"{executor_name(pool)}, from the cache")
    if result is not None:  # every output of this file is in the cache: nothing to send
        item.seconds = time.perf_counter() - began
        return item, result
    try:
        plugins = local_plugin_paths(registry)
        outcome = pool.submit(run_file_task, graph, plugins, *task).result()
    except Exception as error:  # the task itself failed (a worker that died twice, ...)
        item.status, item.error = "failed", f"{type(error).__name__}: {error}"
    else:
        if compiled is None:  # the first file could not be compiled or read
            from graphvision.compiler.compile import compile_graph

            overrides = task[2]
            plain = graph.with_overrides(overrides) if overrides else graph
            compiled = compile_graph(plain, registry, provided=set(task[0]))
        executor = f"{executor_name(pool)}, one task per file"
        result, error_text = file_outcome(outcome, compiled, registry, executor)
        if error_text:
            item.status, item.error = "failed", error_text
        if result is not None and cache is not None:
            _store_outputs(result, cache)
    item.seconds = time.perf_counter() - began
    return item, result


class _NotCachedError(Exception):
    """Raised by :class:`_CacheOnly` for the first node that is not in the cache."""


class _CacheOnly:
    """An executor that runs nothing: a run on it succeeds only if the cache has it all."""

    encodes_values = True  # so the scheduler never runs a node in the calling thread

    def __init__(self, name: str) -> None:
        self.name = name

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future:
        refused: Future = Future()
        refused.set_exception(_NotCachedError())
        return refused

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        return None


def _from_cache(
    graph: Graph, registry: Registry, cache: Cache | None, task: tuple[Any, ...], name: str
) -> RunResult | None:
    """The file's run, if the cache holds every output it asks for (a batch run again);
    None when anything must be computed (or the file cannot be read: the task says why)."""
    if cache is None:
        return None
    inputs, outputs, overrides = task[0], task[1], task[2]
    try:
        return run(
            graph,
            registry,
            inputs=inputs,
            outputs=outputs,
            overrides=overrides,
            executor=_CacheOnly(name),
            cache=cache,
        )
    except Exception:  # anything to compute, or that cannot be read: the file task says
        return None


def _store_outputs(result: RunResult, cache: Cache) -> None:
    """Keep a file task's outputs in the client's cache under the keys the worker gave them."""
    keys = {node.name: node.keys for node in result.record.nodes}
    for name, value in result.outputs.items():
        producer, port = result.compiled.outputs[name]
        step = result.compiled.steps.get(producer)
        key = keys.get(producer, {}).get(port)
        if step is not None and step.spec.cache and key:
            cache.put(key, step.outputs[port], value)


def failure_reason(error: BaseException) -> str:
    """What ``batch.csv`` says of a file that failed: the error's message, its first line; the
    exception's type too when it is not one of graphvision's (a library's ValueError)."""
    text = (str(error).strip().splitlines() or [""])[0]
    if isinstance(error, GraphvisionError):
        return text
    if isinstance(error, OSError) and error.strerror:
        where = f": {error.filename}" if error.filename else ""
        return f"{error.strerror}{where}"
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def finish_item(item: BatchItem, result: RunResult | None, pages: Sequence[RunPage]) -> BatchItem:
    """Write the item's folder from its result (or clear it when there is none)."""
    folder = item.output_dir
    if result is None:  # nothing produced: what a previous run left there must not look current
        remove_owned_files(folder, owned_files(folder))
        return item
    try:
        write_run(result, folder, pages)
    except Exception as error:  # a port type's writer, a report page, the disk: this file fails
        item.status, item.error = "failed", f"writing {folder}: {failure_reason(error)}"
        with contextlib.suppress(Exception):  # what an earlier run left must not look current
            remove_owned_files(folder, owned_files(folder))
    item.scalars = {
        key: value
        for key, value in result.outputs.items()
        if isinstance(value, int | float | str | bool)
    }
    return item
