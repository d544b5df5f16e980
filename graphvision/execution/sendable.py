"""An exception raised in a worker process, made fit to travel back to the client.

A worker sends what a node raised to the client pickled. An exception that does not
pickle (a lock or a lambda among its arguments) lost the node's own error: the client
saw ``TypeError: cannot pickle '_thread.lock' object``. One that pickles in the worker
and does not unpickle in the client (an ``__init__`` that takes other arguments than it
gives its base, a ``__setstate__`` that raises, a class whose module only the workers
import) broke the pool's result queue: the client saw that the worker had died, and ran
the node again; on Dask it arrived as its pickle's bytes.

So an exception travels as its pickle (when it pickles) beside its copy, an
:class:`~graphvision.errors.CopiedError` of its type's name and message with the plugin
line it came from (:func:`~graphvision.nodes.loading.note_plugin_line`): the client
unpickles it there (:func:`arrived`), and takes the copy when it cannot. A task's pickle
does not fail with it, whatever the exception: the pool and Dask stay whole, and the node
runs once. The one thing sent for what a task raises on the ``processes`` pool and on Dask
(:func:`sent_back`: a node's error, a batch file's) and for each file of a task of several
(:func:`~graphvision.execution.file_group.run_files`).
"""

from __future__ import annotations

import pickle
from collections.abc import Callable
from typing import Any

from graphvision.errors import CopiedError, error_text

__all__ = ["arrived", "copy_of", "sendable", "sent_back"]


class _SentError(CopiedError):
    """A copy with its original's pickle (None: it does not pickle), which unpickles as
    the original where it can, else as a plain copy (:func:`arrived`)."""

    def __init__(self, type_name: str, message: str, pickled: bytes | None) -> None:
        super().__init__(type_name, message)
        self.pickled = pickled

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        line = getattr(self, "__graphvision_line__", "")
        return (arrived, (self.pickled, self.type_name, self.message, line))

    def __str__(self) -> str:
        """The message as the worker's side shows it: cut to its first 2,000 characters.
        Dask replaces an exception whose text is longer than 10,000 with ``Exception(
        "Long error message", …)`` (its type, its pickle and its line lost); the whole
        message travels in the pickle."""
        cut = self.message[:_SHOWN_IN_WORKER]
        more = len(self.message) - len(cut)
        return cut + (f"... ({more} more characters sent)" if more else "")


_SHOWN_IN_WORKER = 2000


def sent_back(fn: Callable[..., Any], /, *args: Any) -> Any:
    """``fn(*args)``, a task in a worker process (the ``processes`` pool's, Dask's): what it
    raises is raised :func:`sendable`."""
    try:
        return fn(*args)
    except Exception as error:
        failed = sendable(error)
    raise failed  # here: not with the original as its context, which Dask pickles too


def copy_of(error: BaseException) -> CopiedError:
    """``error``'s copy: its type's name, its message and its plugin line."""
    return _copy(error, None, sent=False)


def sendable(error: BaseException) -> CopiedError:
    """``error`` made to travel to the client: its copy, with its pickle when it pickles.
    Raise it outside the ``except`` that caught ``error``: Dask pickles the context too."""
    try:
        pickled: bytes | None = pickle.dumps(error)
    except Exception:  # (a user's exception class: anything can happen)
        pickled = None
    return _copy(error, pickled, sent=True)


def _copy(error: BaseException, pickled: bytes | None, *, sent: bool) -> CopiedError:
    name, _, message = error_text(error).partition(": ")
    copy = _SentError(name, message, pickled) if sent else CopiedError(name, message)
    line = getattr(error, "__graphvision_line__", "")
    if line:
        copy.__graphvision_line__ = line  # type: ignore[attr-defined]
    return copy


def arrived(pickled: bytes | None, type_name: str, message: str, line: str) -> BaseException:
    """In the client: the exception a worker sent (:func:`sendable`), or its copy when it
    does not unpickle here, each with its plugin ``line``."""
    error: BaseException | None = None
    if pickled is not None:
        try:
            error = pickle.loads(pickled)
        except KeyboardInterrupt:
            raise
        except BaseException:  # (a __setstate__ or __reduce__ of a user's: anything at all)
            error = None
    if not isinstance(error, BaseException):
        error = CopiedError(type_name, message)
    try:
        if line and not getattr(error, "__graphvision_line__", ""):
            error.__graphvision_line__ = line  # type: ignore[attr-defined]
    except Exception:  # a class whose attributes raise: the copy says it
        error = CopiedError(type_name, message)
        error.__graphvision_line__ = line  # type: ignore[attr-defined]
    return error
