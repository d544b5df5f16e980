"""A value the Dask executor's tasks share, held by every worker (:class:`SharedValue`).

A batch sends its job (:class:`~graphvision.execution.file_task.FileJob`: the
graph, the shared nodes' values) to the cluster once, as the result of a task
that returns it (:meth:`DaskExecutor.share
<graphvision.execution.dask.DaskExecutor.share>`), and each file task names that
task among its arguments. Dask runs a task on a worker that holds what the task
reads (``distributed.scheduler.decide_worker``: the candidates are the workers
holding its dependencies, the least busy of them chosen), so with the job on one
worker every file task went to that worker, the other idle unless Dask's work
stealing moved a task there: on a running ``LocalCluster(2)``, coins batches ran
from a quarter to all of their files on one worker, at sync's pace.

So the value is copied to each worker (:meth:`SharedValue.sent`): a task pinned
to the worker (``hold``) reads it, which Dask fetches there as any task's input.
The scheduler is asked which workers there are and which hold the value at most
every :data:`SPREAD_SECONDS` while tasks read it, so that a worker that joins
later (a local cluster's second worker connects after its first) or whose copy
Dask's memory manager dropped gets it again. Then the least busy worker takes
each task.

A value shared before the local cluster has started is sent with the first task
that reads it. It is the result of a task, not scattered data: a worker that dies
holding it loses nothing, the scheduler runs the task again (scattered data lost
with its worker failed every file still to run).
"""

from __future__ import annotations

import threading
import time
from typing import Any

from graphvision.execution.dask_worker import hold, shared

__all__ = ["SPREAD_SECONDS", "SharedValue"]

SPREAD_SECONDS = 0.25  # the workers holding a shared value are asked at most this often


class SharedValue:
    """``value`` on ``executor``'s cluster: the task that returns it, sent once (now, or with
    the first task that reads it), and copied to every worker."""

    def __init__(self, executor: Any, value: Any) -> None:
        self.executor, self.value = executor, value
        self.task: Any = None
        self._held: list[Any] = []  # the copying tasks of the last spread
        self._asked = -SPREAD_SECONDS
        self._lock = threading.Lock()

    def sent(self) -> Any:
        """The task that holds the value on the cluster (submitted on first need), copied to
        the workers that do not hold it yet (asked at most every :data:`SPREAD_SECONDS`)."""
        client = self.executor.client
        with self._lock:
            if self.task is None:
                self.task = client.submit(
                    shared, self.value, pure=False, retries=self.executor.retries
                )
            now = time.monotonic()
            if now - self._asked < SPREAD_SECONDS or not all(t.done() for t in self._held):
                return self.task
            self._asked = now
        from distributed import fire_and_forget  # run even if this handle is dropped

        holders = set(client.who_has([self.task]).get(self.task.key, ()))
        missing = [address for address in client.nthreads() if address not in holders]
        self._held = [
            client.submit(hold, self.task, workers=[address], allow_other_workers=True, pure=False)
            for address in missing
        ]
        fire_and_forget(self._held)
        return self.task

    def __reduce__(self) -> tuple[Any, ...]:  # never sent as such: see DaskExecutor._sent
        raise TypeError("a shared value travels as its task, not as the placeholder")
