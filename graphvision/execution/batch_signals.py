"""A stopped batch's second Ctrl-C (or SIGTERM, SIGHUP) held off while it finishes stopping."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator

__all__ = ["signals_held"]

_STOPPING = (signal.SIGINT, signal.SIGTERM, *([signal.SIGHUP] if hasattr(signal, "SIGHUP") else []))
"""The signals that stop a command (SIGHUP: the terminal closed; not on Windows)."""


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Ctrl-C, SIGTERM and SIGHUP do nothing meanwhile (from the main thread; elsewhere
    signals do not reach Python code anyway): a stopped batch's second Ctrl-C, pressed
    while it waits for its writers and writes ``batch.csv``, no longer ends it before the
    summary and leaves folders half-written; nor does the SIGHUP that follows a SIGTERM
    when the terminal closes. The first stop's exception goes on once it is done."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held = {s: signal.getsignal(s) for s in _STOPPING}
    held = {s: handler for s, handler in held.items() if handler is not None}
    for number in held:
        signal.signal(number, _ignored)
    try:
        yield
    finally:
        for number, handler in held.items():
            signal.signal(number, handler)


def _ignored(signum: int, frame: object) -> None:
    """A signal during a batch's stop: the stop already under way is the answer to it."""
