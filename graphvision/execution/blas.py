"""One BLAS thread while nodes run: the same bits whatever runs beside a node.

Why
---
OpenBLAS splits a product differently with one thread and with two, and the
sums come out in another order: ``(300, 256) @ (256, 64)`` differs in the
14th digit. Its thread count is process-wide, so when it depended on what
else was running (a node that lowered it for its own small products), a
node's value depended on which nodes ran beside it: the R-CNN head scored
its proposals with one BLAS thread or two depending on whether the
detector's twin ran at the same moment, and a warm run that recomputed only
some nodes gave other detections than the cold one. A run therefore holds
BLAS at one thread from its first node to its last, on every executor (in
worker processes and on Dask workers for good), so a node computes the same
bits alone or beside others, cold or warm. The parallelism is across nodes
and files, where the executors put it; one BLAS thread is also faster for
the many small products of mini-batch training (one epoch of ``rcnn.yaml``'s
backbone: 11.7 s with OpenBLAS's threads, 2.5 s with one).

How
---
threadpoolctl's limit is process-wide, so :func:`one_blas_thread` counts its
users under a lock: the first applies the limit, the last restores the
original, and a run inside a batch or a node inside a run only counts.
Finding the loaded BLAS libraries takes milliseconds (threadpoolctl walks
every loaded shared library; 3-8 ms, two walks per run, were most of the
engine's cost on a 35 ms pipeline), so the controller that found them is kept
and found again only when a module has been imported since. The limit is set and
lifted from a helper thread, whatever thread the user is in: once the main thread
has lowered OpenBLAS's thread count, a call from another thread cannot raise it
again. The helper is one thread kept for the process's life, waiting for the next
run (a thread made and joined twice per run cost 5-9 ms of a 15 ms pipeline on a
loaded machine); it asks each BLAS library for its thread count and sets it
directly (microseconds), and does nothing when every library already runs one
thread (a worker process holding the limit for good). A run does not wait for the
helper where it has other work to do (:class:`BlasLimit`): it sends the lowering
when it starts and waits for it just before its first node, and sends the restore
after its last node and waits for it just before it returns (on a loaded machine
each wait for the helper thread to be scheduled took 0.3-5 ms).
"""

from __future__ import annotations

import os
import queue
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["BlasLimit", "one_blas_thread", "one_blas_thread_for_good"]


class _SharedLimit:
    """The process's one BLAS-thread limit, applied while at least one user holds it.

    :meth:`enter` and :meth:`leave` only send their work to the helper thread and return
    the :class:`_Request`; a user waits for it (:meth:`_Request.wait`) before what needs it
    (a run: before its first node, and before it returns), so the thread switches overlap
    the run's own work instead of adding to it.
    """

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.users = 0
        self.lowering: _Request | None = None  # its value: what the last lowering changed
        self.last: _Request | None = None  # the last request sent to the helper
        self.held_for_good = False
        self.controller: Any = None
        self.modules_seen = 0

    def _libraries(self) -> list[Any]:
        """threadpoolctl's controllers of the loaded BLAS libraries, found again after an
        import."""
        from threadpoolctl import ThreadpoolController  # type: ignore[import-untyped]  # no types

        if self.controller is None or len(sys.modules) != self.modules_seen:
            self.modules_seen = len(sys.modules)
            self.controller = ThreadpoolController().select(user_api="blas").lib_controllers
        return list(self.controller)

    def enter(self) -> _Request | None:
        """Count a user; the first sends the lowering. The request to wait for before BLAS
        runs on one thread (None: it does already)."""
        with self.lock:
            if self.users == 0:
                libraries = self._libraries()
                settled = self.last is None or self.last.finished
                if settled and all((lib.get_num_threads() or 1) <= 1 for lib in libraries):
                    self.lowering = None  # nothing to lower, nothing to restore
                else:  # (a restore still on its way is undone in order, in the helper)
                    self.lowering = self.last = _HELPER.send(lambda: _lower(libraries))
            self.users += 1
            return self.lowering

    def leave(self) -> _Request | None:
        """Count a user out; the last sends the restore. The request to wait for before
        BLAS has its threads back (None: nothing to restore)."""
        with self.lock:
            self.users -= 1
            if self.users or self.lowering is None:
                return None
            lowering, self.lowering = self.lowering, None
            self.last = _HELPER.send(lambda: _restore(lowering.value))
            return self.last


def _lower(libraries: list[Any]) -> list[tuple[Any, int]]:
    """Each BLAS library with more than one thread, set to one; what each had."""
    lowered = []
    for library in libraries:
        had = library.get_num_threads()
        if had is not None and had > 1:
            library.set_num_threads(1)
            lowered.append((library, had))
    return lowered


def _restore(lowered: list[tuple[Any, int]] | None) -> None:
    for library, had in lowered or ():  # (None: the lowering failed, and said so)
        library.set_num_threads(had)


class _Request:
    """One call sent to the helper thread: its value once :attr:`finished`."""

    __slots__ = ("call", "done", "error", "finished", "value")

    def __init__(self, call: Callable[[], Any]) -> None:
        self.call = call
        self.value: Any = None
        self.error: BaseException | None = None
        self.finished = False
        self.done = threading.Event()

    def run(self) -> None:
        try:
            self.value = self.call()
        except BaseException as error:  # re-raised in the thread that waits for it
            self.error = error
        self.finished = True
        self.done.set()

    def wait(self) -> Any:
        """Its value (its error raised here), once the helper has run it."""
        if not self.finished:
            self.done.wait()
        if self.error is not None:
            raise self.error
        return self.value


class _Helper:
    """The one thread that sets and lifts the limit (see the module docstring); made on
    first use, and again in a forked child (which has only the thread that forked)."""

    def __init__(self) -> None:
        self.requests: queue.SimpleQueue[_Request] = queue.SimpleQueue()
        self.thread: threading.Thread | None = None

    def send(self, call: Callable[[], Any]) -> _Request:
        """Queue ``call`` for the helper thread (run in the order sent); do not wait."""
        if self.thread is None:
            self.thread = threading.Thread(
                target=_serve, args=(self.requests,), name="graphvision-blas-limit", daemon=True
            )
            self.thread.start()
        request = _Request(call)
        self.requests.put(request)
        return request

    def forget(self) -> None:
        self.__init__()  # type: ignore[misc]  # in a forked child: the thread is not there


def _serve(requests: queue.SimpleQueue) -> None:
    while True:
        requests.get().run()


_HELPER = _Helper()
os.register_at_fork(after_in_child=_HELPER.forget)


_LIMIT = _SharedLimit()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """A context in which BLAS runs on one thread; nested and concurrent uses share it."""
    _wait(_LIMIT.enter())
    try:
        yield
    finally:
        _wait(_LIMIT.leave())


def _wait(request: _Request | None) -> None:
    if request is not None:
        request.wait()


class BlasLimit:
    """:func:`one_blas_thread` in steps, for a run to overlap the helper thread's switches with
    its own work: :meth:`request` early, :meth:`hold` before the first node (BLAS then
    runs on one thread), :meth:`release` after the last, :meth:`restored` before returning
    (BLAS then has its threads back). Nothing is sent until :meth:`request`."""

    def __init__(self) -> None:
        self.entered = False
        self.lowering: _Request | None = None
        self.restoring: _Request | None = None

    def request(self) -> None:
        if not self.entered:
            self.entered = True
            self.lowering = _LIMIT.enter()

    def hold(self) -> None:
        self.request()
        _wait(self.lowering)

    def release(self) -> None:
        if self.entered:
            self.entered = False
            self.restoring = _LIMIT.leave()

    def restored(self) -> None:
        self.release()
        restoring, self.restoring = self.restoring, None
        _wait(restoring)


def one_blas_thread_for_good() -> None:
    """Hold BLAS at one thread for the rest of this process (a worker that only runs nodes);
    the calls after the first only read a flag."""
    with _LIMIT.lock:
        if _LIMIT.held_for_good:
            return
        _LIMIT.held_for_good = True
    _wait(_LIMIT.enter())
