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

import os
import queue
import signal
import socket
import subprocess
import sys
import threading
from collections import deque
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
]

_MAIN = "from graphvision.studio.worker_main import serve; serve()"


class NodeStoppedError(RuntimeError):
    """The node's run was superseded or cancelled: its worker was ended mid-node."""


@dataclass(eq=False)
class _Task:
    run: int
    fn: Callable[..., Any]
    args: tuple[Any, ...]
    future: Future = field(init=False)
    stopped: bool = False
    waits: set[_Task] = field(default_factory=set)  # submitted ahead of these tasks' results
    dependents: list[_Task] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.future = _TaskFuture(self)


class _TaskFuture(Future):
    """A node's future; its ``task`` stands for its result in a later node's arguments."""

    def __init__(self, task: _Task) -> None:
        super().__init__()
        self.task = task


@dataclass(eq=False)
class _Worker:
    process: Any
    connection: Any
    task: _Task | None = None
    sent: queue.SimpleQueue[_Task | None] = field(default_factory=queue.SimpleQueue)


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
        self.pending: deque[_Task] = deque()  # ready, waiting for a free worker
        self.held: set[_Task] = set()  # waiting for the results of the nodes they read
        self.lock = threading.Lock()
        self.workers: list[_Worker] = []
        self.closed = False
        self.broken = ""  # why no worker could start, when none could
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
        """Hand a node over: sent at once, from this thread, to a free worker; else kept
        until one is free, or until the nodes whose tasks stand in ``args`` have results."""
        task = _Task(run, fn, args)
        task.future.set_running_or_notify_cancel()
        with self.lock:  # a node handed over just after its run ended never starts
            refused = "the studio is closing" if self.closed else self.ended.get(run)
            if refused is None:
                for upstream in _handles(args):
                    if not upstream.future.done():
                        task.waits.add(upstream)
                        upstream.dependents.append(task)
                    elif upstream.future.exception() is not None:
                        refused = "a node it reads failed"
            if refused is None and task.waits:
                self.held.add(task)
            placed = self._place(task) if refused is None and not task.waits else None
        if refused is not None:
            task.future.set_exception(NodeStoppedError(refused))
        elif placed is not None:
            self._send(placed, task)
        return task.future

    def end_run(self, run: int, why: str) -> list[int]:
        """Stop every node of ``run``: waiting ones never start, running ones have their
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
            dropped = self._drop(lambda task: task.run == run)
        for task in dropped:
            task.future.set_exception(NodeStoppedError(why))
        return killed

    def running(self) -> dict[int, int]:
        """Process id -> the run whose node it is running now."""
        with self.lock:
            return {w.process.pid: w.task.run for w in self.workers if w.task is not None}

    def close(self) -> None:
        """End every worker (the session is over)."""
        with self.lock:
            self.closed = True
            for worker in self.workers:
                worker.process.kill()
            dropped = self._drop(lambda task: True)
        for worker in list(self.workers):
            worker.sent.put(None)
        for task in dropped:
            task.future.set_exception(NodeStoppedError("the studio is closing"))

    def _drop(self, which: Callable[[_Task], bool]) -> list[_Task]:
        """Take the waiting tasks ``which`` selects out of the pool (under the lock)."""
        dropped = [t for t in (*self.pending, *self.held) if which(t)]
        self.pending = deque(t for t in self.pending if not which(t))
        self.held.difference_update(dropped)
        return dropped

    # -- placing nodes on workers ------------------------------------------------------

    def _place(self, task: _Task, prefer: _Worker | None = None) -> _Worker | None:
        """A free worker now taken by ``task`` (under the lock), or None: it then waits."""
        free = [w for w in self.workers if w.task is None and w.process.poll() is None]
        worker = prefer if prefer in free else (free[0] if free else None)
        if worker is None:
            if self.broken and not self.workers:
                task.future.set_exception(RuntimeError(self.broken))
            else:
                self.pending.append(task)
            return None
        worker.task = task
        return worker

    def _send(self, worker: _Worker, task: _Task) -> None:
        """Send ``task`` to ``worker`` (it has taken it), the results it reads in place of
        their tasks; the worker's thread then waits for its answer."""
        try:
            worker.connection.send((task.fn, _resolved(task.args)))
        except (OSError, EOFError, ValueError):  # the worker died before it got the node
            worker.sent.put(task)  # its thread finds it dead, and says so
            return
        except Exception as error:  # what the node was given could not travel
            with self.lock:
                worker.task = None
            task.future.set_exception(error)
            self._released(task, worker)
            return
        worker.sent.put(task)

    def _released(self, done: _Task, worker: _Worker) -> None:
        """``done`` has settled: the nodes waiting for it start (on ``worker`` first, which is
        free and awake), or fail with it; then a waiting node takes a free worker."""
        failed = done.future.exception() is not None
        starting: list[_Task] = []
        stopped: list[_Task] = []
        with self.lock:
            for task in done.dependents:
                task.waits.discard(done)
                if task in self.held and (failed or not task.waits):
                    self.held.discard(task)
                    (stopped if failed else starting).append(task)
            placed = [(self._place(t, worker), t) for t in starting]
            while self.pending and not self.closed:
                waiting = self.pending.popleft()
                found = self._place(waiting)
                if found is None:
                    break
                placed.append((found, waiting))
        for task in stopped:
            task.future.set_exception(NodeStoppedError("a node it reads failed"))
            self._released(task, worker)
        for target, task in placed:
            if target is not None:
                self._send(target, task)

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
        return _Worker(process, connection)

    def _retire(self, worker: _Worker) -> None:
        with self.lock:
            self.workers.remove(worker)
            worker.task = None
        worker.connection.close()
        worker.process.wait()

    def _join(self, worker: _Worker) -> None:
        """A new worker joins the pool and takes a waiting node, if any."""
        with self.lock:
            self.workers.append(worker)
            task = self.pending.popleft() if self.pending and not self.closed else None
            if task is not None:
                worker.task = task
        if task is not None:
            self._send(worker, task)

    def _feed(self) -> None:
        worker = self._new_worker()
        while worker is not None:
            task = worker.sent.get()
            if task is None or self.closed:
                break
            alive = self._run_on(worker, task)
            if alive and not task.stopped:
                with self.lock:
                    worker.task = None
                self._released(task, worker)
                continue
            self._retire(worker)  # out of the pool first: no node is placed on it
            self._released(task, worker)
            worker = None if self.closed else self._new_worker()
        if worker is not None:
            self._retire(worker)

    def _new_worker(self) -> _Worker | None:
        """A worker started and in the pool; None when none can start (nodes then fail,
        saying why, once no worker is left)."""
        try:
            worker = self._start_worker()
        except Exception as error:  # e.g. no process can start: the runs fail, saying why
            with self.lock:
                self.broken = f"no worker process could start: {type(error).__name__}: {error}"
                dropped = list(self.pending) if not self.workers else []
                if dropped:
                    self.pending.clear()
            for task in dropped:
                task.future.set_exception(RuntimeError(self.broken))
            return None
        self._join(worker)
        return worker

    def _run_on(self, worker: _Worker, task: _Task) -> bool:
        """Take ``task``'s answer from ``worker`` (it was sent) and settle its future; False
        when the worker died."""
        try:
            failed, answer = worker.connection.receive()
        except (OSError, EOFError, ValueError):
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
        ended = ended_by_limit(task.fn, _resolved(task.args))
        task.future.set_exception(
            ended
            or WorkerDiedError(
                f"the worker process running this node (pid {worker.process.pid}) died: "
                f"{how_it_ended(worker.process.returncode)}; a new worker took its place"
            )
        )
        return False


class RunExecutor:
    """One run's view of the pool: what :func:`graphvision.execution.run.run` submits to.

    It chains tasks (``chains_tasks``): a node is handed over as soon as the nodes it reads
    are, their futures' tasks in its arguments; the pool sends it to a worker, with their
    results, from the thread that takes the last of them, not through the run's thread.
    """

    encodes_values = True
    chains_tasks = True
    name = "processes"

    def __init__(self, pool: WorkerPool, run: int) -> None:
        self.pool, self.run = pool, run
        self.width = pool.size

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future:
        return self.pool.submit(self.run, fn, args)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        if cancel_futures:
            self.pool.end_run(self.run, "the run was interrupted")


def _handles(args: Any) -> list[_Task]:
    """The tasks standing for results in ``args`` (in tuples, lists and dicts)."""
    if isinstance(args, _Task):
        return [args]
    if isinstance(args, tuple | list):
        return [t for a in args for t in _handles(a)]
    if isinstance(args, dict):
        return [t for a in args.values() for t in _handles(a)]
    return []


def _resolved(args: Any) -> Any:
    """``args`` with each task in it replaced by its result."""
    if isinstance(args, _Task):
        return args.future.result()
    if isinstance(args, tuple | list) and _handles(args):
        return type(args)(_resolved(a) for a in args)
    if isinstance(args, dict) and _handles(args):
        return {k: _resolved(a) for k, a in args.items()}
    return args


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
