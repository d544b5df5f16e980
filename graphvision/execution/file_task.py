"""One file of a batch as one task: the whole file done where the executor runs tasks.

On an executor whose nodes run in other processes (the process pool, Dask),
a batch that sent every node of every file as a task would pay the
executor's per-task cost (milliseconds on Dask) for each of them, and one
that brought every value back to write the file's folder would make the
client the bottleneck (and, on a cluster, its network link). Instead, after
the first file has run node by node (filling the cache with the nodes every
file shares), each further file becomes one task that does the whole file
on the worker: it runs the pipeline in the worker's own thread (``sync``),
with a memory cache seeded with the shared nodes' values, and writes the
file's folder there (outputs, ``record.json``, report pages and their
thumbnails). The client receives the file's :class:`FileOutcome`: status,
seconds, scalar outputs, the cache keys of the outputs and the bytes of the
values computed; no value travels back.

What every task of a batch shares is a :class:`FileJob`, prepared once per
worker process (:func:`run_file_task` keeps the last few): the plugin
registry (loading the plugins took seconds per task when each task loaded
them), the compiled graph, and the shared values decoded. On Dask the job is
sent to every worker once.

With a cache whose store the workers can open (a disk cache, or an object
store through fsspec: :mod:`graphvision.cache.shared`), the job carries the
store's location and every worker writes the values it computes there, with
the store's guarantees (whole-entry digest, atomic publish, only its own
files touched); a batch run again is then served from that store on the
workers.

The worker must be able to read the file and write its folder (the same
machine, or storage the workers share) and import the plugins (see
:class:`~graphvision.DaskExecutor`).
"""

from __future__ import annotations

import multiprocessing
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from graphvision.cache.entries import Store
from graphvision.cache.memory_store import MemoryStore
from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph, compile_graph
from graphvision.errors import InputError, RunError
from graphvision.execution.batch_files import BatchItem
from graphvision.execution.batch_stop import INTERRUPTED, NOT_STARTED, StopFlag, writing
from graphvision.execution.batch_write import finish_item
from graphvision.execution.folders import RunPage
from graphvision.execution.record import RunRecord
from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry
from graphvision.values.ports import Placed, freeze_all

__all__ = [
    "FileJob",
    "FileOutcome",
    "Seed",
    "local_plugin_paths",
    "preload_modules",
    "run_file_task",
    "shared_seeds",
    "shared_steps",
    "use_registry",
    "warm_graph",
    "warm_worker",
]

Seed = tuple[str, str, dict[str, Any], dict[str, Any]]
"""A cache entry sent to workers: key, port type name, arrays, JSON metadata."""


@dataclass(frozen=True)
class FileJob:
    """What every file task of one batch shares (sent to each Dask worker once).

    ``token`` names the batch (a worker prepares each job once); ``graph`` has
    the overrides applied; ``inputs`` are the graph inputs every file shares;
    ``store`` is the cache store the workers write values to (None: memory
    only); ``executor`` is what the records call the executor; ``out_dir`` the
    batch's folder, the only place its files are written; ``stop`` the flag a
    stopped batch raises (:mod:`graphvision.execution.batch_stop`).
    """

    token: str
    graph: Graph
    plugin_paths: tuple[str, ...]
    input: str
    inputs: dict[str, Any]
    outputs: list[str] | None
    keep_going: bool
    seeds: list[Seed]
    pages: tuple[RunPage, ...]
    store: Store | None
    executor: str
    out_dir: Path
    stop: StopFlag | None = None


@dataclass
class FileOutcome:
    """What a worker sends back for one file: small metadata, never a value.

    ``keys`` are the cache keys of the file's outputs (where the store holds
    them, when there is one); ``value_bytes`` the encoded size of the values
    its nodes computed (what would have travelled had they come back).
    """

    item: BatchItem
    keys: dict[str, str] = field(default_factory=dict)
    value_bytes: int = 0


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
                arrays, meta = port_type.encode(value)  # (frozen where they lay, on a worker)
                seeds.append((key, port_type.type_name(), Placed.of(arrays), meta))
    return seeds


def local_plugin_paths(registry: Registry) -> list[str]:
    """The plugin files and folders ``registry`` loaded from paths (not entry points)."""
    return [
        status.origin
        for status in registry.plugins.values()
        if status.origin == status.name and Path(status.origin).exists()
    ]


def preload_modules(registry: Registry, graph: Graph, pages: tuple[RunPage, ...] = ()) -> list[str]:
    """The modules of the nodes and input types ``graph`` uses that import by name, then
    those their functions and the report ``pages`` import inside their bodies (for a
    worker server to import once: :mod:`graphvision.execution.worker_start`)."""
    from graphvision.execution.batch_preload import lazy_imports
    from graphvision.nodes.plugins import Needs

    needs = Needs.of(graph)
    specs = [registry.nodes[op] for op in sorted(needs.ops) if op in registry.nodes]
    types = [registry.port_types[n] for n in sorted(needs.port_types) if n in registry.port_types]
    modules = [spec.ref.module for spec in specs if not spec.ref.path]
    modules += [kind.__module__ for kind in types]
    functions = [spec.func for spec in specs if not spec.ref.path]
    functions += [source.func for name, source in registry.sources.items() if name == "file"]
    functions += [*pages, *_methods(types)]
    modules += lazy_imports(functions)
    return [m for m in dict.fromkeys(modules) if m != "__main__"]


def _methods(kinds: list[Any]) -> list[Any]:
    """The functions defined in the classes ``kinds`` (their methods, class and static)."""
    found = []
    for kind in kinds:
        for member in vars(kind).values():
            found.append(getattr(member, "__func__", member))
    return [f for f in found if callable(f)]


@dataclass
class _Prepared:
    """A job as a worker process uses it: registry, compiled graph, decoded shared values."""

    registry: Registry
    compiled: CompiledGraph
    seeds: list[tuple[str, Any, int]]


_PREPARED: OrderedDict[str, _Prepared] = OrderedDict()
_REGISTRIES: dict[tuple[tuple[str, ...], frozenset[str], frozenset[str]], Registry] = {}
_PREPARED_LOCK = threading.Lock()
_KEEP_JOBS = 4


def _registry_key(
    graph: Graph, plugin_paths: tuple[str, ...]
) -> tuple[tuple[str, ...], frozenset[str], frozenset[str]]:
    from graphvision.nodes.plugins import Needs

    needs = Needs.of(graph)
    return ((*plugin_paths, *graph.plugins), needs.ops, needs.port_types)


def use_registry(job: FileJob, registry: Registry) -> None:
    """Run ``job``'s files in this process with ``registry`` (the client's, which has loaded
    the plugins already) rather than loading the plugins again."""
    with _PREPARED_LOCK:
        _REGISTRIES.setdefault(_registry_key(job.graph, job.plugin_paths), registry)


def _registry(graph: Graph, plugin_paths: tuple[str, ...]) -> Registry:
    """The plugins ``graph`` needs, loaded once per process (call with the lock held)."""
    from graphvision.nodes.plugins import discover_for

    key = _registry_key(graph, plugin_paths)
    found = _REGISTRIES.get(key)
    if found is None:
        found = _REGISTRIES[key] = discover_for(graph, plugin_paths)
    return found


def warm_worker(graph: Graph, plugin_paths: tuple[str, ...], modules: tuple[str, ...] = ()) -> int:
    """Load the plugins ``graph`` needs in this worker process ahead of its first file,
    import ``modules`` (what its node functions import in their bodies:
    :func:`preload_modules`) and, when they use numba, set up numba's compiler and load
    their kernels from numba's cache (a batch sends one per worker while its first file runs
    in the client; on a worker forked from the server all of it is done already); its pid."""
    import os
    import sys

    from graphvision.execution.batch_preload import import_modules, load_kernels

    with _PREPARED_LOCK:
        _registry(graph, plugin_paths)
    found = import_modules(list(modules))
    if "numba" in sys.modules:
        import graphvision.execution._numba_setup  # noqa: F401 - numba's compiler, once
    load_kernels(found)
    return os.getpid()


def warm_graph(graph: Graph, plugin_paths: tuple[str, ...], provided: tuple[str, ...]) -> None:
    """Load the plugins ``graph`` needs and compile it as each file's task will (building its
    nodes' parameter models and code fingerprints): run by the worker server, once for the
    workers forked from it (:mod:`graphvision.execution._preload`)."""
    with _PREPARED_LOCK:
        registry = _registry(graph, plugin_paths)
    compiled = compile_graph(graph, registry, provided=set(provided))
    for step in compiled.steps.values():
        _ = step.fingerprint


def _prepared(job: FileJob) -> _Prepared:
    """The job prepared in this process (once per job and process; the last few are kept)."""
    with _PREPARED_LOCK:
        found = _PREPARED.get(job.token)
        if found is not None:
            _PREPARED.move_to_end(job.token)
            return found
        registry = _registry(job.graph, job.plugin_paths)
        provided = {*job.inputs, job.input}
        compiled = compile_graph(job.graph, registry, provided=provided)
        seeds = []
        for key, type_name, arrays, meta in job.seeds:
            # frozen as the client's value is (read-only, aligned): a node sees the same
            # arrays on every worker, and a numba kernel compiles one signature, not a
            # second for writable arrays in each worker
            value = registry.port_type(type_name).decode(freeze_all(arrays), meta)
            seeds.append((key, value, sum(int(getattr(a, "nbytes", 0)) for a in arrays.values())))
        found = _PREPARED[job.token] = _Prepared(registry, compiled, seeds)
        while len(_PREPARED) > _KEEP_JOBS:
            _PREPARED.popitem(last=False)
        return found


def run_file_task(
    job: FileJob, path: str, folder: str, stopped: Callable[[], bool] | None = None
) -> FileOutcome:
    """On a worker: run the job's pipeline for the file at ``path`` (the shared values from
    the job's seeds, the values computed written to the job's store) and write ``folder``
    (unless ``stopped()`` says by then that the batch has stopped: the client's own files)."""
    from graphvision.execution.run import run

    item = BatchItem(Path(path), Path(folder))
    if job.stop is not None and job.stop.is_raised():  # stopped before it started: not run
        item.status, item.error = "not run", NOT_STARTED
        return FileOutcome(item)
    kept = job.stop.written_whole(folder) if job.stop is not None else None
    if kept is not None:  # written whole by this task's earlier run, whose worker died
        return FileOutcome(kept)
    prepared = _prepared(job)
    memory = MemoryStore(max_bytes=2**40)
    for key, value, nbytes in prepared.seeds:
        memory.put(key, value, nbytes)
    began = time.perf_counter()
    result = None
    try:
        result = run(
            prepared.compiled,
            prepared.registry,
            inputs={**job.inputs, job.input: path},
            outputs=job.outputs,
            executor="sync",
            cache=Cache(memory, job.store),
            keep_going=job.keep_going,
        )
    except RunError as error:
        item.status = "failed"
        item.error = "; ".join(str(e).splitlines()[0] for e in error.failures.values())
        result = getattr(error, "result", None)
    except InputError as error:  # this file cannot be read; the others may
        item.status, item.error = "failed", str(error)
    except (KeyboardInterrupt, SystemExit) as error:
        if multiprocessing.parent_process() is None:  # Ctrl-C in the client: the batch stops
            raise
        item.status = "failed"  # a worker ignores Ctrl-C: a node raised it, for this file
        item.error = f"a node raised {type(error).__name__} on the worker"
    item.seconds = time.perf_counter() - began
    if result is not None:
        result.record.executor = job.executor
    with writing(job.stop, folder, stopped) as claim:
        if not claim:  # the batch stopped meanwhile: no folder written
            item.status, item.error = "interrupted", INTERRUPTED
            return FileOutcome(item)
        outcome = FileOutcome(finish_item(item, Path(folder), result, job.pages, job.out_dir))
        claim.written(outcome.item)  # the client counts it, should this process die now
    if result is not None:
        outcome.keys, outcome.value_bytes = _output_keys(result.record, result.compiled)
    return outcome


def _output_keys(record: RunRecord, compiled: CompiledGraph) -> tuple[dict[str, str], int]:
    """The cache keys of the run's outputs, and the bytes of the values it computed."""
    keys = {node.name: node.keys for node in record.nodes}
    found = {}
    for name, (producer, port) in compiled.outputs.items():
        key = keys.get(producer, {}).get(port)
        if key:
            found[name] = key
    computed = sum(node.output_bytes for node in record.nodes if node.status == "computed")
    return found, computed
