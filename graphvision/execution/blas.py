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
The limit is process-wide, so :func:`one_blas_thread` counts its users under a
lock: the first applies the limit, the last restores the original, and a run
inside a batch or a node inside a run only counts. Finding the loaded BLAS
libraries takes milliseconds (threadpoolctl walks every loaded shared library;
3-8 ms, two walks per run, were most of the engine's cost on a 35 ms pipeline),
so the controller that found them is kept and found again only when a module has
been imported since. Each library is asked for its thread count and set directly,
in the thread that enters or leaves, whichever it is: OpenBLAS's count (pthreads
build) is one number for the process that any thread may set. For OpenBLAS the
two C functions threadpoolctl would call (``openblas_get_num_threads`` and
``openblas_set_num_threads``, or OpenMP's for an OpenMP build, with the library's
symbol affixes) are looked up once with the controller and called directly: a
sixth of a microsecond each, where threadpoolctl's methods took half of one
(three libraries, nine calls a run: 4.4 µs, 1.5 µs since). threadpoolctl's
``set_num_threads`` of OpenBLAS does nothing, without a word, in any thread but
the first that called it (its "controlling thread"), so the count is set with
the call it makes in that thread, ``_real_set_num_threads`` (versions before it
make that call in any thread), or for OpenBLAS the C function that call makes.
Before, one helper thread made every call: two hand-offs per run (0.17 ms of a
3 ms pipeline; on a loaded machine each wait for the helper to be scheduled took
0.3-5 ms, and it fought the run's thread for the GIL), and its calls were ignored
once a user's thread had called threadpoolctl first. OpenBLAS built with CPU
affinity re-pins the thread that changes the count; the wheels of numpy, scipy
and OpenCV are built ``NO_AFFINITY``. Nothing is set when every library already
runs one thread (a worker process holding the limit for good).
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["BlasLimit", "one_blas_thread", "one_blas_thread_for_good"]


class _SharedLimit:
    """The process's one BLAS-thread limit, applied while at least one user holds it."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.users = 0
        self.lowered: list[tuple[Callable[[int], Any], int]] = []  # what the lowering changed
        self.held_for_good = False
        self.switches: list[_Switch] | None = None
        self.modules_seen = 0

    def _libraries(self) -> list[_Switch]:
        """How to read and set the thread count of each loaded BLAS library
        (:func:`_switch`), found again after an import (the list is not changed by its
        readers)."""
        if self.switches is None or len(sys.modules) != self.modules_seen:
            from threadpoolctl import ThreadpoolController  # type: ignore[import-untyped]

            self.modules_seen = len(sys.modules)
            found = ThreadpoolController().select(user_api="blas").lib_controllers
            self.switches = [_switch(library) for library in found]
        return self.switches

    def enter(self) -> None:
        """Count a user; the first sets every BLAS library running more than one thread
        to one."""
        with self.lock:
            if self.users == 0:
                self.lowered = _lower(self._libraries())
            self.users += 1

    def leave(self) -> None:
        """Count a user out; the last gives each library lowered its threads back."""
        with self.lock:
            self.users -= 1
            if self.users == 0:
                lowered, self.lowered = self.lowered, []
                for setter, had in lowered:
                    setter(had)


_Switch = tuple[Callable[[], Any], Callable[[int], Any]]


def _switch(library: Any) -> _Switch:
    """A library's thread count getter and setter: for OpenBLAS the C functions that
    threadpoolctl's ``get_num_threads`` and ``_real_set_num_threads`` call (its
    ``_get_symbol``, the same choice of OpenBLAS's or OpenMP's by threading layer), else
    those methods."""
    symbol = getattr(library, "_get_symbol", None)
    layer = getattr(library, "threading_layer", None)
    if type(library).__name__ == "OpenBLASController" and symbol is not None and layer:
        openmp = layer == "openmp"
        getter = symbol("omp_get_max_threads" if openmp else "openblas_get_num_threads")
        setter = symbol("omp_set_num_threads" if openmp else "openblas_set_num_threads")
        if getter is not None and setter is not None:
            return getter, setter
    return library.get_num_threads, getattr(
        library, "_real_set_num_threads", library.set_num_threads
    )


def _lower(libraries: list[_Switch]) -> list[tuple[Callable[[int], Any], int]]:
    """Each BLAS library with more than one thread, set to one; its setter and what it had."""
    lowered = []
    for getter, setter in libraries:
        had = getter()
        if had is not None and had > 1:
            setter(1)
            lowered.append((setter, had))
    return lowered


_LIMIT = _SharedLimit()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """A context in which BLAS runs on one thread; nested and concurrent uses share it."""
    _LIMIT.enter()
    try:
        yield
    finally:
        _LIMIT.leave()


class BlasLimit:
    """:func:`one_blas_thread` in two steps, for a run: :meth:`hold` before its first node
    (BLAS then runs on one thread), :meth:`release` after its last (BLAS then has its
    threads back; again, in the run's ``finally``, it does nothing)."""

    def __init__(self) -> None:
        self.entered = False

    def hold(self) -> None:
        if not self.entered:
            _LIMIT.enter()
            self.entered = True

    def release(self) -> None:
        if self.entered:
            self.entered = False
            _LIMIT.leave()


def one_blas_thread_for_good() -> None:
    """Hold BLAS at one thread for the rest of this process (a worker that only runs nodes);
    the calls after the first only read a flag."""
    with _LIMIT.lock:
        if _LIMIT.held_for_good:
            return
        _LIMIT.held_for_good = True
    _LIMIT.enter()
