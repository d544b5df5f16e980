"""What a node raised that is not an ``Exception``: the node's failure, unless it is the
user's stop (:func:`node_failure`).

A node's code can raise a ``BaseException`` by mistake or through a library: ``SystemExit``
(``sys.exit`` in code written as a script), ``GeneratorExit``, a class of its own
(``class Stop(BaseException)``), ``KeyboardInterrupt`` (``raise KeyboardInterrupt``, a
library that raises it). Such an exception escaped the engine on ``sync`` and ``threads``
(a traceback), killed a Dask worker or hung the run, and ``KeyboardInterrupt`` stopped the
command as Ctrl-C does (exit 130, "interrupted"). Each is now that node's failure, named
by its type and message, the same on every executor: it becomes its copy
(:class:`~graphvision.errors.CopiedError`, the original as its cause), an ``Exception``
that every executor reports as a node's error.

The user's stop stays a stop: a ``KeyboardInterrupt`` (or the command line's
``Terminated``, one too) that a signal raised. A signal's exception is raised in the main
thread only, never in a process that ignores Ctrl-C (a worker), and never by a ``raise``
statement: the interpreter runs a signal's handler between two instructions, at a call or
a jump, so the innermost line of its traceback is not a ``raise`` (unless the handler is
Python code: then its own frame is innermost, and it is the handler installed for one of
the stopping signals). What a C library raises as ``KeyboardInterrupt`` (at a call, as a
signal's) cannot be told from Ctrl-C: it stops the run, as before.
"""

from __future__ import annotations

import dis
import signal
import threading
from types import TracebackType

from graphvision.errors import CopiedError, chained
from graphvision.execution.sendable import copy_of

__all__ = ["node_failure", "signalled", "stop_within"]

_RAISE = dis.opmap["RAISE_VARARGS"]
_STOPPING = [
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
]


def node_failure(error: BaseException) -> CopiedError | None:
    """The copy to raise for ``error``, a ``BaseException`` but not an ``Exception`` that a
    node raised, as that node's failure; None when it is the user's stop (:func:`signalled`)."""
    if isinstance(error, KeyboardInterrupt) and signalled(error):
        return None
    return copy_of(error)


def stop_within(error: BaseException) -> KeyboardInterrupt | None:
    """The user's stop that ``error`` carries: a ``KeyboardInterrupt`` a signal raised
    (:func:`signalled`), ``error`` itself or one in its chain of causes and contexts (a
    node that caught Ctrl-C and raised ``SystemExit`` or an error of its own in its place,
    ``from None`` too: the run stops, as it does when the node runs on another thread);
    else None."""
    return chained(error, KeyboardInterrupt, signalled)


def signalled(error: KeyboardInterrupt) -> bool:
    """Whether ``error`` may have come from a signal (Ctrl-C, the command line's SIGTERM):
    raised in the main thread of a process that does not ignore Ctrl-C, by a stopping
    signal's handler or at an instruction that is not a ``raise`` (see the module)."""
    if isinstance(error.__context__, KeyboardInterrupt) and signalled(error.__context__):
        return True  # a Ctrl-C the node's code caught and raised again as its own
    if threading.current_thread() is not threading.main_thread():
        return False
    innermost = _innermost(error.__traceback__)
    if innermost is None:
        return True
    handlers = [getattr(signal.getsignal(number), "__code__", None) for number in _STOPPING]
    if innermost.tb_frame.f_code in handlers:  # (SIGTERM's, in a process ignoring Ctrl-C too)
        return True
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:  # a worker: Ctrl-C is the client's
        return False
    code = innermost.tb_frame.f_code.co_code
    return not (0 <= innermost.tb_lasti < len(code) and code[innermost.tb_lasti] == _RAISE)


def _innermost(trace: TracebackType | None) -> TracebackType | None:
    while trace is not None and trace.tb_next is not None:
        trace = trace.tb_next
    return trace
