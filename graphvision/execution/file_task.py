"""One file of a batch as one task: the whole pipeline run where the executor runs tasks.

On an executor whose nodes run in other processes (the process pool, Dask),
a batch that sent every node of every file as a task would pay the
executor's per-task cost (milliseconds on Dask) for each of them. Instead,
after the first file has run node by node (filling the cache with the nodes
every file shares), each further file becomes one task: the worker runs the
pipeline in its own thread (``sync``), with a memory cache seeded with the
shared nodes' values, so they are reused, not recomputed. Values travel in
their port types' array encoding both ways; the record and the messages of
failed nodes come back with them, and the client writes the file's folder.

The worker must be able to read the file (the same machine, or storage the
workers share) and import the plugins (see :class:`~graphvision.DaskExecutor`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from graphvision.cache.memory_store import MemoryStore
from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import GraphvisionError, InputError, RunError
from graphvision.execution.record import RunRecord, RunResult
from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry

__all__ = [
    "FileOutcome",
    "Seed",
    "file_outcome",
    "local_plugin_paths",
    "run_file_task",
    "shared_seeds",
    "shared_steps",
]

Seed = tuple[str, str, dict[str, Any], dict[str, Any]]
"""A cache entry sent to workers: key, port type name, arrays, JSON metadata."""


@dataclass
class FileOutcome:
    """What a worker sends back for one file (encoded outputs, never pickled values)."""

    outputs: dict[str, tuple[str, dict[str, Any], dict[str, Any]]] = field(default_factory=dict)
    record: RunRecord | None = None
    failures: dict[str, str] = field(default_factory=dict)
    input_error: str = ""


def shared_steps(compiled: CompiledGraph, per_file_input: str) -> list[str]:
    """Steps that do not depend on the input each file is given to: every file shares them."""
    depends: set[str] = {per_file_input}
    for name, step in compiled.steps.items():  # topological order
        if any(source in depends for source, _ in step.inputs.values()):
            depends.add(name)
    return [name for name in compiled.steps if name not in depends]


def shared_seeds(
    compiled: CompiledGraph, record: RunRecord, cache: Cache, per_file_input: str
) -> list[Seed]:
    """The cached values of the shared steps' outputs, as the first file's run keyed them."""
    shared = set(shared_steps(compiled, per_file_input))
    seeds: list[Seed] = []
    for node in record.nodes:
        if node.name not in shared:
            continue
        step = compiled.steps[node.name]
        for port, key in node.keys.items():
            port_type = step.outputs[port]
            hit, value = cache.get(key, port_type)
            if hit:
                arrays, meta = port_type.encode(value)
                seeds.append((key, port_type.type_name(), arrays, meta))
    return seeds


def local_plugin_paths(registry: Registry) -> list[str]:
    """The plugin files and folders ``registry`` loaded from paths (not entry points)."""
    return [
        status.origin
        for status in registry.plugins.values()
        if status.origin == status.name and Path(status.origin).exists()
    ]


def run_file_task(
    graph: Graph,
    plugin_paths: list[str],
    inputs: dict[str, Any],
    outputs: Sequence[str] | None,
    overrides: dict[str, Any] | None,
    keep_going: bool,
    seeds: list[Seed],
) -> FileOutcome:
    """On a worker: run ``graph`` for one file, the shared values taken from ``seeds``;
    ``plugin_paths`` are the local plugins the client's registry loaded."""
    from graphvision.execution.run import run
    from graphvision.nodes.plugins import discover

    registry = discover([*plugin_paths, *graph.plugins])
    memory = MemoryStore(max_bytes=2**40)
    cache = Cache(memory)
    for key, type_name, arrays, meta in seeds:
        value = registry.port_type(type_name).decode(arrays, meta)
        memory.put(key, value, sum(int(getattr(a, "nbytes", 0)) for a in arrays.values()))
    outcome = FileOutcome()
    try:
        result = run(
            graph,
            registry,
            inputs=inputs,
            outputs=outputs,
            overrides=overrides,
            executor="sync",
            cache=cache,
            keep_going=keep_going,
        )
    except RunError as error:
        partial = getattr(error, "result", None)
        outcome.failures = {name: str(e) for name, e in error.failures.items()}
        if partial is None:
            return outcome
        result = partial
    except InputError as error:
        outcome.input_error = str(error)
        return outcome
    outcome.record = result.record
    for name, value in result.outputs.items():
        port_type = result.compiled.output_type(name)
        arrays, meta = port_type.encode(value)
        outcome.outputs[name] = (port_type.type_name(), arrays, meta)
    return outcome


def file_outcome(
    outcome: FileOutcome, compiled: CompiledGraph, registry: Registry, executor: str
) -> tuple[RunResult | None, str]:
    """The client's view of a worker's outcome: a result to write (or None), and the error."""
    if outcome.input_error:
        return None, outcome.input_error
    failures = {name: GraphvisionError(message) for name, message in outcome.failures.items()}
    error = "; ".join(m.splitlines()[0] for m in outcome.failures.values())
    if outcome.record is None:
        return None, error
    outputs = {
        name: registry.port_type(type_name).decode(arrays, meta)
        for name, (type_name, arrays, meta) in outcome.outputs.items()
    }
    outcome.record.executor = executor
    return RunResult(outputs, outcome.record, compiled, failures), error
