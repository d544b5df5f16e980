"""A batch's files on Dask, several to a task (:class:`FileGroups`).

A batch sends each file after the first as one task
(:mod:`graphvision.execution.file_task`). On Dask a task costs the client's
process (where a ``LocalCluster``'s scheduler runs too) milliseconds of CPU:
the task's submission, the scheduler's transitions, the worker's report, the
result's fetch through the scheduler, the key's release; and the worker's
event loop a few more. On 2 cores, with both workers computing, that was 10
to 16 ms of CPU per file (coins files: 40 ms each), taken from the workers'
cores.

Here the files the batch's lanes submit at the same time travel together:
at most :data:`GROUPS_PER_THREAD` tasks per worker thread are in flight (one
running, one queued behind it, so that no worker waits for the client), and
the files submitted meanwhile wait in the client and leave together in the
next task. A task's size follows the files' own time: as many files as take
about :data:`TASK_SECONDS` by the files measured so far (the CPU time of the
worker's thread, which a loaded machine does not stretch as it does the
clock: sized by wall time, coins tasks under a load of 8 held 3 files, not
8), at least one and at most :data:`FILES_PER_TASK` (16: with at most 8, a
200-file batch of 5 ms coins files made 29 tasks, and its client spent a
fifth more CPU time, 0.28 s against 0.23 s, medians of 16 batches each
alternated on a running ``LocalCluster(2)``); one file a task until a
first task has come back. A task of fewer files leaves only for a
worker thread that would wait otherwise (fewer tasks in flight than threads:
the batch's start and its last files); one to queue behind a running task
waits until it is full. Without that rule, each task that came back let the
first file resubmitted leave alone: a quarter of a coins batch's tasks held
one file. Each task's result is awaited on the client's event loop
(:func:`~graphvision.execution.dask_results.fetch_on_loop`), which hands its
files their outcomes and sends the next task from there, so nothing sent from
there may wait for the scheduler (the cluster's width and the job's task are
read as each file is submitted).

A batch runs ``width × GROUPS_PER_THREAD × FILES_PER_TASK`` files at once on
Dask (:attr:`DaskExecutor.files_at_once
<graphvision.execution.dask.DaskExecutor.files_at_once>`), so that the tasks
in flight can be full. Each file keeps its own outcome: one that raises fails
alone, named (:class:`FileTaskError`). A task whose worker died runs again
whole (``retries``, and Dask's own ``allowed-failures``), its files written
whole before come back from their claims, not written again; a task of
several files that fails whole (a node that kills every worker it runs on)
sends each file again as a task of its own, so only the file at fault fails.
"""

from __future__ import annotations

import threading
from collections import deque
from concurrent.futures import Future
from typing import Any

from graphvision.execution.dask_results import settle_found
from graphvision.execution.dask_worker import on_worker
from graphvision.execution.file_group import FileTaskError, run_files

__all__ = ["FILES_PER_TASK", "GROUPS_PER_THREAD", "TASK_SECONDS", "FileGroups"]

FILES_PER_TASK = 16  # a task's most files (see the module's docstring)
GROUPS_PER_THREAD = 2
TASK_SECONDS = 0.1  # a task's files take about this long (Dask's advice: tasks of 100 ms or more)

Call = tuple[Any, Any, str, str, Future]
"""A file submitted: its job, what stands for the job in a task, its path, its folder, its
future."""


class FileGroups:
    """Files of a batch submitted one at a time, sent to ``executor``'s cluster several to a task
    (as many as take about :data:`TASK_SECONDS`)."""

    def __init__(self, executor: Any) -> None:
        self.executor = executor
        self._waiting: deque[Call] = deque()
        self._task: Any = None  # the function that runs one file (file_task.run_file_task)
        self._job: Any = None  # the batch's job whose files are measured
        self._flying = 0
        self._measured = (0.0, 0)  # the job's files back so far: their CPU seconds, how many
        self._lock = threading.Lock()
        self._closed = False
        self._alone: deque[Call] = deque()  # see _next_alone
        self._isolating = False
        self._width = 1  # the cluster's, as last read by submit

    def submit(self, task: Any, job: Any, path: str, folder: str) -> Future:
        """A future of ``task(job, path, folder)``: the file's
        :class:`~graphvision.execution.file_task.FileOutcome`."""
        self._task = task
        future: Future = Future()
        future.set_running_or_notify_cancel()
        width, sent = max(1, self.executor.width), self.executor._sent(job)  # here, not on
        with self._lock:  # the event loop, which must not wait for the scheduler (see _pump)
            if self._job is not job:  # another batch's files: measured afresh
                self._job, self._measured = job, (0.0, 0)
            self._width = width
            self._waiting.append((job, sent, path, folder, future))
        self._pump()
        return future

    def _take(self) -> list[Call]:
        """The next task's files (the same job's, in order), or none while enough fly or
        while a task that would queue behind a running one is not full (see the module's
        docstring)."""
        with self._lock:
            width = self._width
            if self._closed or not self._waiting or self._flying >= width * GROUPS_PER_THREAD:
                return []
            job, size = self._waiting[0][0], self._size()
            taken = [call for call in self._waiting if call[0] is job][:size]
            if len(taken) < size and self._flying >= width:
                return []  # more files come as the lanes get their results
            for call in taken:
                self._waiting.remove(call)
            self._flying += 1
            return taken

    def _size(self) -> int:
        """Files a task: about :data:`TASK_SECONDS` of them, by the files measured so far."""
        seconds, count = self._measured
        if count == 0 or seconds <= 0:
            return 1
        return max(1, min(FILES_PER_TASK, round(TASK_SECONDS * count / seconds)))

    def _pump(self) -> None:
        """Send tasks while fewer than enough are in flight and files wait; each task's result
        is fetched on the client's event loop (:meth:`_fetched`), which then pumps again. Called
        from the batch's lanes and from that loop: it asks the scheduler nothing (the width
        and the job's task are read by :meth:`submit`)."""
        while taken := self._take():
            try:
                files = [(path, folder) for _, _, path, folder, _ in taken]
                task = self._submit(files, taken[0][1])
            except BaseException as error:  # a cluster that did not start, or is closed
                self._landed(taken, error=error)
                continue
            self.executor.when_done(
                task, lambda found, error, taken=taken: self._fetched(taken, found, error), "file"
            )

    def _fetched(self, taken: list[Call], found: Any, error: BaseException | None) -> None:
        """A task's result, fetched on the client's event loop (a done-callback's thread,
        waiting in turn for the loop's fetch, cost two thread hops a task), or the error of
        the whole task (its workers died...)."""
        if error is not None:
            self._landed(taken, error=error, whole=True)
            return
        outcomes, seconds = found
        self._measure(taken[0][0], seconds, len(outcomes))
        self._landed(taken, outcomes)

    def _landed(
        self,
        taken: list[Call],
        outcomes: list[Any] | None = None,
        error: BaseException | None = None,
        whole: bool = False,
    ) -> None:
        """A task came back (``outcomes``), or failed whole (``error``, ``whole``: its workers
        died...), or could not be sent (``error``): each of its files' futures takes its
        outcome or the error."""
        if whole and len(taken) > 1 and not self._closed:
            with self._lock:  # each file again alone: only the one at fault fails
                self._alone.extend(taken)
                start, self._isolating = not self._isolating, True
            if start:  # the first of them leaves before any file still waiting
                self._next_alone()
            taken = []
        for k, (*_, future) in enumerate(taken):
            settle_found(future, error if error is not None or outcomes is None else outcomes[k])
        with self._lock:
            self._flying -= 1
        self._pump()

    def _submit(self, files: list[tuple[str, str]], job: Any) -> Any:
        """A Dask task running ``files`` on a worker, one after another; ``job``: what stands
        for their job in a task (:meth:`DaskExecutor._sent
        <graphvision.execution.dask.DaskExecutor._sent>`)."""
        return self.executor.client.submit(
            on_worker, run_files, self._task, job, files,
            pure=False, retries=self.executor.retries,
        )  # fmt: skip

    def _next_alone(self) -> None:
        """The next file of the tasks of several that failed whole, as a task of its own,
        one at a time (a file whose node kills its worker never shares a worker with another
        of them, which Dask would count as that one's death too); its outcome or error to
        its future. Those the tasks wrote whole come back from their claims
        (:func:`~graphvision.execution.file_task.run_file_task`)."""
        with self._lock:
            if not self._alone:
                self._isolating = False
                return
            _, job, path, folder, future = self._alone.popleft()  # the job's task: no wait

        def landed(done: Any) -> None:
            try:
                found = self.executor.result(done, "file")[0][0]
            except BaseException as error:  # this file's worker died again: it is at fault
                found = error
            settle_found(future, found)
            self._next_alone()

        try:
            if self._closed:
                raise FileTaskError("the Dask executor was shut down")
            task = self._submit([(path, folder)], job)
        except BaseException as error:  # a cluster that is closed
            future.set_exception(error)
            self._next_alone()
            return
        task.add_done_callback(landed)

    def _measure(self, job: Any, seconds: float, files: int) -> None:
        """``files`` of ``job`` took ``seconds`` of a worker thread's CPU time."""
        with self._lock:
            if job is self._job:
                total, count = self._measured
                self._measured = (total + seconds, count + files)

    def close(self) -> None:
        """No task is sent from now on; files still waiting fail (the batch has stopped)."""
        with self._lock:
            self._closed = True
            waiting, self._waiting = list(self._waiting), deque()
        for *_, future in waiting:
            future.set_exception(FileTaskError("the Dask executor was shut down"))
