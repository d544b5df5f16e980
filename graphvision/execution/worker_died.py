"""The error of a task whose worker process died, and how it is worded."""

from __future__ import annotations

from graphvision.execution.batch_guard import guard_hint

__all__ = ["WorkerDiedError", "died"]

_DIED = "the worker process running this node died (killed, or out of memory)"


class WorkerDiedError(RuntimeError):
    """The worker process running a node died (killed, out of memory), also on the retry."""


def died(how: str) -> WorkerDiedError:
    """:class:`WorkerDiedError` saying ``how``, naming the main guard when the script lacks
    it: the retry's worker comes from the fork server and imports the script first."""
    return WorkerDiedError(f"{_DIED}, {how}{guard_hint()}")
