"""Writing one batch file's folder from its result, wherever the file ran (this process,
or a worker: a file task writes its own folder); a failure there fails that file alone."""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from pathlib import Path

from graphvision.errors import GraphvisionError
from graphvision.execution.batch_files import BatchItem
from graphvision.execution.folders import RunPage, retire_run, write_run
from graphvision.execution.record import RunResult

__all__ = ["failure_reason", "finish_item", "settle_folders"]


def failure_reason(error: BaseException) -> str:
    """What ``batch.csv`` says of a file that failed: the error's message, its first line; the
    exception's type too when it is not one of graphvision's (a library's ValueError)."""
    text = (str(error).strip().splitlines() or [""])[0]
    if isinstance(error, GraphvisionError):
        return text
    if isinstance(error, OSError) and error.strerror:
        where = f": {error.filename}" if error.filename else ""
        return f"{error.strerror}{where}"
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def finish_item(
    item: BatchItem,
    folder: Path,
    result: RunResult | None,
    pages: Sequence[RunPage],
    inside: Path,
) -> BatchItem:
    """Write the item's ``folder`` from its result (or clear it when there is none);
    ``inside`` is the batch's folder, the only place it writes (no link below it is
    followed)."""
    if result is None:  # nothing produced: what a previous run left there must not look current
        retire_run(folder, inside)
        return item
    try:
        write_run(result, folder, pages, inside=inside)
    except Exception as error:  # a port type's writer, a report page, the disk: this file fails
        item.status, item.error = "failed", f"writing {folder}: {failure_reason(error)}"
        with contextlib.suppress(Exception):  # what an earlier run left must not look current
            retire_run(folder, inside)
        return item  # no values: batch.csv shows only what the folder holds
    item.scalars = {
        key: value
        for key, value in result.outputs.items()
        if isinstance(value, int | float | str | bool)
    }
    return item


def settle_folders(items: Sequence[BatchItem]) -> None:
    """Set ``output_dir`` to None for each item whose folder is not there once the batch is
    done (a file that could not be read, failed with no earlier run kept, or did not run):
    the items then say what ``batch.csv`` says (an empty ``output_dir``)."""
    for item in items:
        if item.output_dir is not None and not item.output_dir.is_dir():
            item.output_dir = None
