"""The files after the first of a one-task-per-file batch, taken from one queue by lanes: the
executor's (each sends files to the workers and waits for them) and, while the workers
start, the client's own.

A batch on processes or Dask used to send its files to the workers and wait:
the workers' start (the fork server importing graphvision, the plugins,
scipy and numba's compiler, or each Dask worker loading the plugins) took
seconds, during which the client, its first file done, did nothing. Here the
client runs files itself, one at a time, each as the workers would (a
:class:`~graphvision.execution.file_task.FileJob` run in this process), until
the first worker is ready; the executor's lanes wait for that, then take
files as they come: a lane that is ready takes the next files at once, whoever
else is still busy.

On the process pool, an executor lane sends several files as one task
(``per_task``: the executor's ``files_per_task``, 8 on processes): each
task cost the client about a millisecond of CPU (the pool's threads handing
the call and its result on, the lane's and the batch's threads woken), taken
from the cores the workers need; a 200-file coins batch spent 0.25 s of it.
A lane takes a ``2 × at_once``-th of the files left (rounded up), so tasks
shrink to one file as the batch ends and the workers finish together (38 tasks
for 199 files on two workers).

The client leaves the last ``at_once`` files to the workers (its lane takes a
file only while more remain): the end of the batch is the workers' pace, and
a batch no longer than that is done by the workers alone, as before (a
crashing node then kills a worker, not the client).

Stopped (Ctrl-C, an error in the caller), no lane takes a new file; a file the
client is running writes no folder once the batch has stopped.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Iterator

from graphvision.execution.batch_files import BatchItem

__all__ = ["FileLanes"]

Lane = Callable[[list[int]], list[tuple[int, BatchItem]]]
"""Runs files by their indices: each one's ``(index, item)``."""


class FileLanes:
    """Files ``1 .. count - 1``, handed out to ``at_once`` executor lanes (once ``ready`` is
    set), up to ``per_task`` at a time, and, until then, one at a time to the client's lane
    (see the module docstring)."""

    def __init__(
        self,
        count: int,
        at_once: int,
        ready: threading.Event,
        stopped: Callable[[], bool],
        per_task: int = 1,
    ) -> None:
        self.count, self.at_once, self.ready, self.stopped = count, at_once, ready, stopped
        self.per_task = per_task
        self._next = 1
        self._lock = threading.Lock()
        self._results: queue.SimpleQueue[tuple[int, BatchItem | BaseException]] = (
            queue.SimpleQueue()
        )

    def _take(self, in_client: bool) -> list[int]:
        """The next files to run, none when this lane is done."""
        with self._lock:
            left = self.count - self._next
            if self.stopped() or left <= 0:
                return []
            if in_client and (self.ready.is_set() or left <= self.at_once):
                return []
            size = 1 if in_client else min(self.per_task, -(-left // (2 * self.at_once)))
            self._next += size
            return list(range(self._next - size, self._next))

    def _lane(self, run: Lane, in_client: bool) -> None:
        if not in_client:
            self.ready.wait()
        while indices := self._take(in_client):
            try:
                done = run(indices)
            except BaseException as error:  # the lane's files fail; the caller re-raises it
                self._results.put((indices[0], error))
                return
            for found in done:
                self._results.put(found)

    def stream(self, on_workers: Lane, in_client: Lane | None) -> Iterator[tuple[int, BatchItem]]:
        """``(index, item)`` as files complete; ``in_client`` runs files in this process."""
        lanes = [(on_workers, False)] * self.at_once
        if in_client is not None:
            lanes.append((in_client, True))
        for k, (run, here) in enumerate(lanes):
            name = f"graphvision-file-{'client' if here else k}"
            threading.Thread(target=self._lane, args=(run, here), daemon=True, name=name).start()
        for _ in range(1, self.count):
            index, item = self._results.get()
            if isinstance(item, BaseException):
                raise item
            yield index, item
