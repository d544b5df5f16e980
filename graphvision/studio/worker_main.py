"""A studio worker process's loop (:mod:`.workers` starts it with ``python -c``): take a
node and its inputs from the server, answer its result or its exception."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
from multiprocessing.connection import Connection
from typing import Any

from graphvision.studio.transport import Channel

__all__ = ["serve"]


def serve() -> None:
    """A worker's loop (``python -c`` runs it, on the socket whose descriptor is its
    argument): take ``(fn, args)``, answer ``(failed, result or exception)``."""
    import warnings

    from graphvision.execution.blas import one_blas_thread_for_good
    from graphvision.execution.warnings import show_warning

    connection = Channel(Connection(int(sys.argv[1])))
    parent, path, warm = connection.receive()
    sys.path[:] = path  # plugins found where the studio found them
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the server's to handle
    warnings.showwarning = show_warning
    one_blas_thread_for_good()
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()
    for ref in warm:
        with contextlib.suppress(Exception):  # the node fails when it runs, saying why
            ref.resolve()
    while True:
        try:
            fn, args = connection.receive()
        except (EOFError, OSError):
            return
        try:
            answer: tuple[bool, Any] = (False, fn(*args))
        except BaseException as error:  # the parent fails the node with it
            answer = (True, error)
        try:
            connection.send(answer)
        except Exception as error:  # a result or an exception that cannot be pickled
            connection.send((True, RuntimeError(f"{type(error).__name__}: {error}")))


def _watch_parent(parent: int) -> None:
    """End this worker when the studio's process is gone (even after its ``kill -9``)."""
    while os.getppid() == parent:
        time.sleep(0.5)
    os._exit(0)
