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
compiled here. Last, the batch's graph (pickled after the modules, when the
batch sends it) is loaded and compiled as each file's task will, so that its
plugins' registry, parameter models and code fingerprints are built once.

The server starts with Ctrl-C blocked (``worker_start._ensure_running``): here
it ignores Ctrl-C, as the fork server does once it serves, then unblocks it,
so that a Ctrl-C during its imports neither stops it nor prints a traceback
(the client reports it). It takes the client's ``sys.path`` first.

The server's ``sys.excepthook`` is each forked worker's until it runs its
first line: a worker whose start was asked for just before the client ended
(Ctrl-C while the server was still importing) finds the client's semaphores
and pipes gone; the client reports its own end in one line, and the worker
adds nothing to it. Anything else is printed as before.
"""

from __future__ import annotations

import base64
import contextlib
import json
import os
import pickle
import signal
import sys
import threading
from typing import Any

from graphvision.execution.batch_preload import import_modules, load_kernels
from graphvision.execution.file_task import warm_graph

_VARIABLE = "GRAPHVISION_WORKER_PRELOAD"  # worker_start.PRELOAD_VARIABLE


def _quiet_start_failure(kind: type[BaseException], error: BaseException, trace: Any) -> None:
    if issubclass(kind, (OSError, EOFError)):
        return
    sys.__excepthook__(kind, error, trace)


sys.excepthook = _quiet_start_failure
if threading.current_thread() is threading.main_thread():  # the server's start (see module doc)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C that came meanwhile is dropped
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def start_batch(value: str) -> None:
    """Import the modules ``value`` names, load their numba kernels, then compile the graph
    it holds (``modules;pickled warm-up;client's path``: see ``worker_start._encoded``)."""
    names, _, rest = value.partition(";")
    data, _, path = rest.partition(";")
    if path:  # the client's, as a spawned worker has it (see worker_start._encoded)
        with contextlib.suppress(Exception):
            sys.path[:] = [str(folder) for folder in json.loads(base64.b64decode(path))]
    if names:
        load_kernels(import_modules(names.split(",")))
    if data:
        with contextlib.suppress(Exception):  # each worker does it on its first file instead
            warm_graph(*pickle.loads(base64.b64decode(data)))


start_batch(os.environ.pop(_VARIABLE, ""))
