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
thread (a worker process holding the limit for good).
"""

from __future__ import annotations

import os
import queue
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["one_blas_thread", "one_blas_thread_for_good"]


class _SharedLimit:
    """The process's one BLAS-thread limit, applied while at least one user holds it."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.users = 0
        self.limiter: Any = None
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

    def enter(self) -> None:
        with self.lock:
            if self.users == 0:
                busy = [lib for lib in self._libraries() if (lib.get_num_threads() or 1) > 1]
                self.limiter = _in_the_helper_thread(lambda: _lower(busy)) if busy else []
            self.users += 1

    def leave(self) -> None:
        with self.lock:
            self.users -= 1
            if self.users == 0:
                lowered, self.limiter = self.limiter, None
                if lowered:
                    _in_the_helper_thread(lambda: _restore(lowered))


def _lower(libraries: list[Any]) -> list[tuple[Any, int]]:
    """Each BLAS library with more than one thread, set to one; what each had."""
    lowered = []
    for library in libraries:
        had = library.get_num_threads()
        if had is not None and had > 1:
            library.set_num_threads(1)
            lowered.append((library, had))
    return lowered


def _restore(lowered: list[tuple[Any, int]]) -> None:
    for library, had in lowered:
        library.set_num_threads(had)


class _Helper:
    """The one thread that sets and lifts the limit (see the module docstring); made on
    first use, and again in a forked child (which has only the thread that forked)."""

    def __init__(self) -> None:
        self.requests: queue.SimpleQueue[tuple[Callable[[], Any], queue.SimpleQueue]] = (
            queue.SimpleQueue()
        )
        self.thread: threading.Thread | None = None

    def call(self, call: Callable[[], Any]) -> Any:
        if self.thread is None:
            self.thread = threading.Thread(
                target=_serve, args=(self.requests,), name="graphvision-blas-limit", daemon=True
            )
            self.thread.start()
        reply: queue.SimpleQueue[tuple[bool, Any]] = queue.SimpleQueue()
        self.requests.put((call, reply))
        succeeded, value = reply.get()
        if not succeeded:
            raise value
        return value

    def forget(self) -> None:
        self.__init__()  # type: ignore[misc]  # in a forked child: the thread is not there


def _serve(requests: queue.SimpleQueue) -> None:
    while True:
        call, reply = requests.get()
        try:
            reply.put((True, call()))
        except BaseException as error:  # re-raised in the caller's thread
            reply.put((False, error))


_HELPER = _Helper()
os.register_at_fork(after_in_child=_HELPER.forget)


def _in_the_helper_thread(call: Callable[[], Any]) -> Any:
    """``call()`` in the helper thread (see the module docstring), its result or error."""
    return _HELPER.call(call)


_LIMIT = _SharedLimit()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """A context in which BLAS runs on one thread; nested and concurrent uses share it."""
    _LIMIT.enter()
    try:
        yield
    finally:
        _LIMIT.leave()


def one_blas_thread_for_good() -> None:
    """Hold BLAS at one thread for the rest of this process (a worker that only runs nodes);
    the calls after the first only read a flag."""
    with _LIMIT.lock:
        if _LIMIT.held_for_good:
            return
        _LIMIT.held_for_good = True
    _LIMIT.enter()
