"""The signals that stop a batch (Ctrl-C, SIGTERM, SIGHUP): held off while a stopped batch
finishes stopping (:func:`signals_held`), and deferred across a fork and native code that
calls back into Python (:func:`signals_deferred`).

Why a fork loses a Ctrl-C
-------------------------
A signal's Python handler does not run when the signal comes: the C handler notes it,
and the main thread runs the Python handler at its next bytecode. ``os.fork`` runs the
Python callbacks registered with :func:`os.register_at_fork` (``logging``'s, which takes
and releases its lock, in every process that imported it), and an exception such a
callback raises is printed (``Exception ignored in: <function _releaseLock>``) and
dropped. A Ctrl-C that came while the client forked a worker (a fork of a client that
has imported numpy, numba and the plugins copies its page tables: milliseconds) had its
``KeyboardInterrupt`` raised inside ``logging``'s callback, and dropped: the batch ran to
its end and exited 0 (3 times in 60 Ctrl-C's sent in a processes batch's first second).
The same holds for a Python callback that native code calls through ``ctypes``: a
Ctrl-C while numba loaded its kernels from its cache raised inside llvmlite's object
cache callback, which LLVM then read as a missing buffer, and the client crashed
(SIGSEGV). Blocking the signals (``pthread_sigmask``) would not do: the kernel hands a
signal the main thread blocks to another thread (OpenBLAS's), whose C handler notes it
all the same. So the handlers themselves are swapped for one that only notes the
signal, and the first signal noted is sent again once the handlers are back.

Why an import loses a Ctrl-C
----------------------------
The same holds inside an import: the import system drops a module's lock through a
weak reference's callback, and a ``KeyboardInterrupt`` raised there is printed and
dropped (the command went on: 3 times in ~790 Ctrl-C's sent in a command's first
second); one raised inside a class's ``__set_name__`` (a dataclass's fields) comes out
wrapped in a ``RuntimeError`` (an internal error: 2 in ~790). The command line
therefore imports under :func:`signals_deferred` (:func:`defer_signals_in_imports`): a
signal that comes during an import stops the command once the import is done.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["defer_signals_in_imports", "signals_deferred", "signals_held"]

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
    try:
        _set_handlers(dict.fromkeys(held, _ignored))  # a stop that comes meanwhile: ignored
        yield
    finally:
        _raise(_set_handlers(held))


@contextlib.contextmanager
def signals_deferred(*, insisted: bool = False) -> Iterator[None]:
    """Ctrl-C, SIGTERM and SIGHUP noted meanwhile, the first one sent again at the end (its
    handler then raises as usual): for a fork, and for native code that calls back into
    Python, where a handler's exception would be dropped (see the module docstring). Only
    the main thread's Python handlers are swapped; a process forked meanwhile that gets one
    of these signals before it sets its own handlers runs the handler it would have run.
    ``insisted``: a signal that comes again meanwhile runs its handler at once (a body
    that may not end soon, such as an import: the second Ctrl-C stops it).

    Raises
    ------
    KeyboardInterrupt
        Or what the handler of the first signal noted raises (the command line's
        ``Terminated`` for SIGTERM and SIGHUP), once the body is done.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handlers = {s: signal.getsignal(s) for s in _STOPPING}
    handlers = {s: handler for s, handler in handlers.items() if callable(handler)}
    noted: list[int] = []
    try:
        _raise(_set_handlers(dict.fromkeys(handlers, _noting(handlers, noted, insisted))))
        yield
    finally:
        _raise(_set_handlers(handlers))
        if noted:
            signal.raise_signal(noted[0])


def _noting(
    handlers: dict[signal.Signals, Any], noted: list[int], insisted: bool = False
) -> Callable[[int, Any], None]:
    """A handler that notes its signal in ``noted``; in a process forked meanwhile, the
    signal's own handler from ``handlers`` runs instead, and so, ``insisted``, for a signal
    noted already: the handler outside every ``insisted`` deferral this one is in (one
    not insisted, around a fork, notes it)."""
    client = os.getpid()

    def note(signum: int, frame: Any) -> None:
        number = signal.Signals(signum)
        if os.getpid() != client:
            handlers[number](signum, frame)
        elif insisted and signum in noted:
            handler = handlers[number]
            while getattr(handler, "insisted", False):  # an insisted deferral's, around this
                handler = handler.handlers[number]
            handler(signum, frame)
        else:
            noted.append(signum)

    note.insisted, note.handlers = insisted, handlers  # type: ignore[attr-defined]
    return note


def defer_signals_in_imports() -> None:
    """From now on, each import the main thread makes (the outermost one: the modules it
    imports in turn are part of it) runs under :func:`signals_deferred` (``insisted``), so
    that a Ctrl-C, SIGTERM or SIGHUP that comes meanwhile stops the process once the import
    is done, never lost in the import system's callbacks (see the module docstring). For
    the command line, which calls it first thing; a program that imports graphvision is
    left as it is.

    Every import of a module not yet loaded (``import``, ``importlib.import_module``)
    goes through the import system's ``_find_and_load``, which CPython's C code looks up
    by name each time (a private function, the same from Python 3.3 to 3.13): it is
    wrapped. A second call does nothing; so does a Python without it (nothing deferred).
    """
    bootstrap = sys.modules["importlib._bootstrap"]
    find_and_load = getattr(bootstrap, "_find_and_load", None)  # (private: not typed)
    if find_and_load is None or getattr(find_and_load, "__wrapped__", None) is not None:
        return
    main = threading.main_thread()
    depth = [0]  # imports of the main thread under way

    def deferring(*args: Any, **kwargs: Any) -> Any:
        if depth[0] or threading.current_thread() is not main:
            return find_and_load(*args, **kwargs)
        depth[0] += 1
        try:
            with signals_deferred(insisted=True):
                return find_and_load(*args, **kwargs)
        finally:
            depth[0] -= 1

    deferring.__wrapped__ = find_and_load  # type: ignore[attr-defined]
    setattr(bootstrap, "_find_and_load", deferring)  # noqa: B010


def _set_handlers(handlers: dict[signal.Signals, Any]) -> BaseException | None:
    """Each signal's handler set, every one of them even when a signal that comes meanwhile
    runs a handler that raises (Python runs it as ``signal.signal`` is called, before the
    handler changes: set again); the first such exception, or None."""
    raised: BaseException | None = None
    for number, handler in handlers.items():
        while True:
            try:
                signal.signal(number, handler)
                break
            except BaseException as error:  # a signal's handler ran meanwhile
                raised = raised or error
    return raised


def _raise(error: BaseException | None) -> None:
    if error is not None:
        raise error


def _ignored(signum: int, frame: object) -> None:
    """A signal during a batch's stop: the stop already under way is the answer to it."""
