"""The files of one batch as they run (:class:`BatchRun`): the first in this process, the
others in this process's threads or as one task each of the executor
(:mod:`graphvision.execution.file_task`)."""

from __future__ import annotations

import contextlib
import dataclasses
import pickle
import threading
import uuid
import warnings
from concurrent.futures import Future
from pathlib import Path
from typing import Any

from graphvision.compiler.compile import CompiledGraph
from graphvision.execution.batch_files import BatchItem, BatchPages, unreadable_reason
from graphvision.execution.batch_items import could_not_start, plain_graph, run_file, run_item
from graphvision.execution.batch_lanes import Lane
from graphvision.execution.batch_stop import INTERRUPTED, StopFlag, writing
from graphvision.execution.batch_write import failure_reason, finish_item
from graphvision.execution.executors import (
    Executor,
    SyncExecutor,
    executor_name,
    executor_width,
)
from graphvision.execution.file_group import run_files
from graphvision.execution.file_task import (
    FileJob,
    FileOutcome,
    Seed,
    local_plugin_paths,
    preload_modules,
    run_file_task,
    shared_seeds,
    use_registry,
    warm_worker,
)
from graphvision.execution.folders import clear_unfinished
from graphvision.execution.record import RunResult
from graphvision.execution.worker_start import fork_context, warm_server
from graphvision.graph.model import Graph

__all__ = ["BatchRun"]


class BatchRun:
    """The files of one batch, run one at a time by :meth:`run_one` (from several threads).

    The first file runs node by node and fills the cache with the nodes every
    file shares; with ``one_task_per_file``, the others then run as one task each
    with those values sent along. Any failure while a file runs or its folder is
    written fails that file alone, with its reason.
    """

    def __init__(
        self,
        graph: Graph | CompiledGraph,
        paths: list[Path],
        folders: list[Path],
        input: str,
        inputs: dict[str, Any],
        pool: Executor,
        one_task_per_file: bool,
        pages: BatchPages,
        out_dir: Path,
    ) -> None:
        self.graph, self.paths, self.folders = graph, paths, folders
        self.input, self.inputs, self.pool = input, inputs, pool
        self.one_task_per_file, self.pages, self.out_dir = one_task_per_file, pages, out_dir
        self.options: dict[str, Any] = {}
        self.compiled: CompiledGraph | None = None
        self.file_threads = False  # files at once in this process: each one runs on ``sync``
        self.client_files = False  # the client runs files while the workers start
        self.job_sent: FileJob | None = None
        self.job: Any = None  # the FileJob of further files, or the executor's handle on it
        self.outcomes: list[FileOutcome] = []  # what the file tasks sent back
        self.started: set[int] = set()
        self.finished: dict[int, BatchItem] = {}  # as they complete, whoever runs them
        self.stopped = False
        # made as the files start; on Dask, whose workers may be on other machines, in the
        # output folder they share
        self.stop = StopFlag.planned(out_dir if hasattr(pool, "share") else None)
        self.workers_ready = threading.Event()  # a worker has started (or could not)
        self.first_where = "first file in this process"  # its record's executor says so

    def run_one(self, index: int) -> BatchItem:
        if index > 0 or not self.one_task_per_file:
            return self._run_one(index)
        fork = hasattr(self.pool, "fork_workers") and fork_context() is not None
        if not fork:
            self._warm_workers()  # while the first file runs here
        item = self.run_first()
        if fork:  # not after Ctrl-C: only when the first file returned
            self._fork_workers()
        return item

    def run_first(self) -> BatchItem:
        """The first file, in this process, and the others' job made from its run."""
        try:
            return self._run_one(0)
        finally:  # a first file that failed early: the others' job has no shared values
            if self.job is None:
                with contextlib.suppress(Exception):
                    self.job_sent = self.file_job(None)
                    self.job = self._share(self.job_sent)

    def _run_one(self, index: int) -> BatchItem:
        path, folder = self.paths[index], self.folders[index]
        unreadable = self.note_started(index)
        if unreadable is not None:
            return unreadable
        try:
            if index > 0 and self.one_task_per_file:  # the worker writes the folder
                outcome = self._on_worker(index)
                self.outcomes.append(outcome)
                return self.received(index, outcome.item)
            item, result = self._run(index)
            with writing(self.stop, folder, lambda: self.stopped) as claim:
                if not claim:  # the batch was interrupted meanwhile: its folder is not written
                    item.status, item.error = "interrupted", INTERRUPTED
                    return item
                item = finish_item(item, folder, result, self.pages.run, self.out_dir)
                claim.written(item)
            return self.received(index, item)
        except Exception as error:  # whatever it is, it fails this file alone
            return BatchItem(path, folder, "failed", error=failure_reason(error))

    def note_started(self, index: int) -> BatchItem | None:
        """Note file ``index`` as started; its failed item when it is matched by the pattern
        but is not a file that can be read (else None)."""
        self.started.add(index)
        path = self.paths[index]
        reason = unreadable_reason(path)
        if reason:
            return BatchItem(path, self.folders[index], "failed", error=f"{path} {reason}")
        return None

    def received(self, index: int, item: BatchItem) -> BatchItem:
        """The file's item has reached the client: counted, its claim dropped (a file not
        written since the batch stopped is neither)."""
        if item.status != "interrupted":
            self.finished[index] = item
        self.stop.dropped(self.folders[index])
        return item

    def run_files(self, indices: list[int]) -> list[tuple[int, BatchItem]]:
        """Files after the first, as one task of the executor when there are several (see
        :mod:`graphvision.execution.batch_lanes`): each file's ``(index, item)``. A file that
        failed in a task that failed whole (its worker died) is settled as :meth:`_on_worker`
        settles it, then, unless written whole, runs again as a task of its own: only the
        file at fault fails."""
        if len(indices) == 1 or not self.one_task_per_file:
            return [(index, self.run_one(index)) for index in indices]
        found, sent = {}, []
        for index in indices:
            unreadable = self.note_started(index)
            if unreadable is not None:
                found[index] = unreadable
            else:
                sent.append(index)
        files = [(str(self.paths[k]), str(self.folders[k])) for k in sent]
        outcomes: list[Any] = [None] * len(sent)
        with contextlib.suppress(Exception):  # the task failed whole: each file on its own
            outcomes = self.pool.submit(run_files, run_file_task, self.job, files).result()[0]
        for index, outcome in zip(sent, outcomes, strict=True):
            if not isinstance(outcome, FileOutcome):  # it raised, or its worker died
                outcome = self.settled(index) or self._alone(index)
            self.outcomes.append(outcome)
            found[index] = self.received(index, outcome.item)
        return [(index, found[index]) for index in indices]

    def _alone(self, index: int) -> FileOutcome:
        """A file of a task that failed, run again as a task of its own (not once the batch
        has stopped: then it is interrupted)."""
        if self.stopped:
            return FileOutcome(
                BatchItem(self.paths[index], self.folders[index], "interrupted", error=INTERRUPTED)
            )
        return self._on_worker(index)

    def _on_worker(self, index: int) -> FileOutcome:
        """One file as one task of the executor. A task whose worker died (and died again,
        or could not start again: the executor retries once) counts as its claim says
        (:meth:`settled`); when no worker could start, the file runs once more here, as the
        client's own files do."""
        path, folder = self.paths[index], self.folders[index]
        outcome, died = run_file(self.pool, self.job, path, folder)
        if died is None:
            return outcome
        kept = self.settled(index)
        if kept is not None:
            return kept
        if could_not_start(died) and self.job_sent is not None and not self.stopped:
            return FileOutcome(self.run_in_client(index, "in the client: no worker could start"))
        return outcome

    def settled(self, index: int) -> FileOutcome | None:
        """A file whose task failed, as its claim says: its folder written whole is the
        file's (its outcome); one left half-way is cleared, its claim dropped (None)."""
        folder = self.folders[index]
        name = StopFlag.name(folder)
        kept = self.stop.left().get(name, "no claim")
        if isinstance(kept, BatchItem):  # written whole before its worker died
            return FileOutcome(kept)
        if kept is None:  # its worker died writing it
            clear_unfinished(
                folder, self.wanted_outputs(), placed=self.stop.placed_record(name, folder)
            )
        self.stop.dropped(folder)
        return None

    def client_lane(self) -> Lane | None:
        """The client's lane of files while the workers start, when it has one."""
        if not self.client_files:
            return None
        return lambda indices: [(index, self.run_in_client(index)) for index in indices]

    @property
    def lane_files(self) -> int:
        """Files a lane sends to the executor as one task: its ``files_per_task``, unless it
        groups the files itself (Dask's ``files_at_once``)."""
        if hasattr(self.pool, "files_at_once"):
            return 1
        return int(getattr(self.pool, "files_per_task", 1))

    def wanted_outputs(self) -> list[str]:
        """The outputs each file's folder holds."""
        outputs = self.options.get("outputs")
        return list(outputs) if outputs is not None else list(plain_graph(self.graph).outputs)

    def remove_stop_flag(self) -> None:
        self.stop.remove()

    def stop_writers(self) -> dict[int, BatchItem]:
        """The batch has stopped: no folder is started from now on; those being written are
        finished first. Every file finished so far, by its index (see
        :mod:`graphvision.execution.batch_stop`)."""
        self.stopped = True
        self.stop.raise_()
        self.stop.wait()
        index = {StopFlag.name(folder): k for k, folder in enumerate(self.folders)}
        for name, kept in self.stop.left().items():
            k = index.get(name)
            if k is None or k in self.finished:
                continue
            if kept is not None:  # whole, its result not (yet) here: counted from the claim
                self.finished[k] = kept
            else:  # its writer died half-way (SIGTERM, kill -9): what it wrote goes
                placed = self.stop.placed_record(name, self.folders[k])
                clear_unfinished(self.folders[k], self.wanted_outputs(), placed=placed)
        return dict(self.finished)

    def run_in_client(
        self, index: int, where: str = "in the client while the workers started"
    ) -> BatchItem:
        """A further file run here as a worker would run it (while the workers start: see
        :mod:`graphvision.execution.batch_lanes`); its folder is not written once stopped."""
        path, folder = self.paths[index], self.folders[index]
        unreadable = self.note_started(index)
        if unreadable is not None:
            return unreadable
        try:
            if self.job_sent is None:
                raise RuntimeError("the batch's first file did not prepare the other files' job")
            name = f"{executor_name(self.pool)}, {where}"
            job = dataclasses.replace(self.job_sent, executor=name)
            item = run_file_task(job, str(path), str(folder), lambda: self.stopped).item
            return self.received(index, item)
        except Exception as error:  # whatever it is, it fails this file alone
            return BatchItem(path, folder, "failed", error=failure_reason(error))

    def _run(self, index: int) -> tuple[BatchItem, RunResult | None]:
        """A file run in this process (the first one; all of them without one task per file)."""
        item_inputs = {**self.inputs, self.input: str(self.paths[index])}
        path, folder, options = self.paths[index], self.folders[index], self.options
        options = {**options, "inputs": item_inputs}
        if index == 0 and self.one_task_per_file:  # here, while the workers load the plugins
            options["executor"] = SyncExecutor()
            options["executor"].name = f"{executor_name(self.pool)}, {self.first_where}"
        elif index > 0 and self.file_threads:  # each file in its thread, one node at a time
            options["executor"] = SyncExecutor()
            options["executor"].name = f"{executor_name(self.pool)}, one file per thread"
        graph = self.graph
        if self.compiled is not None and not options["overrides"]:
            graph = self.compiled  # compiled once, by the first file's run
        item, result = run_item(graph, path, folder, options)
        if index == 0 and result is not None:
            self.compiled = result.compiled
        if index == 0 and self.one_task_per_file:
            self.job_sent = self.file_job(result)
            self.job = self._share(self.job_sent)
        return item, result

    def file_job(self, first: RunResult | None) -> FileJob:
        """What each further file's task needs, with the shared values the first file cached."""
        options, cache = self.options, self.options["cache"]
        seeds: list[Seed] = []
        if first is not None and cache is not None:
            seeds = shared_seeds(first.compiled, first.record, cache, self.input)
        graph, overrides = plain_graph(self.graph), options["overrides"]
        job = FileJob(
            token=uuid.uuid4().hex,
            graph=graph.with_overrides(overrides) if overrides else graph,
            plugin_paths=tuple(local_plugin_paths(options["registry"])),
            input=self.input,
            inputs=self.inputs,
            outputs=None if options["outputs"] is None else list(options["outputs"]),
            keep_going=options["keep_going"],
            seeds=seeds,
            pages=tuple(self.pages.run),
            store=cache.disk if cache is not None else None,
            executor=f"{executor_name(self.pool)}, {_tasks(self.pool)}",
            out_dir=self.out_dir,
            stop=self.stop,
        )
        use_registry(job, options["registry"])  # for the client's own files
        return job

    def transferred(self) -> tuple[int, int]:
        """The bytes of the values the file tasks computed, and of what passed through the
        client for them (see :class:`~graphvision.execution.batch_files.BatchResult`)."""
        if not self.outcomes:
            return 0, 0
        sent = len(pickle.dumps(self.job_sent)) + sum(
            len(pickle.dumps((str(o.item.file), str(o.item.output_dir)))) for o in self.outcomes
        )
        received = sum(len(pickle.dumps(outcome)) for outcome in self.outcomes)
        return sum(o.value_bytes for o in self.outcomes), sent + received

    def _warm_workers(self) -> None:
        """Have each worker start and load the plugins now, while the first file runs here
        (from a thread: a worker's start may wait for the executor's server to import);
        ``workers_ready`` is set as the first worker is ready, or could not start."""
        registry, graph = self.options["registry"], plain_graph(self.graph)
        preload = getattr(self.pool, "preload", None)
        paths = tuple(local_plugin_paths(registry))
        warm = getattr(self.pool, "warm", None)

        def start() -> None:
            modules: tuple[str, ...] = ()
            with contextlib.suppress(Exception):  # else workers import them on their first file
                modules = tuple(preload_modules(registry, graph, tuple(self.pages.run)))
            if preload is not None:  # the server imports them and compiles the graph, once
                with contextlib.suppress(Exception):
                    warm_server(graph, paths, (*self.inputs, self.input))
                    preload(list(modules))
            futures: list[Future] = []
            with contextlib.suppress(Exception):  # a worker that failed shows on its first file
                if warm is not None:  # on every worker (Dask)
                    futures = list(warm(warm_worker, graph, paths, modules) or ())
                else:
                    for _ in range(executor_width(self.pool)):
                        futures.append(self.pool.submit(warm_worker, graph, paths, modules))
            for future in futures:
                future.add_done_callback(lambda _: self.workers_ready.set())
            if not futures:
                self.workers_ready.set()

        threading.Thread(target=start, daemon=True, name="graphvision-warm-workers").start()

    def _fork_workers(self) -> None:
        """Start the workers now as forks of this process, which has run the first file
        (its modules imported, kernels loaded, plugins and graph ready), from this thread
        while no other runs (:func:`~graphvision.execution.worker_start.fork_context`);
        else from the server, as :meth:`_warm_workers` does."""
        if not self.pool.fork_workers():  # type: ignore[attr-defined]  # checked by run_one
            self._warm_workers()
            return
        graph, width = plain_graph(self.graph), executor_width(self.pool)
        paths = tuple(local_plugin_paths(self.options["registry"]))
        futures: list[Future] = []
        with warnings.catch_warnings(), contextlib.suppress(Exception):
            warnings.simplefilter("ignore", DeprecationWarning)  # 3.12's os.fork note on threads
            futures = [self.pool.submit(warm_worker, graph, paths) for _ in range(width)]
        for future in futures:
            future.add_done_callback(lambda _: self.workers_ready.set())
        if not futures:
            self.workers_ready.set()

    def _share(self, job: FileJob) -> Any:
        """The job, or the executor's handle on it: sent once to every worker (Dask's
        ``share``), or pickled once for all the tasks (the process pool's ``sent_once``)."""
        share = getattr(self.pool, "share", None) or getattr(self.pool, "sent_once", None)
        return share(job) if share is not None else job


def _tasks(pool: Any) -> str:
    """How a batch's files go to ``pool``'s workers, as its records say: several a task on
    an executor that groups them (``files_per_task``: processes, Dask), else one each."""
    per_task = getattr(pool, "files_per_task", 1)
    return f"up to {per_task} files a task" if per_task > 1 else "one task per file"
