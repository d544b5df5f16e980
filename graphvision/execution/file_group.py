"""Several files of a batch as one task (on Dask: :mod:`graphvision.execution.dask_files`; on
the process pool: :mod:`graphvision.execution.batch_lanes`), each with its own outcome."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from graphvision.execution.sendable import sendable

__all__ = ["FileTaskError", "run_files"]


class FileTaskError(Exception):
    """A file of a task of several files that could not run: the executor was shut down."""


def run_files(
    task: Callable[[Any, str, str], Any], job: Any, files: list[tuple[str, str]]
) -> tuple[list[Any], float]:
    """Several files of a batch in one task, each run by ``task(job, path, folder)``
    (:func:`~graphvision.execution.file_task.run_file_task`): each one's outcome, or what it
    raised (that file fails alone, named, and the others run); and the CPU seconds they took
    in this thread (what sizes the next Dask tasks: :mod:`graphvision.execution.dask_files`).
    On the process pool a batch's lanes send several files this way too
    (:mod:`graphvision.execution.batch_lanes`)."""
    found: list[Any] = []
    began = time.thread_time()
    for path, folder in files:
        try:
            found.append(task(job, path, folder))
        except Exception as error:  # this file fails alone, with its reason
            found.append(sendable(error))  # itself in the client, or its copy (not the task's)
    return found, time.thread_time() - began


run_files.settles_its_files = True  # type: ignore[attr-defined]
"""A task of several files whose worker died is not run again whole (the files it had
written whole would be written again): the batch settles each file by its claim and runs
the others one to a task (:meth:`~graphvision.execution.batch_run.BatchRun.run_files`)."""
