"""What the Dask executor's tasks run on a worker (:mod:`graphvision.execution.dask`): a node
with the worker's set-up (one BLAS thread, glibc's allocator keeping freed memory), a shared
value's task and its copies (:mod:`graphvision.execution.dask_shared`), and several files of
a batch as one task (:mod:`graphvision.execution.dask_files`)."""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable
from typing import Any

from graphvision.errors import GraphvisionError
from graphvision.execution.blas import one_blas_thread, one_blas_thread_for_good
from graphvision.execution.sendable import sent_back
from graphvision.nodes.spec import FunctionRef

__all__ = ["hold", "keep_freed_memory", "on_worker", "shared"]


def keep_freed_memory() -> None:
    """In a worker started with ``MALLOC_TRIM_THRESHOLD_`` (Dask's nanny sets 64 KiB, to give
    freed memory back to the system): glibc's allocator keeps up to 64 MiB of freed memory
    and serves arrays up to 32 MiB from it, once per process.

    That variable also pins glibc's mmap threshold at 128 KiB, so every array over 128 KiB
    a node makes is a fresh mapping, its pages faulted in and zeroed again: the coins
    pipeline's ``regions.describe`` (then a dozen 1 MB temporaries) took twice the CPU time,
    and a batch's file on a Dask worker about twice that of a ``processes`` worker. Memory
    over 64 MiB freed at the heap's top is still given back.
    """
    if "MALLOC_TRIM_THRESHOLD_" in os.environ:
        from graphvision.execution import heap

        heap.keep_freed_memory()  # the thresholds a run sets where its nodes run


def shared(value: Any) -> Any:
    """The value a task was given (see :meth:`DaskExecutor.share`)."""
    return value


def hold(value: Any) -> None:
    """Nothing: run on a worker so that it holds a copy of ``value``, a shared value's task
    (:mod:`graphvision.execution.dask_shared`)."""


def on_worker(fn: Callable[..., Any], *args: Any) -> Any:
    """``fn(*args)`` on a worker; a node the worker cannot import is named with the worker;
    what it raises reaches the client whole, or as its copy
    (:func:`~graphvision.execution.sendable.sent_back`: Dask sent the bytes of one that does
    not unpickle there)."""
    ref = args[0] if args and isinstance(args[0], FunctionRef) else None
    if ref is not None:
        try:
            ref.resolve()
        except Exception as error:
            from distributed import get_worker

            where = ref.path or ref.module
            raise GraphvisionError(
                f"worker {get_worker().address} cannot import {where} ({error}): install the "
                "plugin in every worker's environment, or put local plugin files on storage "
                "the workers share"
            ) from None
    if multiprocessing.parent_process() is not None:  # a worker process: nodes only
        one_blas_thread_for_good()  # set by the first task, a flag read after
        keep_freed_memory()
        return sent_back(fn, *args)
    with one_blas_thread():  # a worker thread in the client's process (processes=False)
        return sent_back(fn, *args)
