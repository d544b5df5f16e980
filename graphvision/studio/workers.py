"""The studio's worker processes: nodes run there, and a superseded run's nodes are ended.

Python cannot stop a thread, so a node still running when its run is superseded (a newer
change) or cancelled would keep the CPU busy until it returns, minutes for a parameter
that makes it slow. The studio therefore runs its nodes in worker processes of its own
(fresh interpreters, started with the session, so the first change finds them warm),
each fed by one thread here that knows which run's node it is running. Ending a run
(:meth:`WorkerPool.end_run`) drops its queued nodes and kills (``SIGKILL``) every worker
running one of its nodes; the worker is replaced by a new process at once. The killed
node's future fails with :class:`NodeStoppedError`, so no value of it reaches the cache
(the engine stores whole results only, in this process).

A worker that dies by itself (``kill -9`` from outside, ``os._exit`` or a crash in a
node's C code, out of memory) fails its node alone with :class:`WorkerDiedError`, naming
the process and how it ended; the worker is replaced and the session goes on. Values
travel in their port type's encoding, as on the engine's ``processes`` executor
(:func:`graphvision.execution.executors.call_node_encoded`), so results are the same
bits as there; each worker holds one BLAS thread (:mod:`graphvision.execution.blas`).
"""

from __future__ import annotations

import contextlib
import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from typing import Any

from graphvision.execution.executors import WorkerDiedError
from graphvision.execution.limits import ended_by_limit
from graphvision.studio.transport import Channel

__all__ = [
    "NodeStoppedError",
    "RunExecutor",
    "WorkerPool",
    "how_it_ended",
    "serve",
]

_MAIN = "from graphvision.studio.workers import serve; serve()"


class NodeStoppedError(RuntimeError):
    """The node's run was superseded or cancelled: its worker was ended mid-node."""


@dataclass(eq=False)
class _Task:
    run: int
    fn: Callable[..., Any]
    args: tuple[Any, ...]
    future: Future = field(default_factory=Future)
    stopped: bool = False


@dataclass(eq=False)
class _Worker:
    process: Any
    connection: Any
    task: _Task | None = None


class WorkerPool:
    """``size`` worker processes shared by the session's runs (see the module docstring).

    Parameters
    ----------
    size : int, optional
        Worker processes (default: the machine's cores).
    warm : list, optional
        The node functions (:class:`~graphvision.nodes.spec.FunctionRef`) each new worker
        imports as it starts, so that a node's first run there does not import its plugin.
    """

    def __init__(self, size: int | None = None, warm: list[Any] | None = None) -> None:
        self.size = max(1, size or os.cpu_count() or 1)
        self.warm = list(warm or [])
        self.tasks: queue.SimpleQueue[_Task | None] = queue.SimpleQueue()
        self.lock = threading.Lock()
        self.workers: list[_Worker] = []
        self.closed = False
        self.ended: dict[int, str] = {}  # runs ended, and why
        self.feeders = [
            threading.Thread(target=self._feed, daemon=True, name=f"studio-worker-{i}")
            for i in range(self.size)
        ]
        for feeder in self.feeders:
            feeder.start()

    def executor(self, run: int) -> RunExecutor:
        """The executor one run hands its nodes to (:meth:`end_run` ends them)."""
        return RunExecutor(self, run)

    def submit(self, run: int, fn: Callable[..., Any], args: tuple[Any, ...]) -> Future:
        task = _Task(run, fn, args)
        task.future.set_running_or_notify_cancel()
        with self.lock:  # a node handed over just after its run ended never starts
            refused = "the studio is closing" if self.closed else self.ended.get(run)
            if refused is None:
                self.tasks.put(task)
        if refused is not None:
            task.future.set_exception(NodeStoppedError(refused))
        return task.future

    def end_run(self, run: int, why: str) -> list[int]:
        """Stop every node of ``run``: queued ones never start, running ones have their
        worker killed. Returns the process ids killed."""
        killed = []
        with self.lock:
            self.ended[run] = why
            for worker in self.workers:
                task = worker.task
                if task is not None and task.run == run and not task.stopped:
                    task.stopped = True
                    worker.process.kill()
                    killed.append(worker.process.pid)
        self._drop_queued(run, why)
        return killed

    def running(self) -> dict[int, int]:
        """Process id -> the run whose node it is running now."""
        with self.lock:
            return {w.process.pid: w.task.run for w in self.workers if w.task is not None}

    def close(self) -> None:
        """End every worker (the session is over)."""
        self.closed = True
        for _ in self.feeders:
            self.tasks.put(None)
        with self.lock:
            for worker in self.workers:
                worker.process.kill()
        self._drop_queued(None, "the studio is closing")

    def _drop_queued(self, run: int | None, why: str) -> None:
        kept = []
        while True:
            try:
                task = self.tasks.get_nowait()
            except queue.Empty:
                break
            if task is not None and (run is None or task.run == run):
                task.future.set_exception(NodeStoppedError(why))
            else:
                kept.append(task)
        for task in kept:
            self.tasks.put(task)

    # -- one thread per worker ----------------------------------------------------------

    def _start_worker(self) -> _Worker:
        """A new worker: a fresh interpreter (it imports no ``__main__``, so a script that
        calls ``gv.studio`` needs no ``if __name__ == "__main__"``), on a socket pair."""
        mine, theirs = socket.socketpair()
        process = subprocess.Popen(
            [sys.executable, "-c", _MAIN, str(theirs.fileno())],
            pass_fds=[theirs.fileno()],
            stdin=subprocess.DEVNULL,
        )
        theirs.close()
        connection = Channel(Connection(mine.detach()))
        connection.send((os.getpid(), sys.path, self.warm))
        worker = _Worker(process, connection)
        with self.lock:
            self.workers.append(worker)
        return worker

    def _retire(self, worker: _Worker) -> None:
        worker.connection.close()
        worker.process.wait()
        with self.lock:
            self.workers.remove(worker)

    def _feed(self) -> None:
        try:
            worker = self._start_worker()
        except Exception as error:  # e.g. no process can start: the runs fail, saying why
            self._refuse_all(f"no worker process could start: {type(error).__name__}: {error}")
            return
        while True:
            task = self.tasks.get()
            if task is None or self.closed:
                break
            if task.future.done():  # dropped while queued
                continue
            with self.lock:
                worker.task = task
            alive = self._run_on(worker, task)
            with self.lock:
                worker.task = None
            if not alive or task.stopped:
                self._retire(worker)
                if self.closed:
                    return
                try:
                    worker = self._start_worker()
                except Exception as error:
                    self._refuse_all(f"no new worker process could start: {error}")
                    return
        self._retire(worker)

    def _refuse_all(self, why: str) -> None:
        """This feeder has no worker: fail each node it takes (the server goes on)."""
        while (task := self.tasks.get()) is not None and not self.closed:
            if not task.future.done():
                task.future.set_exception(RuntimeError(why))

    def _run_on(self, worker: _Worker, task: _Task) -> bool:
        """Run ``task`` on ``worker`` and settle its future; False when the worker died."""
        try:
            worker.connection.send((task.fn, task.args))
        except (OSError, EOFError, ValueError):  # the worker died before it got the node
            return self._died(worker, task)
        except Exception as error:  # what the node was given could not travel
            task.future.set_exception(error)
            return True
        try:
            failed, answer = worker.connection.receive()
        except (OSError, EOFError):
            return self._died(worker, task)
        except Exception as error:  # the result could not be read back
            task.future.set_exception(RuntimeError(f"its result could not be read: {error}"))
            return True
        if failed:
            task.future.set_exception(answer)
        else:
            task.future.set_result(answer)
        return True

    def _died(self, worker: _Worker, task: _Task) -> bool:
        worker.process.wait()
        if task.stopped:
            stopped = "its run was superseded or cancelled: its worker was ended"
            task.future.set_exception(NodeStoppedError(stopped))
            return False
        ended = ended_by_limit(task.fn, task.args)
        task.future.set_exception(
            ended
            or WorkerDiedError(
                f"the worker process running this node (pid {worker.process.pid}) died: "
                f"{how_it_ended(worker.process.returncode)}; a new worker took its place"
            )
        )
        return False


class RunExecutor:
    """One run's view of the pool: what :func:`graphvision.execution.run.run` submits to."""

    encodes_values = True
    name = "processes"

    def __init__(self, pool: WorkerPool, run: int) -> None:
        self.pool, self.run = pool, run
        self.width = pool.size

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future:
        return self.pool.submit(self.run, fn, args)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        if cancel_futures:
            self.pool.end_run(self.run, "the run was interrupted")


def how_it_ended(exitcode: int | None) -> str:
    """A worker's exit code in words: ``killed by signal 9 (SIGKILL)``, ``exited with status 3``."""
    if exitcode is None:
        return "it stopped answering"
    if exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = "unknown signal"
        return f"killed by signal {-exitcode} ({name})"
    return f"exited with status {exitcode}"


# -- in the worker process -------------------------------------------------------------


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
