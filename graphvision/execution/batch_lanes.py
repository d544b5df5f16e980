"""The files after the first of a one-task-per-file batch, taken from one queue by lanes: the
executor's (each sends one file at a time to the workers and waits for it) and, while the
workers start, the client's own.

A batch on processes or Dask used to send its files to the workers and wait:
the workers' start (the fork server importing graphvision, the plugins,
scipy and numba's compiler, or each Dask worker loading the plugins) took
seconds, during which the client, its first file done, did nothing. Here the
client runs files itself, one at a time, each as the workers would (a
:class:`~graphvision.execution.file_task.FileJob` run in this process), until
the first worker is ready; the executor's lanes wait for that, then take
files as they come. Files are handed out one by one, so a lane that is ready
takes the next file at once, whoever else is still busy.

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

Lane = Callable[[int], BatchItem]


class FileLanes:
    """Files ``1 .. count - 1``, handed out one at a time to ``at_once`` executor lanes (once
    ``ready`` is set) and, until then, to the client's lane (see the module docstring)."""

    def __init__(
        self,
        count: int,
        at_once: int,
        ready: threading.Event,
        stopped: Callable[[], bool],
    ) -> None:
        self.count, self.at_once, self.ready, self.stopped = count, at_once, ready, stopped
        self._next = 1
        self._lock = threading.Lock()
        self._results: queue.SimpleQueue[tuple[int, BatchItem | BaseException]] = (
            queue.SimpleQueue()
        )

    def _take(self, in_client: bool) -> int | None:
        """The next file to run, or None when this lane is done."""
        with self._lock:
            if self.stopped() or self._next >= self.count:
                return None
            if in_client and (self.ready.is_set() or self.count - self._next <= self.at_once):
                return None
            self._next += 1
            return self._next - 1

    def _lane(self, run: Lane, in_client: bool) -> None:
        if not in_client:
            self.ready.wait()
        while (index := self._take(in_client)) is not None:
            try:
                self._results.put((index, run(index)))
            except BaseException as error:  # the lane's file fails; the caller re-raises it
                self._results.put((index, error))
                return

    def stream(self, on_workers: Lane, in_client: Lane | None) -> Iterator[tuple[int, BatchItem]]:
        """``(index, item)`` as files complete; ``in_client`` runs a file in this process."""
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
