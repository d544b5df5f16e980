"""numba's compiler set up in this process, once: imported by the worker fork server when it
serves a batch (:mod:`graphvision.execution.worker_start`), and by each batch worker's
warm-up otherwise (on Dask).

numba's CPU target installs its implementations on its first compile or cache
load: over 3 s on a loaded machine, then 30 ms for each cached kernel. Done in
the server, every worker forked from it has it done. numba is one of
graphvision's dependencies, but plugins import their kernels when a node first
runs, so it is imported here. Nothing here may fail: a process that lacks it
does the same work on its first kernel.
"""

from __future__ import annotations

import contextlib
import importlib.util


def _numba_target() -> None:
    if importlib.util.find_spec("numba") is None:  # pragma: no cover - a dependency
        return
    from numba.core.registry import cpu_target

    cpu_target.target_context.refresh()


with contextlib.suppress(Exception):  # see the module docstring
    _numba_target()
