"""One BLAS thread for the many small matrix products of mini-batch training.

OpenBLAS starts its threads for every product; on products of a few thousand rows by a
few dozen columns the hand-off costs more than the product, and on a loaded 2-core
machine one epoch of ``rcnn.yaml``'s backbone took 11.7 s with the default threads
against 2.5 s with one (``fit_network`` on 9,210 crops of 16×16, the same run). The limit
is process-wide while it lasts (threadpoolctl has no per-thread limit): nodes running
at the same time in other threads get one BLAS thread too, which changes their speed,
never their results.
"""

from __future__ import annotations

from contextlib import AbstractContextManager

__all__ = ["one_blas_thread"]


def one_blas_thread() -> AbstractContextManager[object]:
    """A context in which BLAS runs on one thread (threadpoolctl)."""
    from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]  # ships no types

    return threadpool_limits(limits=1, user_api="blas")
