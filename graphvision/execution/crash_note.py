"""Which nodes were running when a node killed the process (issue 29 F).

On ``sync`` and ``threads`` a node runs in the run's own process, so a node that
segfaults (a broken C extension) or calls ``os._exit`` ends the whole command. Two
things then name it on stderr:

* every node function is called through a frame named after the node
  (``node 'boom' (crash.segfault)``): Python's fault handler, which the command line
  enables (``python -X faulthandler`` or :func:`faulthandler.enable` in a script or
  notebook), prints each thread's frames on a segfault, an abort, a bus error or an
  illegal instruction, so the running nodes appear by name in its traceback;
* ``os._exit`` called by a running node first writes one line naming them (the process
  that calls it ends at once, with no traceback and no ``atexit``).

A C library that calls ``exit()`` itself is not seen. The ``processes`` executor
isolates such nodes: their worker dies, the node fails alone and the run goes on.
"""

from __future__ import annotations

import os
import threading
import types
from collections.abc import Callable
from typing import Any, NoReturn

__all__ = ["call_named", "real_exit", "running_nodes"]

_RUNNING: dict[int, str] = {}
"""Thread ident -> the node it runs (``node 'name' (op)``)."""
_TRAMPOLINES: dict[str, Callable[[Callable, dict[str, Any]], Any]] = {}
_MOST_TRAMPOLINES = 16384  # a 10,000-node chain keeps its frames named without a rebuild
real_exit = os._exit
"""``os._exit`` itself, for the engine's own exits (no note)."""
_INSTALLED_IN: list[int] = []  # the process whose os._exit notes the running nodes


def _call(func: Callable, kwargs: dict[str, Any]) -> Any:
    return func(**kwargs)


def _trampoline(label: str) -> Callable[[Callable, dict[str, Any]], Any]:
    """:func:`_call` under the name ``label``: what a traceback shows for the frame."""
    found = _TRAMPOLINES.get(label)
    if found is None:
        code = _call.__code__.replace(co_name=label, co_qualname=label)
        found = types.FunctionType(code, _call.__globals__, label)
        if len(_TRAMPOLINES) < _MOST_TRAMPOLINES:
            _TRAMPOLINES[label] = found
    return found


def running_nodes() -> list[str]:
    """The nodes running in this process now, each as ``node 'name' (op)``."""
    return list(_RUNNING.values())


def _exit_noting(status: int) -> NoReturn:
    """The note, when a node's own thread calls ``os._exit`` (the command line's exit after
    Ctrl-C, from the main thread while nodes run on threads, is the engine's, not theirs)."""
    if threading.get_ident() in _RUNNING and [os.getpid()] == _INSTALLED_IN:
        listed = "; ".join(sorted(_RUNNING.values()))
        os.write(2, f"graphvision: os._exit({status}) while running {listed}\n".encode())
    real_exit(status)


def call_named(label: str, func: Callable, kwargs: dict[str, Any]) -> Any:
    """``func(**kwargs)`` in a frame named ``label``, noted as running meanwhile."""
    if not _INSTALLED_IN:
        _INSTALLED_IN.append(os.getpid())
        os._exit = _exit_noting
    ident = threading.get_ident()
    _RUNNING[ident] = label
    try:
        return _trampoline(label)(func, kwargs)
    finally:
        _RUNNING.pop(ident, None)
