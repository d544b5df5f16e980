"""The ``processes`` executor: a process pool that survives a dying worker.

When a worker dies, ``concurrent.futures`` breaks the whole pool: it fails every task
running in it, then terminates the pool's other workers. A task's failure reaches its
caller only once those workers have exited (:func:`_after_exit`): a caller that settles
a batch file by its claim (:mod:`graphvision.execution.batch_stop`) must not find a
worker still writing the folder it clears.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
import warnings
from collections.abc import Callable
from concurrent.futures import CancelledError, Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from multiprocessing.connection import wait
from typing import Any

from graphvision.execution.batch_guard import bootstrapping
from graphvision.execution.batch_signals import signals_deferred
from graphvision.execution.limits import ended_by_limit
from graphvision.execution.pickled_once import PickledOnce
from graphvision.execution.sendable import sent_back
from graphvision.execution.warnings import show_warning
from graphvision.execution.worker_died import WorkerDiedError, died
from graphvision.execution.worker_start import (
    ClientStdio,
    context,
    fork_context,
    process_pool,
    start_server,
)

__all__ = ["ProcessExecutor", "client_setup", "worker_setup"]

EXIT_WAIT = 30.0  # seconds a broken pool's workers get to exit before its tasks fail anyway


def client_setup() -> tuple[dict[str, str], ClientStdio]:
    """The arguments of :func:`worker_setup` for workers started now."""
    return dict(os.environ), ClientStdio()


def worker_setup(environment: dict[str, str], _: ClientStdio) -> None:
    """In each worker: the client's environment variables, standard output and error (a
    worker forked from the server has the server's), leave Ctrl-C to the client, end on
    SIGTERM as a worker does (a fork of the client carries its handler, which stopped the
    whole batch when one worker was sent SIGTERM), exit when
    the client is gone (even after ``kill -9``), and print warnings as the command line
    does (one line naming the node)."""
    from graphvision.execution.blas import one_blas_thread_for_good

    if environment != os.environ:
        os.environ.clear()
        os.environ.update(environment)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # not the client's handler a fork carries
    warnings.showwarning = show_warning
    one_blas_thread_for_good()  # the same bits as in the parent's runs (execution.blas)
    threading.Thread(target=_exit_with_client, daemon=True, name="graphvision-parent-watch").start()


def _exit_with_client() -> None:
    """Wait for the client process to end, then end this worker.

    The worker's end of a pipe the client holds open (multiprocessing's parent
    sentinel) becomes readable when the client exits, however it ends. The
    worker's parent process is no sign: a worker forked from the fork server is
    the server's child, and the server lives while any of its workers does.
    """
    import multiprocessing

    client = multiprocessing.parent_process()
    if client is not None:
        client.join()
    else:  # pragma: no cover - a pool's workers always have one
        parent = os.getppid()
        while os.getppid() == parent:
            time.sleep(0.5)
    os._exit(0)


class ProcessExecutor:
    """A process pool that survives a dying worker.

    When a worker dies, ``concurrent.futures`` breaks the whole pool and fails
    every node running in it. Here the pool is replaced and each node whose
    future broke runs again, once, in a worker of its own: a node that kills
    its worker again fails (it is the culprit), the others complete. What a task
    raises comes back whole, or as its copy, and never breaks the pool
    (:func:`~graphvision.execution.sendable.sent_back`). A worker
    that imports its client's script (the fork server's, as ``spawn``'s do) and
    finds a process pool made there (a script without ``if __name__ ==
    "__main__":``) ends at once without a word: its client says why, once,
    where each worker printed a traceback of its own. Workers ignore Ctrl-C (the
    parent handles it) and exit when their parent process is gone, even after
    ``kill -9``.
    """

    encodes_values = True
    name = "processes"
    files_per_task = 8  # files a batch sends as one task (execution.batch_forked)
    forks_file_workers = True  # a batch's files run on workers forked from the client

    def __init__(self, workers: int) -> None:
        if bootstrapping():  # a worker importing its client's script, which has no guard
            raise SystemExit(1)  # it ends without a traceback; its client names the guard
        self._workers = workers
        self.width = workers
        self.file_workers: list[Any] = []  # a batch's (execution.file_workers): joined here
        self._lock = threading.Lock()
        start_server(start=False)  # the server imports graphvision (a batch adds its plugins)
        self._pool = self._new_pool()

    def _new_pool(self, workers: int = 0) -> ProcessPoolExecutor:
        return process_pool(workers or self._workers, context(), worker_setup, client_setup())

    def preload(self, modules: list[str]) -> None:
        """Start the workers' server in the background, importing ``modules`` too (the
        plugin modules a batch uses) when it has not started yet."""
        start_server(modules)

    def fork_workers(self) -> bool:
        """Have the workers be forks of this process, all started now (when it is safe now:
        :func:`~graphvision.execution.worker_start.fork_context`; a pool made again after a
        worker died uses the server); False when not. A Ctrl-C that comes while they fork is
        raised once they have (:func:`~graphvision.execution.batch_signals.signals_deferred`:
        its exception was dropped in a fork's callback, and the batch ran on)."""
        forked = fork_context()
        if forked is None:
            return False
        pool = process_pool(self._workers, forked, worker_setup, client_setup())
        with self._lock:
            old, self._pool = self._pool, pool
        old.shutdown(wait=False)
        with warnings.catch_warnings(), signals_deferred():
            warnings.simplefilter("ignore", DeprecationWarning)  # 3.12's os.fork note on threads
            pool.submit(os.getpid)  # a fork pool forks all its workers at its first task
        return True

    def sent_once(self, value: Any) -> PickledOnce:
        """``value`` for the arguments of many tasks (a batch's job): pickled once here and
        unpickled once per worker (:mod:`graphvision.execution.pickled_once`)."""
        return PickledOnce(value)

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future:
        outer: Future = Future()
        outer.set_running_or_notify_cancel()
        pool = self._pool
        try:
            inner = pool.submit(sent_back, fn, *args)
        except BrokenProcessPool:
            pool = self._replace(pool)
            inner = pool.submit(sent_back, fn, *args)
        except (OSError, EOFError) as error:  # no worker starts (the fork server killed, say)
            outer.set_exception(WorkerDiedError(f"no worker process could start ({error!r})"))
            return outer
        workers = _workers(pool)

        def settle(done: Future) -> None:
            if done.cancelled():  # a stop's shutdown(cancel_futures=True): so is this one
                outer.set_exception(CancelledError())
                return
            if isinstance(done.exception(), BrokenProcessPool):
                self._replace(pool)
                _after_exit(list(workers.values()), lambda: self._broken(outer, fn, args))
            else:
                _copy(done, outer)

        inner.add_done_callback(settle)
        return outer

    def _broken(self, outer: Future, fn: Callable[..., Any], args: tuple) -> None:
        """A task whose pool broke, once the pool's workers are gone: failed when its node
        went past a limit or when its caller retries each of its files, else run again."""
        ended = ended_by_limit(fn, args)  # a node past its limit is not retried
        if ended is not None:
            outer.set_exception(ended)
        elif getattr(fn, "settles_its_files", False):  # the caller retries each file
            outer.set_exception(died("running a task of several files"))
        else:
            self._retry_alone(outer, fn, args)

    def _retry_alone(self, outer: Future, fn: Callable[..., Any], args: tuple) -> None:
        """Run a node whose pool broke again, in a worker of its own.

        The pool breaks for every node it was running when one worker died, so
        the retry is isolated: a node that kills its worker again is the one
        at fault and fails; the others complete.
        """
        alone = self._new_pool(workers=1)
        try:
            retry = alone.submit(sent_back, fn, *args)
        except Exception as error:  # no worker starts (the fork server killed, say): say so
            alone.shutdown(wait=False)
            why = f"{type(error).__name__}: {error}"
            outer.set_exception(died(f"and no worker could start again ({why})"))
            return

        workers = _workers(alone)

        def settle(done: Future) -> None:
            alone.shutdown(wait=False)
            if isinstance(done.exception(), BrokenProcessPool):
                ended = list(workers.values())
                _after_exit(ended, lambda: outer.set_exception(_died_again(fn, args, ended)))
            else:
                _copy(done, outer)

        retry.add_done_callback(settle)

    def _replace(self, broken: ProcessPoolExecutor) -> ProcessPoolExecutor:
        with self._lock:
            if self._pool is broken:
                broken.shutdown(wait=False, cancel_futures=True)
                self._pool = self._new_pool()
            return self._pool

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        for workers in self.file_workers:
            workers.shutdown(wait=wait)
        if wait:
            self.file_workers.clear()
        self._pool.shutdown(wait=wait, cancel_futures=cancel_futures)


def _died_again(fn: Callable[..., Any], args: tuple, ended: list[Any]) -> BaseException:
    """The error of a task whose worker died again when retried alone: the limit it went
    past, or how its worker ended (the retry's pool has that one worker)."""
    codes = []
    for worker in ended:
        with contextlib.suppress(ValueError):  # a process object already closed
            codes.append(worker.exitcode)
    running = "file" if getattr(fn, "__name__", "") in ("run_files", "run_file_task") else "node"
    code = codes[0] if codes else None
    return ended_by_limit(fn, args) or died("and again when retried alone", code, running)


def _copy(source: Future, target: Future) -> None:
    error = source.exception()
    if error is not None:
        target.set_exception(error)
    else:
        target.set_result(source.result())


def _workers(pool: ProcessPoolExecutor) -> dict[int, Any]:
    """The pool's worker processes by pid: the pool's own dict, which gains the workers it
    starts later and which the pool's manager keeps after ``shutdown`` drops the pool's
    name for it (``concurrent.futures`` has no public list of its workers)."""
    workers = getattr(pool, "_processes", None)
    return workers if isinstance(workers, dict) else {}


def _after_exit(workers: list[Any], then: Callable[[], None]) -> None:
    """Call ``then`` once every one of ``workers`` has exited (at most :data:`EXIT_WAIT`
    seconds), from a thread of its own: the pool's manager thread, which runs a broken
    task's callback, terminates the other workers only after its callbacks return. It waits
    on their sentinels, which reaps nothing (the pool joins its workers itself), and holds
    the process objects, whose sentinels close with them."""
    sentinels = []
    for worker in workers:
        with contextlib.suppress(ValueError):  # a process object already closed: gone
            sentinels.append(worker.sentinel)
    left = [sentinel for sentinel in sentinels if sentinel not in wait(sentinels, timeout=0)]
    if not left:
        then()
        return

    def wait_then() -> None:
        ends, waiting = time.monotonic() + EXIT_WAIT, left
        while waiting and time.monotonic() < ends:
            ready = wait(waiting, timeout=ends - time.monotonic())
            waiting = [sentinel for sentinel in waiting if sentinel not in ready]
        then()
        workers.clear()  # held until here: their sentinels stay open while waited on

    threading.Thread(target=wait_then, daemon=True, name="graphvision-broken-pool").start()
