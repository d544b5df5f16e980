"""What the Dask executor's tasks run on a worker (:mod:`graphvision.execution.dask`): a node
with the worker's set-up (one BLAS thread, glibc's allocator keeping freed memory), a shared
value's task and its copies (:mod:`graphvision.execution.dask_shared`), and several files of
a batch as one task (:mod:`graphvision.execution.dask_files`)."""

from __future__ import annotations

import multiprocessing
import os
import pickle
import time
from collections.abc import Callable
from typing import Any

from graphvision.errors import GraphvisionError
from graphvision.execution.blas import one_blas_thread, one_blas_thread_for_good
from graphvision.nodes.spec import FunctionRef

__all__ = ["FileTaskError", "hold", "keep_freed_memory", "on_worker", "run_files", "shared"]


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
    """``fn(*args)`` on a worker; a node the worker cannot import is named with the worker."""
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
        return fn(*args)
    with one_blas_thread():  # a worker thread in the client's process (processes=False)
        return fn(*args)


class FileTaskError(Exception):
    """What a file of a task of several files raised, as its type's name and message (when the
    exception itself does not pickle: it would have failed the task's other files)."""


def run_files(
    task: Callable[[Any, str, str], Any], job: Any, files: list[tuple[str, str]]
) -> tuple[list[Any], float]:
    """Several files of a batch in one task, each run by ``task(job, path, folder)``
    (:func:`~graphvision.execution.file_task.run_file_task`): each one's outcome, or what it
    raised (that file fails alone, named, and the others run); and the CPU seconds they took
    in this thread (what sizes the next tasks: :mod:`graphvision.execution.dask_files`)."""
    found: list[Any] = []
    began = time.thread_time()
    for path, folder in files:
        try:
            found.append(task(job, path, folder))
        except Exception as error:  # this file fails alone, with its reason
            found.append(
                error if _pickles(error) else FileTaskError(f"{type(error).__name__}: {error}")
            )
    return found, time.thread_time() - began


def _pickles(error: Exception) -> bool:
    """Whether ``error`` goes back to the client as it is (else as a :class:`FileTaskError`)."""
    try:
        pickle.loads(pickle.dumps(error))
    except Exception:
        return False
    return True
