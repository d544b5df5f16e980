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

import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from typing import Any

from graphvision.cache.memory_store import MemoryStore
from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import InputError
from graphvision.execution.batch_files import (
    NO_PAGES,
    BatchItem,
    BatchPages,
    BatchResult,
    batch_files,
    common_parts,
    output_folders,
    pattern_root,
    previous_folders,
    replace_text,
    write_summary,
)
from graphvision.execution.batch_items import finish_item, plain_graph, run_file, run_item
from graphvision.execution.executors import (
    Executor,
    encodes_values,
    executor_width,
    make_executor,
)
from graphvision.execution.file_task import (
    Seed,
    shared_seeds,
)
from graphvision.execution.folders import (
    check_output_folder,
    owned_files,
    remove_owned_files,
)
from graphvision.execution.record import RunHooks
from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry

__all__ = [
    "run_batch",
]


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
    pages: BatchPages = NO_PAGES,
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
        :mod:`graphvision.execution.file_task`); default: on executors whose nodes run in
        other processes (``processes``, Dask), where a task costs most.
    pages : BatchPages
        Report pages to write besides outputs, records and ``batch.csv``
        (``graphvision.run_batch`` writes ``report.md``, ``report.html`` and
        ``batch.html``: :data:`graphvision.views.batch_page.BATCH_PAGES`).

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
    from graphvision.execution.arguments import (
        graph_argument,
        mapping_argument,
        names_argument,
        run_arguments,
    )

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
        root = Path(*common_parts([p.parent.parts for p in paths])) if paths else Path()
    folders = output_folders(paths, root, out_dir)
    names = list(outputs) if outputs is not None else list(graph.outputs)
    for folder in folders:
        check_output_folder(folder, names)
    current = {folder.resolve() for folder in folders}
    for folder in previous_folders(out_dir) - current:  # its file is no longer in the batch
        remove_owned_files(folder, owned_files(folder))
    if registry is None:  # found once for the batch, not once per file
        from graphvision.nodes.plugins import discover_for

        registry = discover_for(plain_graph(graph))
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
            item, result = run_item(
                graph, paths[index], folders[index], {**options, "inputs": item_inputs}
            )
            if index == 0 and one_task_per_file and result is not None and cache is not None:
                values: list[Seed] = shared_seeds(result.compiled, result.record, cache, input)
                share = getattr(pool, "share", None)  # Dask: sent to the workers once
                seeds.append(share(values) if share is not None and values else values)
                compiled.append(result.compiled)
            return finish_item(item, result, pages.run)
        item, result = run_file(
            pool,
            plain_graph(graph),
            paths[index],
            folders[index],
            compiled[0] if compiled else None,
            registry,
            cache,
            (item_inputs, outputs, overrides, keep_going, seeds[0] if seeds else []),
        )
        return finish_item(item, result, pages.run)

    compiled: list[CompiledGraph] = []
    try:
        width = files_at_once or executor_width(pool)
        for done, (index, item) in enumerate(_stream(run_one, len(paths), width), start=1):
            items[index] = item
            if on_item is not None:
                on_item(done, len(paths), item)
    except BaseException:  # Ctrl-C or an error: the files done so far are still summarised
        _summarise(_not_run(items, paths, folders, started), out_dir, pages)
        raise
    finally:
        if isinstance(executor, str):
            pool.shutdown()
    finished = [item for item in items if item is not None]
    return BatchResult(finished, _summarise(finished, out_dir, pages))


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


def _summarise(items: list[BatchItem], out_dir: Path, pages: BatchPages) -> Path:
    """``batch.csv`` for ``items``, and the summary page when there is one."""
    summary = write_summary(items, out_dir)
    if pages.summary is not None:
        name, text = pages.summary(items, out_dir)
        replace_text(out_dir / name, text)
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
