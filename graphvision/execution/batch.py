"""Batch runs: one pipeline over many input files, one output folder per file.

:func:`run_batch` runs the items on one shared executor and cache: the first
file alone, so that the nodes every file shares (a trained model, a template,
a vocabulary: nodes upstream of nothing file-specific) are computed once and
cached, then the others several at a time, as many as the executor runs tasks
at once (its workers, or a Dask cluster's threads), each reported as it
completes. A bad file or a failed run is recorded and the batch goes on: any
failure while a file runs or its folder is written (outputs, records, report
pages) fails that file alone, with its reason in ``batch.csv``, and a path the
pattern matches that cannot be read (a folder named like a file, a dangling
or looping symbolic link, a pipe) is listed as failed, saying why. On Dask a
node whose worker died runs again on another worker. The pipeline is checked
before anything else: an invalid one makes no folder. Stopped (Ctrl-C,
SIGTERM), a batch lists in ``batch.csv`` every file, done or not (even when
none is done yet), each file's folder whole or absent as listed
(:mod:`graphvision.execution.batch_stop`), and removes the folders it made
that hold nothing.
Each file gets its own folder, named after its path below the pattern's
fixed part (``photos/a/img.png`` and ``photos/b/img.png`` give
``OUT/a/img`` and ``OUT/b/img``), so no two files ever share a folder
(:func:`output_folders`). ``batch.csv`` lists every item: file, output
folder, status, seconds, error message and the scalar outputs (none for a file
whose folder could not be written); ``batch.json`` lists it and ``batch.html``
with their digests (:mod:`graphvision.execution.manifest`). A folder a previous
batch into the same place listed, whose file is not in this batch, and the
folder of a file that failed, keep their last run in ``history/`` and lose their
graphvision files: nothing there is left looking current. Item folders are
written only inside the output folder, never through a link below it, and the
files a pattern matches inside the output folder are not read (said so when no
other file matches).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from typing import Any

from graphvision.cache.memory_store import MemoryStore
from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import InputError
from graphvision.execution.arguments import (
    graph_argument,
    mapping_argument,
    names_argument,
    run_arguments,
)
from graphvision.execution.batch_files import (
    NO_PAGES,
    BatchItem,
    BatchPages,
    BatchResult,
    batch_files,
    checked_folders,
    common_parts,
    output_folders,
    pattern_root,
)
from graphvision.execution.batch_forked import forked_files
from graphvision.execution.batch_guard import refuse_in_bootstrap
from graphvision.execution.batch_lanes import FileLanes
from graphvision.execution.batch_run import BatchRun
from graphvision.execution.batch_signals import signals_held
from graphvision.execution.batch_stop import INTERRUPTED, NOT_STARTED
from graphvision.execution.batch_summary import summarise
from graphvision.execution.blas import one_blas_thread
from graphvision.execution.closing import Closing
from graphvision.execution.executors import (
    Executor,
    encodes_values,
    executor_width,
    make_executor,
)
from graphvision.execution.folder_lock import only_writer
from graphvision.execution.folders import missing_folders, remove_empty_folders
from graphvision.execution.record import RunHooks
from graphvision.execution.utf8_names import refuse_folder_not_utf8, refuse_names_not_utf8
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
    client_files: bool | None = None,
    pages: BatchPages = NO_PAGES,
    backends: Sequence[str] | str | None = None,
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
        at once (1 for ``sync``), twice that with one task per file (a task
        queued behind each running one: a worker never waits for the client), or the
        executor's ``files_at_once`` (Dask's, which sends several files a task).
    one_task_per_file : bool, optional
        After the first file, run each file's whole pipeline as one task of the
        executor, the shared nodes' values sent along (see
        :mod:`graphvision.execution.file_task`); default: on executors whose nodes run in
        other processes (``processes``, Dask), where a task costs most.
    client_files : bool, optional
        With one task per file, the client runs files itself until the first worker is
        ready (:mod:`graphvision.execution.batch_lanes`): the seconds a worker takes to
        start are no longer seconds lost, but a node that crashes its process in one of
        those files ends the batch, as on the first file. Default: on for ``processes``
        (workers forked on this machine, whose start costs seconds) and on an executor
        whose ``client_files`` attribute says so (Dask: a worker's first batch imports
        the plugins, scipy and numba's compiler, seconds before its first file).
    pages : BatchPages
        Report pages to write besides outputs, records and ``batch.csv``
        (``graphvision.run_batch`` writes ``report.md``, ``report.html`` and
        ``batch.html``: :data:`graphvision.views.batch_page.BATCH_PAGES`).
    backends : sequence of str, optional
        The backend lookup order of every file's run, as for :func:`graphvision.run`.

    Returns
    -------
    BatchResult
        Every item with its folder, status, error message and scalar outputs.

    Raises
    ------
    InputError
        When the glob matches no file, or ``inputs`` also gives ``input``.
    ValueError
        When ``output_dir`` is an empty string (it would be this folder).
    OutputFolderError
        When an item folder holds files graphvision did not write,
        ``batch.csv`` is not a graphvision summary, or ``output_dir``'s name is
        not UTF-8 (checked before anything runs).
    """
    refuse_in_bootstrap("a batch")  # a worker importing an unguarded script
    run_arguments(cache, executor, workers)
    graph = graph_argument(graph, backends)  # another order: compiled again with it
    inputs, outputs = mapping_argument(inputs, "inputs"), names_argument(outputs, "outputs")
    overrides = mapping_argument(overrides, "overrides")
    _check_batch_arguments(output_dir, inputs, input)
    registry = _checked_pipeline(graph, registry, inputs, input, outputs, overrides)
    out_dir = Path(output_dir)
    paths, root = _batch_paths(files, out_dir, input, registry)
    refuse_names_not_utf8(paths, input)
    folders = output_folders(paths, root, out_dir)
    stale = checked_folders(out_dir, folders, outputs if outputs is not None else graph.outputs)
    name = graph.name if isinstance(graph, Graph) else graph.graph.name
    with only_writer(out_dir, f"batch of {name}"):  # one writer per folder
        pool = make_executor(executor, workers) if isinstance(executor, str) else executor
        one_task_per_file = encodes_values(pool) if one_task_per_file is None else one_task_per_file
        cache = Cache(MemoryStore()) if one_task_per_file and cache is None else cache  # for seeds
        batch = BatchRun(
            graph, paths, folders, input, inputs or {}, pool, one_task_per_file, pages, out_dir
        )
        batch.options = dict(registry=registry, outputs=outputs, overrides=overrides, executor=pool)
        batch.options.update(cache=cache, keep_going=keep_going, hooks=hooks)
        made, own = missing_folders(out_dir, *folders), isinstance(executor, str)
        grouped = getattr(pool, "files_at_once", 0) if one_task_per_file else 0  # Dask's
        width = files_at_once or grouped or executor_width(pool) * (2 if one_task_per_file else 1)
        batch.file_threads = width > 1 and not one_task_per_file and not encodes_values(pool)
        default = getattr(pool, "client_files", hasattr(pool, "preload"))
        batch.client_files = one_task_per_file and (
            default if client_files is None else client_files
        )
        finished = _run_files(batch, width, on_item, own, (out_dir, stale, made))
        closing = Closing(pool) if own else None  # its workers end while the summary is made
        try:
            summary = summarise(finished, out_dir, pages, stale)
        finally:
            if closing is not None:
                closing.wait()
        return BatchResult(finished, summary, *batch.transferred())


def _check_batch_arguments(output_dir: object, inputs: dict[str, Any], input: str) -> None:
    """Refuse an output folder that is no path or whose name is not UTF-8, and the batch's
    input given as well."""
    if not isinstance(output_dir, (str, os.PathLike)):
        raise TypeError(f"output_dir must be a folder's path, got {output_dir!r}")
    if not str(output_dir).strip():  # Path('') would be this folder
        raise ValueError("output_dir is an empty path: give a folder ('.' for this one)")
    refuse_folder_not_utf8(Path(output_dir))
    if inputs and input in inputs:
        raise InputError(
            f"input '{input}' is given twice: once per file by the batch and once as"
            f" {inputs[input]!r}; drop one of them"
        )


def _source_hint(pattern: str, registry: Registry) -> str:
    """Why a pattern that names a source, or one mistyped (``file:photos/*.png``,
    ``sample:camera``, ``smaple:camera``), matched no file: a batch's pattern names files."""
    from graphvision.execution.inputs import scheme_hint

    scheme, sep, rest = pattern.partition(":")
    if sep and scheme == "file":
        return (
            f" (a batch's pattern names files, without a source's scheme: did you mean '{rest}'?)"
        )
    if sep and scheme in registry.sources:  # one value, not files: a single run's input
        return f" (a batch runs over files; '{pattern}' is one value: give it with -i, or inputs=)"
    return scheme_hint(pattern, registry)


def _batch_paths(
    files: str | Sequence[str | Path], out_dir: Path, input: str, registry: Registry
) -> tuple[list[Path], Path]:
    """The files of a batch and the folder their output folders are named below; none
    matched is an error, with a hint for a pattern that names a source (``sample:…``)."""
    if isinstance(files, str):
        paths, inside = batch_files(files, exclude=out_dir)
        if not paths and inside:
            raise InputError(
                f"batch input '{input}': every file '{files}' matches ({len(inside)}, such as "
                f"{inside[0]}) is inside the output folder {out_dir}, and a batch never reads "
                "its output folder (its own outputs would become its inputs): move the files "
                "out of it, or choose another --output-dir"
            )
        if not paths:
            raise InputError(
                f"batch input '{input}': no file matches '{files}'" + _source_hint(files, registry)
            )
        if inside:  # the others run; these are named, not dropped without a word
            warnings.warn(
                f"batch input '{input}': {len(inside)} file(s) '{files}' matches (such as "
                f"{inside[0]}) lie inside the output folder {out_dir} and are left out: a "
                "batch never reads its output folder",
                stacklevel=3,
            )
        return paths, pattern_root(files)
    paths = [Path(f) for f in files]
    return paths, Path(*common_parts([p.parent.parts for p in paths])) if paths else Path()


def _run_files(
    batch: BatchRun,
    width: int,
    on_item: Callable[[int, int, BatchItem], None] | None,
    own: bool,
    where: tuple[Path, set[Path], list[Path]],
) -> list[BatchItem]:
    """Every file of ``batch``, ``width`` at once; on Ctrl-C or an error, the files done
    so far are still summarised and the folders made for unfinished files removed. BLAS
    is held at one thread meanwhile (:mod:`graphvision.execution.blas`): each file's run in
    this process then only counts itself in, where it lowered and restored it through the
    helper thread, two thread switches a file (0.3-5 ms each on a loaded machine)."""
    items: list[BatchItem | None] = [None] * len(batch.paths)
    try:
        batch.stop.create()  # from here on, a stop is summarised
        with one_blas_thread():  # held from file to file: each file's run only counts in it
            for done, (index, item) in enumerate(_stream(batch, width), start=1):
                items[index] = item
                if on_item is not None:
                    on_item(done, len(batch.paths), item)
    except BaseException:
        with signals_held():  # a second Ctrl-C does not cut the stop short
            _stop(batch, items, own, where)
        raise
    finally:
        batch.remove_stop_flag()
    return [item for item in items if item is not None]


def _stop(
    batch: BatchRun,
    items: list[BatchItem | None],
    own: bool,
    where: tuple[Path, set[Path], list[Path]],
) -> None:
    """A stopped batch: no folder is started now, those being written are finished (those
    whose writer died are cleared), every file is summarised, done or not (even when none
    is), and the folders made for unfinished files removed."""
    out_dir, stale, made = where
    finished = batch.stop_writers()
    for index, item in finished.items():
        items[index] = items[index] or item
    if own:  # nodes still running are not waited for
        batch.pool.shutdown(wait=False, cancel_futures=True)
    try:
        not_run = _not_run(items, batch.paths, batch.folders, batch.started)
        summarise(not_run, out_dir, batch.pages, stale)
    finally:
        batch.remove_stop_flag()  # a writer that looks now sees it gone: stopped
        remove_empty_folders(made)


def _checked_pipeline(
    graph: Graph | CompiledGraph,
    registry: Registry | None,
    inputs: dict[str, Any] | None,
    input: str,
    outputs: Sequence[str] | None,
    overrides: dict[str, Any] | None,
) -> Registry:
    """The registry, after checking the pipeline, its overrides, inputs and outputs as each
    file's run will, and reading the inputs every file shares: an invalid batch stops
    before any file is looked at or folder made."""
    from graphvision.execution.inputs import resolve_input
    from graphvision.execution.run import _compiled, _wanted_outputs

    per_file = {**(inputs or {}), input: ""}
    compiled, found = _compiled(graph, registry, per_file, overrides or {})
    read = compiled.schedule_for(_wanted_outputs(compiled, outputs, per_file)).inputs
    for name, value in (inputs or {}).items():  # every file's: one that cannot be read fails all
        resolve_input(name, compiled.input_types[name], value, found)
    for name in sorted(set(read) - set(per_file)):  # so are the defaults the outputs read
        default = compiled.graph.inputs[name].default
        if default is not None:
            resolve_input(name, compiled.input_types[name], default, found, graph=compiled.graph)
    return found


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
            marked.append(BatchItem(path, folder, "interrupted", error=INTERRUPTED))
        else:
            marked.append(BatchItem(path, folder, "not run", error=NOT_STARTED))
    return marked


def _stream(batch: BatchRun, at_once: int) -> Iterator[tuple[int, BatchItem]]:
    """``(index, item)`` as items complete: item 0 alone (it fills the cache with the shared
    nodes), then the rest ``at_once`` at a time on client threads that wait on the executor
    (with one task per file, the client runs files itself while the workers start:
    :mod:`graphvision.execution.batch_lanes`)."""
    run_one, count = batch.run_one, len(batch.paths)
    if count == 0:
        return
    forked = forked_files(batch, at_once)  # every file on workers, the first one included
    if forked is not None:
        yield from forked.stream()
        return
    yield 0, run_one(0)
    if batch.one_task_per_file and at_once > 1:
        ready, stopped = batch.workers_ready, lambda: batch.stopped
        lanes = FileLanes(count, at_once, ready, stopped, batch.lane_files)
        yield from lanes.stream(batch.run_files, batch.client_lane())
        return
    if at_once <= 1:
        for index in range(1, count):
            yield index, run_one(index)
        return
    files = ThreadPoolExecutor(max_workers=at_once, thread_name_prefix="graphvision-file")
    pending = {files.submit(run_one, index): index for index in range(1, count)}
    try:
        for future in as_completed(pending):
            yield pending[future], future.result()
    except BaseException:  # Ctrl-C or an error: files not started yet are not started, and
        files.shutdown(wait=False, cancel_futures=True)  # those running are not waited for
        raise
    files.shutdown()
