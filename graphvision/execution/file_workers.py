"""A batch's worker processes on ``processes``: forked once per batch, each with a pipe of
its own, and one client thread (the batch's) waiting on every pipe and every worker's
sentinel at once (:func:`multiprocessing.connection.wait`).

Why not ``ProcessPoolExecutor``
-------------------------------
On two cores every millisecond of the client's CPU is taken from a worker. A
``ProcessPoolExecutor`` task passes through the pool's queue feeder thread, its
call queue, its manager thread and back through a result queue, and a batch's
lanes each waited in a thread of their own: 0.10-0.15 s of the client's CPU per
200-file coins batch, where the work itself took 1 s. Here a task is one
``send`` on the worker's pipe and its answer one ``recv``, both from the batch's
own thread, which sleeps in a single ``wait`` between them.

A worker's death
----------------
When a worker dies, ``concurrent.futures`` breaks the whole pool, fails every
task in it and ends the other workers before a task's failure can be settled
(:mod:`graphvision.execution.process_executor`). Here a death is its sentinel
becoming ready: the worker has exited, its exit code says how, and the tasks it
held are known (the first one sent and not answered is the one it ran); the
other workers go on. Whatever the dead worker had answered is read from its pipe
first.

Each worker runs :func:`~graphvision.execution.process_executor.worker_setup`
first (Ctrl-C left to the client, SIGTERM's default, exit with the client even
after ``kill -9``), as the pool's workers do. A Ctrl-C (SIGTERM, SIGHUP) that comes
while the client forks a worker is delivered once the fork is done
(:func:`~graphvision.execution.batch_signals.signals_deferred`): raised during the fork,
it was dropped and the batch ran on.
"""

from __future__ import annotations

import contextlib
import pickle
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from multiprocessing.context import BaseContext
from multiprocessing.process import BaseProcess
from typing import Any

from graphvision.execution.batch_signals import signals_deferred
from graphvision.execution.process_executor import client_setup, worker_setup

__all__ = ["FileWorker", "FileWorkers", "Handler"]

Handler = Callable[[Any, Any], Any]
"""Runs one message's payload in a worker: ``handler(state, payload)`` (``state`` is what
the worker was started with: the batch, for a fork of the client), its answer sent back."""


@dataclass(eq=False)
class FileWorker:
    """One worker process, its end of the pipe in the client, and the tasks sent to it that
    it has not answered yet (oldest first: the first is the one it is running)."""

    process: BaseProcess
    conn: Connection
    held: list[Any] = field(default_factory=list)
    has_job: bool = False  # it was sent the batch's job
    alone: bool = False  # it runs a file retried alone: nothing is sent beside it


class FileWorkers:
    """The worker processes of one batch (see the module docstring)."""

    def __init__(self, start: BaseContext) -> None:
        self.start_method = start
        self.setup = client_setup()
        self.workers: list[FileWorker] = []
        self.ended: list[BaseProcess] = []  # dead workers, reaped at shutdown

    def start(self, state: Any = None) -> FileWorker:
        """A new worker, ``state`` given to its handlers (forked: the client's memory)."""
        client_end, worker_end = self.start_method.Pipe()
        inherited = [worker.conn for worker in self.workers] + [client_end]
        if self.start_method.get_start_method() != "fork":  # a fresh process inherits none
            inherited = []
        process = self.start_method.Process(  # type: ignore[attr-defined]  # every context has it
            target=_serve,
            args=(worker_end, self.setup, state, inherited),
            name=f"graphvision-file-worker-{len(self.workers) + len(self.ended)}",
            daemon=True,
        )
        with warnings.catch_warnings(), signals_deferred():  # a Ctrl-C meanwhile is not lost
            warnings.simplefilter("ignore", DeprecationWarning)  # 3.12's os.fork note on threads
            process.start()
        worker_end.close()
        worker = FileWorker(process, client_end)
        self.workers.append(worker)
        return worker

    def send(self, worker: FileWorker, task: Any, handler: Handler, payload: Any) -> None:
        """Have ``worker`` run ``handler(state, payload)``; ``task`` names it in the answer."""
        worker.held.append(task)
        worker.conn.send((handler, payload))

    def answers(self) -> tuple[list[tuple[FileWorker, Any, Any]], list[FileWorker]]:
        """Waits for the workers: the answers that came, each ``(worker, task, answer)``
        (what the handler returned, or the exception it raised), and the workers that died
        (each removed, its ``held`` tasks unanswered: what it answered before is read
        first)."""
        live = list(self.workers)
        ready = set(wait([w.conn for w in live] + [w.process.sentinel for w in live]))
        found, dead = [], []
        for worker in live:
            if worker.conn not in ready and worker.process.sentinel not in ready:
                continue
            ended = worker.process.sentinel in ready
            try:
                while worker.held and worker.conn.poll():
                    answer = worker.conn.recv()  # before the task is taken: EOF leaves it
                    found.append((worker, worker.held.pop(0), answer))
            except (EOFError, OSError):  # its end of the pipe closed: it is exiting
                ended = True
            if ended:
                worker.process.join()  # its exit code (it has exited, or is exiting)
                dead.append(worker)
                self._ended(worker)
        return found, dead

    def _ended(self, worker: FileWorker) -> None:
        """``worker`` is gone, or leaving: joined at :meth:`shutdown`."""
        self.workers.remove(worker)
        self.ended.append(worker.process)
        worker.conn.close()

    def reaped(self) -> bool:
        """Whether every worker has ended (each then joined and closed, nothing left to
        wait for at the executor's shutdown); a worker still running is left alone."""
        running = []
        for process in self.ended:
            if process.exitcode is None:  # (polls it: reaped when it has exited)
                running.append(process)
            else:
                process.close()
        self.ended = running
        return not (self.workers or self.ended)

    def shutdown(self, wait: bool = True) -> None:
        """Every worker exits once its task is done (now when it has none); all of them
        joined with ``wait``."""
        for worker in list(self.workers):
            with contextlib.suppress(OSError, ValueError):  # gone already
                worker.conn.send(None)
            self._ended(worker)
        if wait:
            for process in self.ended:
                process.join()
                process.close()
            self.ended.clear()


def _serve(
    conn: Connection, setup: tuple[Any, ...], state: Any, inherited: list[Connection]
) -> None:
    """A worker: each message's handler run in turn, its answer (or what it raised) sent
    back, until ``None`` or the client's end of the pipe closes."""
    for other in inherited:  # the client's ends of the pipes, which a fork carries
        other.close()
    worker_setup(*setup)
    while True:
        try:
            message = conn.recv()
        except EOFError:
            return
        if message is None:
            return
        handler, payload = message
        try:
            answer = handler(state, payload)
        except Exception as error:  # the task fails, with its reason; the worker goes on
            answer = error
        try:
            conn.send_bytes(_pickled(answer))
        except OSError:  # the client's end closed (the batch stopped): nobody to answer
            return


def _pickled(answer: Any) -> bytes:
    """``answer`` pickled, or when it does not pickle, an error saying what it was."""
    try:
        return pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception as error:
        why = f"a worker's answer could not be sent back ({type(error).__name__}: {error})"
        return pickle.dumps(RuntimeError(why))
