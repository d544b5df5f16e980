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
8), at least one and at most :data:`FILES_PER_TASK`; one file a task until a
first task has come back. A task of fewer files leaves only for a
worker thread that would wait otherwise (fewer tasks in flight than threads:
the batch's start and its last files); one to queue behind a running task
waits until it is full. Without that rule, each task that came back let the
first file resubmitted leave alone: a quarter of a coins batch's tasks held
one file.

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

from graphvision.execution.dask_worker import on_worker
from graphvision.execution.file_group import FileTaskError, run_files

__all__ = ["FILES_PER_TASK", "GROUPS_PER_THREAD", "TASK_SECONDS", "FileGroups"]

FILES_PER_TASK = 8
GROUPS_PER_THREAD = 2
TASK_SECONDS = 0.1  # a task's files take about this long (Dask's advice: tasks of 100 ms or more)


class FileGroups:
    """Files of a batch submitted one at a time, sent to ``executor``'s cluster several to a task
    (as many as take about :data:`TASK_SECONDS`)."""

    def __init__(self, executor: Any) -> None:
        self.executor = executor
        self._waiting: deque[tuple[Any, str, str, Future]] = deque()
        self._task: Any = None  # the function that runs one file (file_task.run_file_task)
        self._job: Any = None  # the batch's job whose files are measured
        self._flying = 0
        self._measured = (0.0, 0)  # the job's files back so far: their CPU seconds, how many
        self._lock = threading.Lock()
        self._closed = False
        self._alone: deque[tuple[Any, str, str, Future]] = deque()  # see _next_alone
        self._isolating = False

    def submit(self, task: Any, job: Any, path: str, folder: str) -> Future:
        """A future of ``task(job, path, folder)``: the file's
        :class:`~graphvision.execution.file_task.FileOutcome`."""
        self._task = task
        future: Future = Future()
        future.set_running_or_notify_cancel()
        with self._lock:
            if self._job is not job:  # another batch's files: measured afresh
                self._job, self._measured = job, (0.0, 0)
            self._waiting.append((job, path, folder, future))
        self._pump()
        return future

    def _take(self) -> list[tuple[Any, str, str, Future]]:
        """The next task's files (the same job's, in order), or none while enough fly or
        while a task that would queue behind a running one is not full (see the module's
        docstring)."""
        with self._lock:
            width = max(1, self.executor.width)
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
        """Send tasks while fewer than enough are in flight and files wait."""
        while taken := self._take():
            try:
                task = self._submit(taken[0][0], [(path, folder) for _, path, folder, _ in taken])
            except BaseException as error:  # a cluster that did not start, or is closed
                self._landed(None, taken, error)
                continue
            task.add_done_callback(lambda done, taken=taken: self._landed(done, taken))

    def _landed(
        self, task: Any, taken: list[tuple[Any, str, str, Future]], error: Any = None
    ) -> None:
        """A task came back: each of its files' futures takes its outcome or error."""
        outcomes: list[Any] = []
        if task is not None:
            try:
                outcomes, seconds = self.executor.result(task, "file")
            except BaseException as failed:  # the whole task failed (its workers died...)
                error = failed
            else:
                self._measure(taken[0][0], seconds, len(outcomes))
        if error is not None and task is not None and len(taken) > 1 and not self._closed:
            with self._lock:  # each file again alone: only the one at fault fails
                self._alone.extend(taken)
                start, self._isolating = not self._isolating, True
            if start:
                self._next_alone()
            taken = []
        for k, (*_, future) in enumerate(taken):
            found = error if error is not None else outcomes[k]
            if isinstance(found, BaseException):
                future.set_exception(found)
            else:
                future.set_result(found)
        with self._lock:
            self._flying -= 1
        self._pump()

    def _submit(self, job: Any, files: list[tuple[str, str]]) -> Any:
        """A Dask task running ``files`` of ``job`` on a worker, one after another."""
        return self.executor.client.submit(
            on_worker, run_files, self._task, self.executor._sent(job), files,
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
            job, path, folder, future = self._alone.popleft()

        def landed(done: Any) -> None:
            try:
                found = self.executor.result(done, "file")[0][0]
            except BaseException as error:  # this file's worker died again: it is at fault
                found = error
            if isinstance(found, BaseException):
                future.set_exception(found)
            else:
                future.set_result(found)
            self._next_alone()

        try:
            if self._closed:
                raise FileTaskError("the Dask executor was shut down")
            task = self._submit(job, [(path, folder)])
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
