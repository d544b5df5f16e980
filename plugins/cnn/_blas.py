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

The limit is set and lifted from a helper thread of its own, whatever thread the node
runs in: once the main thread has lowered OpenBLAS's thread count, a call from another
thread cannot raise it again, so a node in the main thread (the engine runs some there)
that entered first, beside one on a worker that left last, left the process on one
BLAS thread for good (and a later decomposition in the main thread gave results a few
1e-15 away from the same one in a worker process).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
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
                self.limiter = _in_a_helper_thread(
                    lambda: threadpool_limits(limits=1, user_api="blas")
                )
            self.users += 1

    def leave(self) -> None:
        with self.lock:
            self.users -= 1
            if self.users == 0:
                _in_a_helper_thread(self.limiter.restore_original_limits)
                self.limiter = None


def _in_a_helper_thread(call: Callable[[], Any]) -> Any:
    """``call()`` in a thread of its own (see the module docstring), its result or error."""
    outcome: list[Any] = []

    def run() -> None:
        try:
            outcome.append((True, call()))
        except BaseException as error:  # re-raised in the caller's thread
            outcome.append((False, error))

    helper = threading.Thread(target=run, name="graphvision-blas-limit")
    helper.start()
    helper.join()
    succeeded, value = outcome[0]
    if not succeeded:
        raise value
    return value


_LIMIT = _SharedLimit()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """A context in which BLAS runs on one thread; nested and concurrent uses share it."""
    _LIMIT.enter()
    try:
        yield
    finally:
        _LIMIT.leave()
