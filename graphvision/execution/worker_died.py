"""The error of a task whose worker process died, and how it is worded: by how the worker
ended, where that is known (the signal that ended it, or the status it exited with)."""

from __future__ import annotations

import signal

from graphvision.execution.batch_guard import guard_hint

__all__ = ["WorkerDiedError", "died", "how_it_ended"]

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


def died(how: str, exitcode: int | None = None) -> WorkerDiedError:
    """:class:`WorkerDiedError` saying ``how`` and how the worker ended (:func:`how_it_ended`),
    naming the main guard when the script lacks it: the retry's worker comes from the fork
    server and imports the script first."""
    ended = how_it_ended(exitcode)
    return WorkerDiedError(
        f"the worker process running this node died ({ended}), {how}{guard_hint()}"
    )
