"""The error of a task whose worker process died, and how it is worded: by how the worker
ended, where that is known (the signal that ended it, or the status it exited with)."""

from __future__ import annotations

import signal

from graphvision.execution.batch_guard import guard_hint

__all__ = ["WorkerDiedError", "died", "died_on_dask", "how_it_ended"]

_UNKNOWN = "killed, or out of memory"
_SIGNALS = {
    signal.SIGKILL: "killed by SIGKILL, as `kill -9` and the out-of-memory killer end a process",
    signal.SIGSEGV: "crashed in native code: SIGSEGV, a segmentation fault",
    signal.SIGBUS: "crashed in native code: SIGBUS, a bus error",
    signal.SIGILL: "crashed in native code: SIGILL, an illegal instruction",
    signal.SIGFPE: "crashed in native code: SIGFPE, an arithmetic error",
    signal.SIGABRT: "aborted by native code: SIGABRT",
    signal.SIGTERM: "terminated by SIGTERM",
}


class WorkerDiedError(RuntimeError):
    """The worker process running a node died (killed, out of memory), also on the retry."""


def how_it_ended(exitcode: int | None) -> str:
    """How a worker process ended, from its exit code (``multiprocessing``'s: the negated
    signal number when a signal ended it); ``killed, or out of memory`` when not known."""
    if exitcode is None or exitcode == 0:
        return _UNKNOWN
    if exitcode > 0:
        return f"it exited with status {exitcode}: something in the node ended the process"
    try:
        ended = signal.Signals(-exitcode)
    except ValueError:
        return f"ended by signal {-exitcode}"
    return _SIGNALS.get(ended, f"ended by {ended.name}")


def died(
    how: str, exitcode: int | None = None, running: str = "node", forked: bool = False
) -> WorkerDiedError:
    """:class:`WorkerDiedError` saying ``how`` and how the worker ended (:func:`how_it_ended`),
    naming the main guard when the script lacks it: the retry's worker comes from the fork
    server and imports the script first (not one ``forked`` from the client). ``running``:
    what the worker ran (``node``, or a batch's ``file``)."""
    ended = how_it_ended(exitcode)
    hint = "" if forked else guard_hint()
    return WorkerDiedError(f"the worker process running this {running} died ({ended}), {how}{hint}")


def died_on_dask(error: BaseException, running: str = "node") -> BaseException:
    """``error`` as a node's failure says it: Dask's ``KilledWorker`` (the workers that ran a
    task all died while running it, ``allowed-failures + 1`` of them) becomes a
    :class:`WorkerDiedError` in the words of the ``processes`` executor's; any other error
    is returned as it is. ``running``: what the task ran (``node``, or a batch's ``file``).

    Dask does not tell the client how its workers ended; each of graphvision's workers
    prints it, and the node it ran, on its standard error
    (:mod:`graphvision.execution.crash_note`) before it ends.
    """
    kind = type(error)
    if kind.__name__ != "KilledWorker" or not kind.__module__.startswith("distributed"):
        return error
    runs = getattr(error, "allowed_failures", 0) + 1
    last = getattr(getattr(error, "last_worker", None), "address", "unknown")
    return WorkerDiedError(
        f"the Dask worker running this {running} died each of the {runs} times it was run "
        f"(killed, crashed in native code, or out of memory; Dask gives up on a task after "
        f"`distributed.scheduler.allowed-failures` deaths): each worker's standard error, or "
        f"its log, says how it ended and in which node; the last ran at {last}"
    )
