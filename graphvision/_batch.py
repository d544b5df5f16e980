"""Batch runs: one pipeline over many input files, one output folder per file.

:func:`run_batch` runs the items on one shared executor and cache: the first
file alone, so that the nodes every file shares (a trained model, a template,
a vocabulary: nodes upstream of nothing file-specific) are computed once and
cached, then the others several at a time, as many as the executor runs tasks
at once (its workers, or a Dask cluster's threads), each reported as it
completes. A bad file or a failed run is recorded and the batch goes on; on
Dask a node whose worker died runs again on another worker.
Each file gets its own folder, named after its path below the pattern's
fixed part (``photos/a/img.png`` and ``photos/b/img.png`` give
``OUT/a/img`` and ``OUT/b/img``), so no two files ever share a folder
(:func:`output_folders`). ``batch.csv`` lists every item: file, output
folder, status, seconds, error message and the scalar outputs. A folder a
previous batch into the same place listed, whose file is not in this batch,
loses its graphvision files: nothing there is left looking current.
"""

from __future__ import annotations

import csv
import glob
import io
import os
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ._cache import Cache, MemoryStore
from ._compile import CompiledGraph
from ._errors import GraphvisionError, InputError, OutputFolderError, RunError
from ._executors import (
    Executor,
    encodes_values,
    executor_name,
    executor_width,
    make_executor,
)
from ._file_task import Seed, file_outcome, local_plugin_paths, run_file_task, shared_seeds
from ._graph import Graph
from ._registry import Registry
from ._report import check_output_folder, owned_files, remove_owned_files, write_run
from ._run import RunHooks, RunResult, run

__all__ = [
    "SUMMARY",
    "BatchItem",
    "BatchResult",
    "batch_files",
    "output_folders",
    "pattern_root",
    "previous_folders",
    "run_batch",
    "write_summary",
]

SUMMARY = "batch.csv"


@dataclass
class BatchItem:
    """One file of a batch: where its outputs went, how it went, its scalar outputs."""

    file: Path
    output_dir: Path
    status: str = "ok"
    seconds: float = 0.0
    error: str = ""
    scalars: dict[str, Any] = field(default_factory=dict)


@dataclass
class BatchResult:
    """Every item, and the summary table written to ``summary``."""

    items: list[BatchItem]
    summary: Path

    @property
    def failed(self) -> int:
        return sum(item.status != "ok" for item in self.items)


def batch_files(pattern: str, exclude: Path | None = None) -> list[Path]:
    """The files a glob matches, sorted; ``**`` matches any depth of folders.

    Files under ``exclude`` (the batch's output folder, when it lies inside
    the searched folders) are left out, so a batch never reads its own outputs.
    A file reached by several paths (a folder symlink, a link back up the tree)
    is taken once, by its shortest path.
    """
    skipped = exclude.resolve() if exclude is not None else None
    found: dict[Path, Path] = {}
    for path in sorted(map(Path, glob.glob(pattern, recursive=True)), key=lambda p: len(p.parts)):
        if not path.is_file():
            continue
        real = path.resolve()
        if (skipped is None or skipped not in real.parents) and real not in found:
            found[real] = path
    return sorted(found.values())


def pattern_root(pattern: str) -> Path:
    """The folder before a glob's first wildcard (``photos`` for ``photos/**/*.png``)."""
    fixed = []
    for part in Path(pattern).parts:
        if glob.has_magic(part):
            break
        fixed.append(part)
    else:  # no wildcard: a single file, named by its own folder
        fixed = fixed[:-1]
    return Path(*fixed) if fixed else Path()


def output_folders(files: Sequence[Path], root: Path, out_dir: Path) -> list[Path]:
    """A distinct folder under ``out_dir`` for each file: its path below ``root`` without suffix.

    Two files whose paths differ only by suffix (``img.png``, ``img.jpg``) keep
    it (``img_png``, ``img_jpg``); any name still taken, or the summary's
    name, gets ``-2``, ``-3``... so the folders are always distinct.
    """
    relative = [_below(f, root) for f in files]
    plain = [r.with_suffix("") for r in relative]
    counts: dict[Path, int] = {}
    for name in plain:
        counts[name] = counts.get(name, 0) + 1
    taken = {Path(SUMMARY)}
    folders = []
    for rel, name in zip(relative, plain, strict=True):
        if counts[name] > 1 and rel.suffix:
            name = name.with_name(f"{name.name}_{rel.suffix[1:]}")
        candidate, number = name, 1
        while candidate in taken:
            number += 1
            candidate = name.with_name(f"{name.name}-{number}")
        taken.add(candidate)
        folders.append(out_dir / candidate)
    return folders


def _below(file: Path, root: Path) -> Path:
    try:
        return file.relative_to(root)
    except ValueError:  # outside the root: keep what can be kept, without '..' or an anchor
        return Path(*[p for p in file.parts if p not in ("..", file.anchor)])


def run_batch(
    graph: Graph | CompiledGraph,
    files: str | Sequence[str | Path],
    *,
    input: str,
    output_dir: str | Path,
    registry: Registry | None = None,
    inputs: dict[str, Any] | None = None,
    outputs: Sequence[str] | None = None,
    overrides: dict[str, Any] | None = None,
    executor: str | Executor = "threads",
    workers: int | None = None,
    cache: Cache | None = None,
    keep_going: bool = False,
    hooks: Sequence[RunHooks] = (),
    on_item: Callable[[int, int, BatchItem], None] | None = None,
    files_at_once: int | None = None,
    one_task_per_file: bool | None = None,
) -> BatchResult:
    """Run ``graph`` once per file, giving the file to graph input ``input``.

    Parameters
    ----------
    graph : Graph or CompiledGraph
        The pipeline.
    files : str or sequence of paths
        A glob (``photos/**/*.jpg``; ``**`` recurses) or the files themselves.
    input : str
        The graph input each file is given to.
    output_dir : str or Path
        Where the item folders and ``batch.csv`` go.
    registry, inputs, outputs, overrides, executor, workers, cache, keep_going, hooks
        As for :func:`~graphvision.run`; ``inputs`` are the other graph inputs.
    on_item : callable, optional
        Called as ``on_item(number, total, item)`` as each item completes
        (``number`` counts completed items, 1-based).
    files_at_once : int, optional
        Files in flight after the first; default: the tasks the executor runs
        at once (1 for ``sync``).
    one_task_per_file : bool, optional
        After the first file, run each file's whole pipeline as one task of the
        executor, the shared nodes' values sent along (see
        :mod:`graphvision._file_task`); default: on executors whose nodes run in
        other processes (``processes``, Dask), where a task costs most.

    Returns
    -------
    BatchResult
        Every item with its folder, status, error message and scalar outputs.

    Raises
    ------
    InputError
        When the glob matches no file, or ``inputs`` also gives ``input``.
    OutputFolderError
        When an item folder holds files graphvision did not write, or
        ``batch.csv`` is not a graphvision summary (checked before anything
        runs).
    """
    from ._arguments import graph_argument, mapping_argument, names_argument, run_arguments

    run_arguments(cache, executor, workers)
    graph = graph_argument(graph)
    inputs = mapping_argument(inputs, "inputs")
    outputs = names_argument(outputs, "outputs")
    overrides = mapping_argument(overrides, "overrides")
    if not isinstance(output_dir, (str, os.PathLike)):
        raise TypeError(f"output_dir must be a folder's path, got {output_dir!r}")
    if inputs and input in inputs:
        raise InputError(
            f"input '{input}' is given twice: once per file by the batch and once as"
            f" {inputs[input]!r}; drop one of them"
        )
    out_dir = Path(output_dir)
    if isinstance(files, str):
        paths, root = batch_files(files, exclude=out_dir), pattern_root(files)
        if not paths:
            raise InputError(f"batch input '{input}': no file matches '{files}'")
    else:
        paths = [Path(f) for f in files]
        root = Path(*_common_parts([p.parent.parts for p in paths])) if paths else Path()
    folders = output_folders(paths, root, out_dir)
    names = list(outputs) if outputs is not None else list(graph.outputs)
    for folder in folders:
        check_output_folder(folder, names)
    current = {folder.resolve() for folder in folders}
    for folder in previous_folders(out_dir) - current:  # its file is no longer in the batch
        remove_owned_files(folder, owned_files(folder))
    if registry is None:  # found once for the batch, not once per file
        from ._plugins import discover_for

        registry = discover_for(_plain(graph))
    pool = make_executor(executor, workers) if isinstance(executor, str) else executor
    one_task_per_file = encodes_values(pool) if one_task_per_file is None else one_task_per_file
    if one_task_per_file and cache is None:  # the first file's shared values are sent on
        cache = Cache(MemoryStore())
    items: list[BatchItem | None] = [None] * len(paths)
    options: dict[str, Any] = {
        "registry": registry,
        "outputs": outputs,
        "overrides": overrides,
        "executor": pool,
        "cache": cache,
        "keep_going": keep_going,
        "hooks": hooks,
    }
    seeds: list[Any] = []  # the shared values, or the executor's handle on them

    started: set[int] = set()

    def run_one(index: int) -> BatchItem:
        started.add(index)
        item_inputs = {**(inputs or {}), input: str(paths[index])}
        if index == 0 or not one_task_per_file:
            item, result = _run_item(
                graph, paths[index], folders[index], {**options, "inputs": item_inputs}
            )
            if index == 0 and one_task_per_file and result is not None and cache is not None:
                values: list[Seed] = shared_seeds(result.compiled, result.record, cache, input)
                share = getattr(pool, "share", None)  # Dask: sent to the workers once
                seeds.append(share(values) if share is not None and values else values)
                compiled.append(result.compiled)
            return item
        return _run_file(
            pool,
            _plain(graph),
            paths[index],
            folders[index],
            compiled[0] if compiled else None,
            registry,
            cache,
            (item_inputs, outputs, overrides, keep_going, seeds[0] if seeds else []),
        )

    compiled: list[CompiledGraph] = []
    try:
        width = files_at_once or executor_width(pool)
        for done, (index, item) in enumerate(_stream(run_one, len(paths), width), start=1):
            items[index] = item
            if on_item is not None:
                on_item(done, len(paths), item)
    except BaseException:  # Ctrl-C or an error: the files done so far are still summarised
        _summarise(_not_run(items, paths, folders, started), out_dir)
        raise
    finally:
        if isinstance(executor, str):
            pool.shutdown()
    finished = [item for item in items if item is not None]
    return BatchResult(finished, _summarise(finished, out_dir))


def _not_run(
    items: list[BatchItem | None], paths: list[Path], folders: list[Path], started: set[int]
) -> list[BatchItem]:
    """Every item; those that did not complete are ``interrupted`` (the batch stopped while
    the file ran: its folder may or may not be complete) or ``not run`` (never started).
    A re-run of the batch does both, from the cache where it can."""
    marked = []
    for index, (item, path, folder) in enumerate(zip(items, paths, folders, strict=True)):
        if item is not None:
            marked.append(item)
        elif index in started:
            reason = "the batch stopped while this file ran; re-run the batch to finish it"
            marked.append(BatchItem(path, folder, "interrupted", error=reason))
        else:
            reason = "the batch stopped before this file started"
            marked.append(BatchItem(path, folder, "not run", error=reason))
    return marked


def _summarise(items: list[BatchItem], out_dir: Path) -> Path:
    """``batch.csv`` and ``batch.html`` for ``items``."""
    from ._html import batch_page

    summary = write_summary(items, out_dir)
    _replace_text(out_dir / "batch.html", batch_page(items, out_dir))
    return summary


def _stream(
    run_one: Callable[[int], BatchItem], count: int, at_once: int
) -> Iterator[tuple[int, BatchItem]]:
    """``(index, item)`` as items complete: item 0 alone (it fills the cache with the shared
    nodes), then the rest ``at_once`` at a time on client threads that wait on the executor."""
    if count == 0:
        return
    yield 0, run_one(0)
    if at_once <= 1:
        for index in range(1, count):
            yield index, run_one(index)
        return
    with ThreadPoolExecutor(max_workers=at_once, thread_name_prefix="graphvision-file") as files:
        pending = {files.submit(run_one, index): index for index in range(1, count)}
        try:
            for future in as_completed(pending):
                yield pending[future], future.result()
        finally:  # Ctrl-C or an error: files not started yet are not started
            for future in pending:
                future.cancel()


def _common_parts(parts: list[tuple[str, ...]]) -> tuple[str, ...]:
    common: tuple[str, ...] = parts[0] if parts else ()
    for other in parts[1:]:
        length = 0
        while length < min(len(common), len(other)) and common[length] == other[length]:
            length += 1
        common = common[:length]
    return common


def _plain(graph: Graph | CompiledGraph) -> Graph:
    return graph.graph if isinstance(graph, CompiledGraph) else graph


def _run_item(
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
    return _finish_item(item, result), result


def _run_file(
    pool: Executor,
    graph: Graph,
    path: Path,
    folder: Path,
    compiled: CompiledGraph | None,
    registry: Registry,
    cache: Cache | None,
    task: tuple[Any, ...],
) -> BatchItem:
    """One file as one task of the executor (:func:`~graphvision._file_task.run_file_task`)."""
    item = BatchItem(path, folder)
    began = time.perf_counter()
    result = _from_cache(graph, registry, cache, task, f"{executor_name(pool)}, from the cache")
    if result is not None:  # every output of this file is in the cache: nothing to send
        item.seconds = time.perf_counter() - began
        return _finish_item(item, result)
    try:
        plugins = local_plugin_paths(registry)
        outcome = pool.submit(run_file_task, graph, plugins, *task).result()
    except Exception as error:  # the task itself failed (a worker that died twice, ...)
        item.status, item.error = "failed", f"{type(error).__name__}: {error}"
    else:
        if compiled is None:  # the first file could not be compiled or read
            from ._compile import compile_graph

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
    return _finish_item(item, result)


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
    except (RunError, InputError):
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


def _finish_item(item: BatchItem, result: RunResult | None) -> BatchItem:
    """Write the item's folder from its result (or clear it when there is none)."""
    folder = item.output_dir
    if result is None:  # nothing produced: what a previous run left there must not look current
        remove_owned_files(folder, owned_files(folder))
        return item
    try:
        write_run(result, folder)
    except (GraphvisionError, OSError) as error:
        item.status, item.error = "failed", f"writing {folder}: {error}"
    item.scalars = {
        key: value
        for key, value in result.outputs.items()
        if isinstance(value, int | float | str | bool)
    }
    return item


def previous_folders(out_dir: Path) -> set[Path]:
    """The item folders (resolved) a previous ``batch.csv`` lists, only those inside ``out_dir``.

    Raises
    ------
    OutputFolderError
        When ``out_dir`` holds a ``batch.csv`` that is not a graphvision
        summary (the batch would overwrite it).
    """
    summary = out_dir / SUMMARY
    if not summary.is_file():
        return set()
    try:
        with summary.open(newline="") as handle:
            reader = csv.DictReader(handle)
            if (
                not reader.fieldnames
                or reader.fieldnames[0] != "file"
                or ("status" not in reader.fieldnames)
            ):
                raise ValueError("not a batch summary")
            listed = [row.get("output_dir") or "" for row in reader]
    except (OSError, UnicodeDecodeError, ValueError, csv.Error):
        raise OutputFolderError(
            f"{summary} is not a graphvision batch summary; the batch would replace it: "
            "move it, or choose another --output-dir"
        ) from None
    root = out_dir.resolve()
    folders = {Path(folder).resolve() for folder in listed if folder}
    return {folder for folder in folders if root in folder.parents and folder.is_dir()}


def write_summary(items: Sequence[BatchItem], out_dir: Path) -> Path:
    """``batch.csv``: file, output_dir, status, seconds, error, then every scalar output."""
    rows = [
        {
            "file": str(item.file),
            "output_dir": str(item.output_dir),
            "status": item.status,
            "seconds": round(item.seconds, 4),
            "error": item.error,
            **item.scalars,
        }
        for item in items
    ]
    columns = list(dict.fromkeys(key for row in rows for key in row))
    out_dir.mkdir(parents=True, exist_ok=True)
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, fieldnames=columns)
    writer.writeheader()
    writer.writerows(rows)
    path = out_dir / SUMMARY
    _replace_text(path, text.getvalue())
    return path


def _replace_text(path: Path, text: str) -> None:
    """Write ``path`` whole or not at all (a temporary file beside it, then a rename)."""
    temp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with temp.open("w", encoding="utf-8", newline="") as handle:
            handle.write(text)
        os.replace(temp, path)
    finally:
        temp.unlink(missing_ok=True)
