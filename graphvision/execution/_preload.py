"""Imported last by the worker fork server (:mod:`graphvision.execution.worker_start`): a
worker that cannot start because the client has gone ends without a traceback.

The server's ``sys.excepthook`` is each forked worker's until it runs its
first line: a worker whose start was asked for just before the client ended
(Ctrl-C while the server was still importing) finds the client's semaphores
and pipes gone; the client reports its own end in one line, and the worker
adds nothing to it. Anything else is printed as before.
"""

from __future__ import annotations

import sys
from typing import Any


def _quiet_start_failure(kind: type[BaseException], error: BaseException, trace: Any) -> None:
    if issubclass(kind, (OSError, EOFError)):
        return
    sys.__excepthook__(kind, error, trace)


sys.excepthook = _quiet_start_failure
