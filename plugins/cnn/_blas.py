"""One BLAS thread for the many small matrix products of mini-batch training.

OpenBLAS starts its threads for every product; on products of a few thousand rows by a
few dozen columns the hand-off costs more than the product, and on a loaded 2-core
machine one epoch of ``rcnn.yaml``'s backbone took 11.7 s with the default threads
against 2.5 s with one (``fit_network`` on 9,210 crops of 16×16, the same run).

threadpoolctl's limit is process-wide, so two nodes running at once in threads must not
each save and restore it: the second would save the first's limit and restore it last,
leaving the process on one thread for good. :func:`one_blas_thread` counts its users
under a lock; the first applies the limit, the last restores the original. Meanwhile
nodes running in other threads get one BLAS thread too, which changes their speed,
never their results.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["one_blas_thread"]


class _SharedLimit:
    """The process's one BLAS-thread limit, applied while at least one user holds it."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.users = 0
        self.limiter: Any = None

    def enter(self) -> None:
        from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]  # no types

        with self.lock:
            if self.users == 0:
                self.limiter = threadpool_limits(limits=1, user_api="blas")
            self.users += 1

    def leave(self) -> None:
        with self.lock:
            self.users -= 1
            if self.users == 0:
                self.limiter.restore_original_limits()
                self.limiter = None


_LIMIT = _SharedLimit()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """A context in which BLAS runs on one thread; nested and concurrent uses share it."""
    _LIMIT.enter()
    try:
        yield
    finally:
        _LIMIT.leave()
