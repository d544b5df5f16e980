"""Imported last by the worker fork server (:mod:`graphvision.execution.worker_start`),
once per client process: what each worker's first task would otherwise do.

numba's CPU target installs its implementations on its first compile or cache
load (over 3 s on a loaded machine, then 30 ms for a cached kernel); done here,
every worker forked from the server has it done. numba is one of graphvision's
dependencies, but plugins import their kernels when a node first runs, so it
is imported here. Nothing here may fail the server: a worker that lacks it
does the same work on its first task.

A worker that cannot start because the client has gone prints nothing
(:func:`_quiet_start_failure`).
"""

from __future__ import annotations

import contextlib
import importlib.util
import sys
from typing import Any


def _numba_target() -> None:
    if importlib.util.find_spec("numba") is None:  # pragma: no cover - a dependency
        return
    from numba.core.registry import cpu_target

    cpu_target.target_context.refresh()


def _quiet_start_failure(kind: type[BaseException], error: BaseException, trace: Any) -> None:
    """The server's (and so each worker's) ``sys.excepthook``: a worker that cannot start
    because the client is gone (its semaphores and pipes went with it: a batch stopped by
    Ctrl-C while the server was still importing) ends without a traceback; the client
    reports its own end in one line. Anything else is printed as before."""
    if issubclass(kind, (OSError, EOFError)):
        return
    sys.__excepthook__(kind, error, trace)


with contextlib.suppress(Exception):  # see the module docstring
    _numba_target()
sys.excepthook = _quiet_start_failure
