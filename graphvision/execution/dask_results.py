"""A Dask task's result fetched on the client's event loop (:func:`fetch_on_loop`).

A ``distributed.Future``'s done-callback runs in a thread of Dask's (the loop hands it the
task, waking that thread), and a blocking ``gather`` there hands the fetch back to the loop
and waits for it: two thread hops a task, each waiting for the GIL while the loop held it.
Awaited on the loop instead, the result is fetched as soon as the task is done and handed
on there, no thread woken but the one that waits for it.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from graphvision.execution.worker_died import died_on_dask

__all__ = ["Landed", "fetch_on_loop", "settle", "settle_found"]

Landed = Callable[[Any, "BaseException | None"], None]
"""Called with a task's result and None, or None and the task's error."""


def fetch_on_loop(
    client: Any, task: Any, direct: bool | None, landed: Landed, running: str = "node"
) -> None:
    """``landed(result, None)``, or ``landed(None, error)`` (a lost worker's as
    :func:`~graphvision.execution.worker_died.died_on_dask` words it, ``running`` saying what
    the task ran), called on ``client``'s event loop once ``task`` is done; ``direct``: fetch
    from the worker straight (:func:`~graphvision.execution.dask_fork.direct_gathers`).
    ``landed`` runs on the loop: it must not wait for the scheduler."""

    async def fetch() -> None:
        try:
            value = await client.gather(task, direct=direct, asynchronous=True)
        except BaseException as error:
            landed(None, died_on_dask(error, running))
        else:
            landed(value, None)

    client.loop.add_callback(fetch)


def settle(future: Future, value: Any, error: BaseException | None) -> None:
    """``future`` takes ``value``, or ``error`` when there is one."""
    if error is not None:
        future.set_exception(error)
    else:
        future.set_result(value)


def settle_found(future: Future, found: Any) -> None:
    """``future`` takes ``found``: a result, or the exception it is (a file's outcome or what
    the file raised)."""
    if isinstance(found, BaseException):
        settle(future, None, found)
    else:
        settle(future, found, None)
