"""Warnings as one line naming the node that raised them.

numpy's "invalid value encountered in divide" says nothing of where it came
from; :func:`~graphvision.execution.executors.call_node` records in :data:`running` the
op each thread is running, and :func:`show_warning` (installed by the command
line and in worker processes) prefixes it. Imports nothing heavy: the command
line installs it before it knows whether it will run anything.
"""

from __future__ import annotations

import sys
import threading
from typing import Any

__all__ = ["running", "show_warning"]

running = threading.local()
"""``running.op``: the node id the current thread is running ("" between nodes)."""


def show_warning(
    message: Any, category: type, filename: str, lineno: int, file: Any = None, line: Any = None
) -> None:
    """Print ``warning: OP: message`` (or ``warning: message`` outside a node), for
    :data:`warnings.showwarning`."""
    op = getattr(running, "op", "")
    print(f"warning: {op + ': ' if op else ''}{message}", file=file or sys.stderr)
