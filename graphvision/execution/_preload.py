"""Imported last by the worker fork server (:mod:`graphvision.execution.worker_start`): the
batch's modules imported and its numba kernels loaded, once for every worker; a worker
that cannot start because the client has gone ends without a traceback.

The batch's modules (its plugins' node modules and what their functions import
inside their bodies: :mod:`graphvision.execution.batch_preload`) come in the
environment variable ``GRAPHVISION_WORKER_PRELOAD``, set only while the server
starts. Each is imported on its own, whatever it raises (a name that is not a
module is skipped; a module that fails fails its nodes in the workers, as it
would without the server). The numba kernels those modules define then load
the compiled code numba's cache holds for them (this machine's, for the
kernels' current code), so that no worker pays it on its first file; nothing is
compiled here.

The server's ``sys.excepthook`` is each forked worker's until it runs its
first line: a worker whose start was asked for just before the client ended
(Ctrl-C while the server was still importing) finds the client's semaphores
and pipes gone; the client reports its own end in one line, and the worker
adds nothing to it. Anything else is printed as before.
"""

from __future__ import annotations

import os
import sys
from typing import Any

from graphvision.execution.batch_preload import import_modules, load_kernels

_VARIABLE = "GRAPHVISION_WORKER_PRELOAD"  # worker_start.PRELOAD_VARIABLE


def _quiet_start_failure(kind: type[BaseException], error: BaseException, trace: Any) -> None:
    if issubclass(kind, (OSError, EOFError)):
        return
    sys.__excepthook__(kind, error, trace)


sys.excepthook = _quiet_start_failure
_names = [name for name in os.environ.pop(_VARIABLE, "").split(",") if name]
if _names:
    load_kernels(import_modules(_names))
