"""An exception raised in a worker process, made fit to travel back to the client.

A worker sends what a node raised to the client pickled; an exception that does not
pickle (a lock or a lambda among its arguments) or does not unpickle (an ``__init__``
that takes other arguments than it gives its base) lost the node's own error: the
client saw ``TypeError: cannot pickle '_thread.lock' object``, or, for one that broke
the pool's result queue, that the worker had died, and ran the node again. Such an
exception travels as an :class:`~graphvision.errors.CopiedError` of its type's name and
message, with the plugin line it came from
(:func:`~graphvision.nodes.loading.note_plugin_line`).
"""

from __future__ import annotations

import pickle

from graphvision.errors import CopiedError, error_text

__all__ = ["pickles", "sendable"]


def pickles(error: BaseException) -> bool:
    """Whether ``error`` pickles and unpickles (it can travel between processes as itself)."""
    try:
        pickle.loads(pickle.dumps(error))
    except Exception:
        return False
    return True


def sendable(error: Exception) -> Exception:
    """``error`` itself when it can travel between processes, else its copy."""
    if pickles(error):
        return error
    name, _, message = error_text(error).partition(": ")
    copy = CopiedError(name, message)
    line = getattr(error, "__graphvision_line__", "")
    if line:
        copy.__graphvision_line__ = line  # type: ignore[attr-defined]
    return copy
