"""A batch on ``processes`` whose every file runs on workers forked from the client, the
first one included (:mod:`graphvision.execution.file_workers`).

The workers are forked as the batch starts, when forking the client is safe then
(:func:`~graphvision.execution.worker_start.fork_context`), the first one sent the
first file before the next one is forked (a fork of the client takes milliseconds).
The first worker runs the first file as the client ran it before (node by node,
filling the cache with the nodes every file shares) and sends back its item and the
others' job (the graph, those shared values, the options); the others load the
plugins and their kernels meanwhile. Each worker is then sent the job once, and tasks
of up to ``files_per_task`` files (a ``2 × at_once``-th of the files left, so tasks
shrink to one file as the batch ends), two at a time: the next one waits in its pipe
while it runs the first. The first worker's next task is sent with the first file: it
runs it with the job it made, without waiting for the client.

No file runs in the client: a node that kills its process (``os._exit``,
SIGSEGV, SIGKILL) on any file, the first one included, kills a worker. The files
of the task it ran are settled by their claims
(:meth:`~graphvision.execution.batch_run.BatchRun.settled`: a folder written whole
counts, one left half-way is cleared), the others run again, each alone on a
worker that runs nothing beside it; a file whose worker dies again then fails,
saying how it ended (:func:`~graphvision.execution.worker_died.died`). The tasks
the dead worker had not begun go back to the queue, and a new worker replaces it.
When the first file's worker dies, the others' job is made in the client, without
shared values.

Stopped (Ctrl-C, SIGTERM, an error in the caller), no task is sent; each worker
ends once its task is done, and a file it runs writes no folder once the batch has
stopped (the stop flag: :mod:`graphvision.execution.batch_stop`). The files of a task
still waiting in a worker's pipe are listed ``not run``, not ``interrupted``.
"""

from __future__ import annotations

import collections
import contextlib
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from graphvision.execution.batch_files import BatchItem
from graphvision.execution.batch_items import plain_graph
from graphvision.execution.batch_preload import import_modules, load_kernels
from graphvision.execution.batch_run import BatchRun
from graphvision.execution.batch_write import failure_reason
from graphvision.execution.file_group import run_files
from graphvision.execution.file_task import FileOutcome, preload_modules, run_file_task
from graphvision.execution.file_workers import FileWorker, FileWorkers
from graphvision.execution.worker_died import died
from graphvision.execution.worker_start import context, fork_context

__all__ = ["ForkedFiles", "forked_files"]

TASKS_AHEAD = 2  # tasks a worker holds: the one it runs and the next, waiting in its pipe
FIRST_WHERE = "first file on a worker"  # its record's executor says so


@dataclass(frozen=True)
class _Task:
    """Files sent as one task: the first file (which makes the job), a retry alone, or
    files of the queue; ``sent`` when (``time.perf_counter``)."""

    indices: tuple[int, ...]
    first: bool = False
    alone: bool = False
    sent: float = field(default_factory=time.perf_counter, compare=False)


def forked_files(batch: BatchRun, at_once: int) -> ForkedFiles | None:
    """The batch's files on forked workers, when its executor asks for them
    (``forks_file_workers``: processes) and forking the client is safe now (else None: the
    first file runs in the client). Not with run hooks: they watch the first file's run in
    this process."""
    if not (batch.one_task_per_file and getattr(batch.pool, "forks_file_workers", False)):
        return None
    start = fork_context()
    if start is None or batch.options.get("hooks"):
        return None
    return ForkedFiles(batch, FileWorkers(start), at_once)


class ForkedFiles:
    """The files of ``batch`` on its forked workers (see the module docstring)."""

    def __init__(self, batch: BatchRun, workers: FileWorkers, at_once: int) -> None:
        self.batch, self.workers, self.at_once = batch, workers, at_once
        self.per_task = int(getattr(batch.pool, "files_per_task", 1))
        self.todo = collections.deque(range(1, len(batch.paths)))
        self.again: collections.deque[int] = collections.deque()  # to run alone
        self.done: list[tuple[int, BatchItem]] = []  # settled, not yet yielded
        self.job: Any = None

    def stream(self) -> Iterator[tuple[int, BatchItem]]:
        """``(index, item)`` as files complete, the first file's included."""
        batch = self.batch
        earlier = batch.pool.file_workers  # type: ignore[attr-defined]  # joined at its shutdown
        earlier[:] = [workers for workers in earlier if not workers.reaped()]  # (a long script's)
        earlier.append(self.workers)
        try:
            self._start(batch)
            left = len(batch.paths)
            while left:
                self._dispatch()
                found, dead = self.workers.answers() if not self.done else ([], [])
                for worker, task, answer in found:
                    self._answered(worker, task, answer)
                for worker in dead:
                    self._died(worker)
                while self.done:
                    left -= 1
                    yield self.done.pop(0)
        finally:  # each worker ends once its task is done; joined by the executor's shutdown
            try:
                self._not_begun()
            finally:
                self.workers.shutdown(wait=False)

    def _start(self, batch: BatchRun) -> None:
        """The workers, forked now: the first file sent to the first as soon as it is forked
        (each fork of the client takes milliseconds), a warm-up to each of the others."""
        _load_kernels(batch)
        state = {"batch": batch}
        batch.started.add(0)
        first = self.workers.start(state)
        self.workers.send(first, _Task((0,), first=True), _first_file, None)
        ahead = self._take()  # run with the job the first worker makes: no wait for the client
        if ahead is not None:
            self.workers.send(first, ahead, _run_files, (None, self._files(ahead)))
        for _ in range(1, max(1, int(getattr(batch.pool, "width", 1)))):
            self.workers.send(self.workers.start(state), _Task(()), _warm, None)

    def _dispatch(self) -> None:
        """Tasks for the workers that can take one: a file to retry goes alone to a worker
        that holds nothing; else files from the queue, up to :data:`TASKS_AHEAD` a worker."""
        if self.job is None:
            return
        for worker in self.workers.workers:
            while not worker.alone and len(worker.held) < TASKS_AHEAD:
                if self.again:
                    if not worker.held:
                        worker.alone = True
                        self._send(worker, _Task((self.again.popleft(),), alone=True))
                    break
                task = self._take()
                if task is None:
                    break
                self._send(worker, task)

    def _take(self) -> _Task | None:
        """The next files of the queue (those that cannot be read fail here, unsent)."""
        size = min(self.per_task, -(-len(self.todo) // (2 * self.at_once)))
        indices: list[int] = []
        while self.todo and len(indices) < size:
            index = self.todo.popleft()
            unreadable = self.batch.note_started(index)
            if unreadable is not None:
                self.done.append((index, self.batch.received(index, unreadable)))
            else:
                indices.append(index)
        return _Task(tuple(indices)) if indices else None

    def _send(self, worker: FileWorker, task: _Task) -> None:
        job = None if worker.has_job else self.job
        worker.has_job = True
        self.workers.send(worker, task, _run_files, (job, self._files(task)))

    def _files(self, task: _Task) -> list[tuple[str, str]]:
        """Each file of ``task``: its path and its folder."""
        paths, folders = self.batch.paths, self.batch.folders
        return [(str(paths[k]), str(folders[k])) for k in task.indices]

    def _not_begun(self) -> None:
        """The batch ends (stopped): the answers already in the workers' pipes are read,
        then the files of each task that waits in a worker's pipe behind the first it holds
        are not started (``not run`` in batch.csv, not ``interrupted``). Its worker may have
        begun one since: a file of it whose folder is whole counts as done (its claim says
        so), and one it was running writes nothing once the batch has stopped. Of the
        answers read, the first file's is taken (with its job); the others' files count as
        their claims say, the first one's too when its answer is not read (its worker keeps
        its claim: :meth:`~graphvision.execution.batch_stop.StopFlag.in_worker`)."""
        for worker in self.workers.workers:
            for task, answer in _unread(worker):
                if task.first:
                    self._first_answered(worker, answer)
            for task in worker.held[1:]:
                self.batch.started.difference_update(task.indices)

    def _answered(self, worker: FileWorker, task: _Task, answer: Any) -> None:
        """What a worker sent back for ``task``: each file's outcome, or why it failed."""
        if task.first:
            self._first_answered(worker, answer)
            return
        if not task.indices:  # a warm-up
            return
        worker.alone = False
        outcomes = answer if isinstance(answer, list) else [answer] * len(task.indices)
        for index, outcome in zip(task.indices, outcomes, strict=True):
            if isinstance(outcome, FileOutcome):
                self._settle(index, outcome)
                continue
            kept = self.batch.settled(index)
            if kept is not None:
                self._settle(index, kept)
            elif task.alone:  # it failed again, on its own: with its reason
                self._failed(index, f"{type(outcome).__name__}: {outcome}", task)
            else:
                self.again.append(index)

    def _first_answered(self, worker: FileWorker, answer: Any) -> None:
        """The first file's item, and the job the first worker made from its run."""
        if isinstance(answer, BaseException):
            batch = self.batch
            item = BatchItem(batch.paths[0], batch.folders[0], "failed")
            item.error = failure_reason(answer)
            self._job(None)
        else:
            item, job = answer
            worker.has_job = True  # it made it
            self._job(job)
        self.done.append((0, self.batch.received(0, item)))

    def _job(self, job: Any) -> None:
        """The job of the files after the first: the first worker's, or made here (without
        shared values) when there is none."""
        if job is None:
            job = self.batch.file_job(None)
        self.job = self.batch.job_sent = job

    def _failed(self, index: int, reason: str, task: _Task) -> None:
        """File ``index`` failed on its own, for ``reason`` (what batch.csv says), in
        ``task``: its seconds are the task's, from when it was sent."""
        item = BatchItem(self.batch.paths[index], self.batch.folders[index], "failed")
        item.error, item.seconds = reason, time.perf_counter() - task.sent
        self._settle(index, FileOutcome(item))

    def _settle(self, index: int, outcome: FileOutcome) -> None:
        self.batch.outcomes.append(outcome)
        self.done.append((index, self.batch.received(index, outcome.item)))

    def _died(self, worker: FileWorker) -> None:
        """A worker died: the task it ran settled (see the module docstring), those it had
        not begun sent again, and a new worker in its place."""
        ran, *waiting = worker.held or [_Task(())]
        for task in reversed(waiting):
            self.todo.extendleft(reversed(task.indices))
        code = worker.process.exitcode
        if ran.first:
            kept = self.batch.settled(0)
            self._job(None)  # the first worker's job died with it
            if kept is not None:
                self.done.append((0, self.batch.received(0, kept.item)))
            else:
                self.again.append(0)
        for index in ran.indices if not ran.first else ():
            kept = self.batch.settled(index)
            if kept is not None:
                self._settle(index, kept)
            elif ran.alone:
                forked = self.workers.start_method.get_start_method() == "fork"
                error = died("and again when retried alone", code, "file", forked=forked)
                self._failed(index, failure_reason(error), ran)
            else:
                self.again.append(index)
        if self.todo or self.again:
            self._replace()

    def _replace(self) -> None:
        """A new worker (a fork of the client when that is safe now, else from the server);
        when none can start and none is left, the files left run in the client."""
        start = fork_context() or context()
        self.workers.start_method = start
        try:
            self.workers.start({})
        except OSError:
            if not self.workers.workers:
                self._in_client()

    def _in_client(self) -> None:
        """The files left, run here: no worker could start."""
        where = "in the client: no worker could start"
        for index in [*self.again, *self.todo]:
            self.done.append((index, self.batch.run_in_client(index, where)))
        self.again.clear()
        self.todo.clear()


def _unread(worker: FileWorker) -> list[tuple[_Task, Any]]:
    """The answers already in ``worker``'s pipe, each with its task, taken from those it
    holds."""
    found = []
    with contextlib.suppress(Exception):  # it died, or a Ctrl-C cut a message short: its
        while worker.held and worker.conn.poll():  # files' claims say the rest
            answer = worker.conn.recv()
            found.append((worker.held.pop(0), answer))
    return found


def _load_kernels(batch: BatchRun) -> None:
    """In the client, before it forks: the modules the nodes import in their bodies, and
    when none of their numba kernels is loaded yet (a fresh command), every kernel's code
    from numba's cache, once for all the workers (each loaded them again on its first
    files: 0.5 s more of the workers' CPU on a fresh coins batch). A client that has run
    them (a script's second batch) loads nothing."""
    with contextlib.suppress(Exception):  # else each worker loads them on its first files
        registry, graph = batch.options["registry"], plain_graph(batch.graph)
        found = import_modules(preload_modules(registry, graph, tuple(batch.pages.run)))
        if "numba" not in sys.modules:
            return
        from numba.core.dispatcher import Dispatcher

        kernels = [
            kernel
            for module in found
            for kernel in vars(module).values()
            if isinstance(kernel, Dispatcher) and kernel.__module__ == module.__name__
        ]
        if not any(kernel.overloads for kernel in kernels):
            load_kernels(found)


def _first_file(state: dict[str, Any], _: Any) -> tuple[BatchItem, Any]:
    """In the first worker: the batch's first file, run as the client ran it, and the job of
    the others made from its run (kept here for this worker's next tasks)."""
    batch: BatchRun = state["batch"]
    batch.first_where = FIRST_WHERE
    batch.stop = batch.stop.in_worker()  # its claim left for the client, which has no result yet
    item = batch.run_first()
    state["job"] = batch.job_sent
    return item, batch.job_sent


def _warm(state: dict[str, Any], _: Any) -> None:
    """In the other workers, while the first runs the first file: the client's registry
    for the job to come (a fork has its plugins loaded; else 0.3 s to load them again).
    Kernels load on a worker's first files, as the client's would: loading every signature
    numba's cache holds took 0.1 s more of a worker's CPU here."""
    with contextlib.suppress(Exception):  # else on its first file
        state["batch"].file_job(None)


def _run_files(state: dict[str, Any], payload: tuple[Any, list[tuple[str, str]]]) -> list[Any]:
    """In a worker: files of the batch, each one's outcome or what it raised
    (:func:`~graphvision.execution.file_group.run_files`); the job comes with the first."""
    job, files = payload
    if job is not None:
        state["job"] = job
    if "job" not in state:  # sent ahead of the first file, which made none
        raise RuntimeError("the batch's first file did not prepare the other files' job")
    return run_files(run_file_task, state["job"], files)[0]
