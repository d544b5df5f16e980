"""How the ``processes`` executor's worker processes start: forked from a server that has
already imported what every task needs.

Why not ``spawn``
-----------------
A spawned worker is a new interpreter that imports numpy, graphvision, the
plugins and numba's compiler before its first task: seconds per worker (on
two loaded cores, 6 s to start two workers and 10 s more for each one's first
coins file, numba's compiler set-up alone over 3 s), paid again by every batch.

``fork``, when it is safe
-------------------------
A fork of the client is nearly free, and a batch's client, once it has run
the first file, has everything a worker needs (the plugins and what their
node functions import, the kernels' machine code, the compiled graph): on two
loaded cores its workers began their first file 0.5 s after the batch's start,
against 6.2 s from the fork server. But a fork is unsafe while another thread
runs: a lock it holds at the fork (a logging handler's, a BLAS or numba thread
pool's, the pool's own queues') stays held in the child for good. So a batch
forks its workers (:func:`fork_context`) only from its main thread, right
after the first file, before it starts any thread of its own, and only when no
other thread runs but tqdm's progress-bar monitor (asleep but for microseconds
every 10 s, holding a lock no worker takes), and numba's parallel threading
layer has not started; on Linux only (macOS's system libraries are not
fork-safe). A client with other threads (a studio's server, Dask's client, a
notebook's), ``GRAPHVISION_WORKER_START=forkserver``, ``gv.run`` and a pool
made again after a worker died use the fork server. Python 3.12 warns at any
fork of a process with threads (OpenBLAS's idle ones included, which its own
fork handler stops): that warning is silenced for this fork alone.

``forkserver`` with a preload list
----------------------------------
The first pool of a client process starts one server process: a fresh
interpreter, single-threaded, which imports the preload list once:
graphvision's file task and, for a batch, numba's compiler
(:mod:`graphvision.execution._numba_setup`), then
:mod:`graphvision.execution._preload`, which imports the batch's modules (its
plugin modules and what their node functions import in their bodies: scipy's
``ndimage``, the numba kernel modules; :mod:`graphvision.execution.batch_preload`),
loads those kernels' compiled code from numba's cache and compiles the batch's
graph as each file's task will (plugin registry, parameter models, code
fingerprints). They reach it in an environment variable that only its start
sees (``GRAPHVISION_WORKER_PRELOAD``). Each worker is a fork of that server,
which has no other thread: milliseconds, with all of that already done once
for every worker (on two loaded cores, a worker's first coins file went from
over 2 s to 0.6 s). The list also names the client's ``__main__``, which
Python 3.11's fork server does not import (it drops the script's path): each
worker imports it, as ``spawn`` does, so that nodes a script defines are
found. The server is started while the client runs a batch's first file (its
start takes milliseconds; it imports in its own process) with Ctrl-C blocked,
which it ignores once it has imported (the client reports Ctrl-C in one line;
the server printed a ``KeyboardInterrupt`` traceback of its own); it takes the
client's ``sys.path`` (Python 3.11's drops it), lives as long as the client and
serves every later pool (its preload list is the first one's); it exits when
the client does, even after ``kill -9``. Each worker takes the client's environment variables,
standard output and error as they are at its start, as under ``spawn``
(:class:`ClientStdio`). Where the platform has no fork server (Windows),
workers are spawned.
"""

from __future__ import annotations

import contextlib
import errno
import multiprocessing
import os
import signal
import sys
import threading
from collections.abc import Iterable
from concurrent.futures import ProcessPoolExecutor
from multiprocessing.context import BaseContext
from typing import Any

__all__ = [
    "BASE_PRELOAD",
    "PRELOAD_VARIABLE",
    "START_VARIABLE",
    "ClientStdio",
    "context",
    "fork_context",
    "process_pool",
    "start_server",
    "warm_server",
]

BASE_PRELOAD = ("__main__", "graphvision.execution.file_task")
PRELOAD_VARIABLE = "GRAPHVISION_WORKER_PRELOAD"  # the server's start only: see _ensure_running
_NUMBA = "graphvision.execution._numba_setup"
_LAST = "graphvision.execution._preload"
START_VARIABLE = "GRAPHVISION_WORKER_START"  # "forkserver": never fork from the client
_MOST_BYTES = 100_000  # Linux refuses one environment string over 128 KiB
_WARM: tuple[Any, ...] = ()  # see warm_server


def context() -> BaseContext:
    """The start method of worker processes: ``forkserver`` where there is one, else spawn."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("forkserver")
    return multiprocessing.get_context("spawn")  # pragma: no cover - not on Linux


def fork_context() -> BaseContext | None:
    """The ``fork`` start method, when forking this process now is safe (else None): on
    Linux, from a thread with no other thread beside it (but tqdm's idle monitor), numba's
    parallel threads not started, and ``GRAPHVISION_WORKER_START`` not ``forkserver``. A
    batch forks its workers from the client this way after its first file, from the main
    thread (see the module docstring)."""
    if sys.platform != "linux" or os.environ.get(START_VARIABLE) == "forkserver":
        return None
    if "fork" not in multiprocessing.get_all_start_methods():  # pragma: no cover - Linux has it
        return None
    here = threading.current_thread()
    others = [t for t in threading.enumerate() if t is not here]
    if not all(_is_bar_monitor(t) for t in others):
        return None
    parallel = sys.modules.get("numba.np.ufunc.parallel")
    if parallel is not None and getattr(parallel, "_is_initialized", False):
        return None  # a threading layer (OpenMP, TBB) whose threads a fork does not carry
    return multiprocessing.get_context("fork")


def process_pool(workers: int, start: BaseContext, *setup: Any) -> ProcessPoolExecutor:
    """A process pool of ``workers`` started by ``start``, each running ``setup`` (the
    initializer and its arguments) first.

    Raises
    ------
    OSError
        When the pool cannot make its semaphores, saying so and where they live (on Linux,
        POSIX semaphores are files in ``/dev/shm``: a full one, Docker's 64 MB, refused
        them with a bare "No space left on device").
    """
    try:
        return ProcessPoolExecutor(workers, start, *setup)
    except OSError as error:
        where = "in /dev/shm" if os.path.isdir("/dev/shm") else "in the system's shared memory"
        fix = "free space there" if error.errno == errno.ENOSPC else "make it writable"
        raise OSError(
            error.errno,
            f"the process pool cannot make its semaphores {where} ({error.strerror}): {fix}, "
            "or use the threads executor",
        ) from None


def _is_bar_monitor(thread: Any) -> bool:
    """tqdm's monitor (the command line's progress bar on a terminal starts it): it wakes
    every 10 s and holds tqdm's lock for microseconds, which a worker never takes."""
    kind = type(thread)
    return kind.__name__ == "TMonitor" and kind.__module__.startswith("tqdm")


def warm_server(*arguments: Any) -> None:
    """The arguments of :func:`~graphvision.execution.file_task.warm_graph` (a batch's graph,
    plugin paths and inputs) for the server to run once it has imported the modules the
    next :func:`start_server` gives it, if it starts then."""
    global _WARM
    _WARM = arguments


def start_server(modules: Iterable[str] = (), *, start: bool = True) -> None:
    """Have the fork server preload ``modules`` too (when it has not started yet) and, with
    ``start``, start it now (milliseconds: it imports in its own process, while the client
    goes on), so that the first worker's start does not wait for it."""
    found = context()
    if found.get_start_method() != "forkserver":  # pragma: no cover - not on Linux
        return
    extra = [m for m in dict.fromkeys(modules) if m not in BASE_PRELOAD and m != _LAST]
    found.set_forkserver_preload([*BASE_PRELOAD, *([_NUMBA] if extra else []), _LAST])
    if start:
        if extra:  # a batch's: its workers will run kernels; for the server's start only
            os.environ[PRELOAD_VARIABLE] = _encoded(extra, _WARM)
        _ensure_running()  # milliseconds: the server imports after it has started


def _encoded(modules: list[str], warm: tuple[Any, ...]) -> str:
    """What the server's :mod:`~graphvision.execution._preload` reads: the modules, the
    warm-up's arguments pickled (left out when they do not pickle or are too long for one
    environment variable) and the client's ``sys.path`` (Python 3.11's fork server drops
    it: the plugin index's key, which covers the path, then differed from the client's, and
    the server imported every plugin, then removed the client's index for its own)."""
    import base64
    import json
    import pickle
    import sys

    text = ",".join(modules)
    path = base64.b64encode(json.dumps(sys.path).encode()).decode("ascii")
    try:
        data = base64.b64encode(pickle.dumps(warm)).decode("ascii") if warm else ""
    except Exception:  # a graph that does not pickle: the workers compile it themselves
        data = ""
    if len(text) + len(data) + len(path) >= _MOST_BYTES:
        data = ""
    return f"{text};{data};{path}"


class ClientStdio:
    """The client's standard output and error, for a worker: pickled as a worker starts
    (in its process object), unpickled in the worker by pointing its own at them.

    A worker forked from the server would otherwise write where the server's went: the
    client's when the server started, not where the client's are now (a test's capture,
    a redirection made since), as a spawned worker does.
    """

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        from multiprocessing import context as mp_context
        from multiprocessing import reduction

        if mp_context.get_spawning_popen() is None:  # not a worker's start: nothing to send
            return (ClientStdio, ())
        return (_use_stdio, (reduction.DupFd(1), reduction.DupFd(2)))


def _use_stdio(out: Any, err: Any) -> ClientStdio:
    """In a starting worker: standard output and error are the client's (see ClientStdio)."""
    for target, sent in ((1, out), (2, err)):
        fd = sent.detach()
        if fd != target:
            os.dup2(fd, target)
            os.close(fd)
    return ClientStdio()


def _ensure_running(server: Any = None) -> None:
    """Start the server if it is not running (whoever starts it, this thread or a pool's
    first worker, sees the batch's modules in the environment: removed once it runs).
    :mod:`graphvision.execution._preload` imports them in the server, each on its own (one
    that fails to import fails its nodes, not the server), and loads the compiled code of
    their numba kernels from numba's cache.

    The server starts with Ctrl-C blocked (a thread's signal mask passes to the process it
    starts): it is in the client's process group, and a Ctrl-C while it imported printed a
    ``KeyboardInterrupt`` traceback of its own beside the client's one line; ``_preload``
    ignores Ctrl-C, as the server does once it serves, then unblocks it."""
    from multiprocessing import forkserver

    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        with contextlib.suppress(Exception):  # the pool's first worker start reports it
            (server or forkserver._forkserver).ensure_running()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        os.environ.pop(PRELOAD_VARIABLE, None)
