"""The Dask executor's own ``LocalCluster`` (:func:`start_local_cluster`) and its workers
forked from a batch's client (:class:`ForkedWorkers`), as the ``processes`` executor's are
(:mod:`graphvision.execution.worker_start`).

A ``LocalCluster`` spawns each worker: a new interpreter that imports numpy,
Dask, graphvision, the plugins, scipy and numba's compiler before its first
file (on 2 cores, each worker spent 2 to 3 s of CPU on it, taken from the
files). A batch's client, once it has run the first file, has all of that, and
the batch's registry; a fork of it costs milliseconds. So when the executor's
own cluster has not started yet and forking the client is safe
(:func:`~graphvision.execution.worker_start.fork_context`: no other thread runs,
as before any Dask client exists), the batch forks the workers right after
its first file (``fork_workers``); the cluster's scheduler then starts in the
client, as a ``LocalCluster``'s does, and each worker connects to it, a
``distributed.Worker`` in its own event loop, while the client runs files.

A forked worker ignores Ctrl-C (the client reports it and closes the cluster),
ends on SIGTERM as any worker does, and exits when the client does (its pipe
from the client closes, even after ``kill -9``). One that dies is replaced by
a worker the cluster spawns, and the scheduler runs its tasks again on the
others (``retries``), as with a nanny's worker; one ended by SIGTERM is not
(SIGTERM to the batch's process group: replacements spawned then made the
cluster's close take 7 to 13 s after the batch had stopped).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading
import warnings
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from graphvision.execution.batch_signals import signals_deferred
from graphvision.execution.worker_start import fork_context

__all__ = ["ForkedWorkers", "direct_gathers", "start_forked_cluster", "start_local_cluster"]

_JOIN_SECONDS = 5.0


class ForkedWorkers:
    """``count`` processes forked from this one now, each waiting for the scheduler's address
    to become a Dask worker of ``threads`` threads (:meth:`connect`)."""

    def __init__(self, count: int, threads: int) -> None:
        found = fork_context()
        if found is None:
            raise RuntimeError("forking this process is not safe now")
        self.closing = False
        self._pipes: list[int] = []
        self.processes: list[Any] = []
        with signals_deferred():  # a Ctrl-C meanwhile is not dropped by a fork's callbacks
            mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})  # (the workers')
            try:
                for k in range(count):
                    self._fork(found, k, threads)
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, mask)

    def _fork(self, found: Any, k: int, threads: int) -> None:
        """Worker ``k``, forked, with its pipe."""
        read, write = os.pipe()
        process = found.Process(
            target=_serve,
            args=(read, threads, tuple(self._pipes)),
            name=f"graphvision-dask-worker-{k}",
            daemon=True,
        )
        with warnings.catch_warnings():  # 3.12's os.fork note on threads
            warnings.simplefilter("ignore", DeprecationWarning)
            process.start()
        os.close(read)
        self._pipes.append(write)
        self.processes.append(process)

    def connect(self, address: str) -> None:
        """Each worker connects to the scheduler at ``address``."""
        for pipe in self._pipes:
            with contextlib.suppress(OSError):  # a worker already gone: replaced by watch
                os.write(pipe, f"{address}\n".encode())

    def watch(self, replace: Callable[[int], None]) -> None:
        """Call ``replace(n)`` with the number of workers lost so far each time one dies (not
        once :meth:`close` has begun, nor for one ended by SIGTERM: the batch is being
        stopped, its whole process group with it), from a thread of its own."""

        def run() -> None:
            from multiprocessing.connection import wait

            alive = {process.sentinel: process for process in self.processes}
            lost = 0
            while alive and not self.closing:
                for sentinel in wait(list(alive), timeout=1.0):
                    ended = alive.pop(sentinel)
                    ended.join(_JOIN_SECONDS)  # its exit status
                    if not self.closing and ended.exitcode != -signal.SIGTERM:
                        lost += 1
                        replace(lost)

        threading.Thread(target=run, daemon=True, name="graphvision-dask-forked").start()

    def close(self) -> None:
        """The workers' pipes closed: each closes its worker and exits; those still there
        after a few seconds are ended."""
        self.closing = True
        for pipe in self._pipes:
            with contextlib.suppress(OSError):
                os.close(pipe)
        self._pipes = []
        for process in self.processes:
            process.join(_JOIN_SECONDS)
            if process.is_alive():
                process.kill()
                process.join(_JOIN_SECONDS)


def start_local_cluster(workers: int, threads_per_worker: int) -> tuple[Any, Any]:
    """A ``LocalCluster`` of ``workers`` processes and its client. Its workers do not run
    Dask's statistical profiler (``distributed.worker.profile``: a thread that took the GIL
    every 10 ms to walk the stack, 7 % of a batch's worker time on coins files)."""
    import dask
    import distributed

    with dask.config.set({"distributed.worker.profile.enabled": False}):
        cluster = distributed.LocalCluster(
            n_workers=workers,
            threads_per_worker=threads_per_worker,
            processes=True,
            scheduler_port=0,
            dashboard_address=":0",
            # a failing node is reported once, by the run, naming it: not also as
            # each worker's "Compute Failed" traceback
            silence_logs=logging.CRITICAL,
        )
    try:  # its results fetched from the workers straight (see direct_gathers)
        return cluster, distributed.Client(cluster, direct_to_workers=True)
    except BaseException:
        cluster.close()
        raise


def start_forked_cluster(forked: ForkedWorkers, ready: Future) -> tuple[Any, Any]:
    """A ``LocalCluster`` of no worker of its own (its scheduler here), the ``forked`` workers
    connected to it, and its client; ``ready`` is done once a worker has joined. A forked
    worker that dies is replaced by one the cluster spawns."""
    cluster, client = start_local_cluster(0, 1)
    try:
        forked.connect(cluster.scheduler_address)
        forked.watch(cluster.scale)
        client.wait_for_workers(1, timeout=60)
    except BaseException as error:
        ready.set_exception(error)
        client.close()
        cluster.close()
        raise
    ready.set_result(None)
    return cluster, client


def _serve(pipe: int, threads: int, inherited: tuple[int, ...]) -> None:
    """In a forked worker: wait for the scheduler's address, then be a Dask worker until the
    client closes the pipe or the scheduler closes the worker."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the client reports Ctrl-C
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # not the command line's handler
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    for other in inherited:  # the other workers' pipes: their end is the client's alone
        with contextlib.suppress(OSError):
            os.close(other)
    address = _read_line(pipe)
    if not address:  # the client closed before the scheduler started
        return
    import asyncio

    import dask

    # a failing node is reported once, by the run, naming it (as LocalCluster's silence_logs)
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    with dask.config.set({"distributed.worker.profile.enabled": False}):
        asyncio.run(_worker(address, threads, pipe))


def _read_line(pipe: int) -> str:
    data = b""
    while not data.endswith(b"\n"):
        chunk = os.read(pipe, 256)
        if not chunk:
            return ""
        data += chunk
    return data.decode().strip()


async def _worker(address: str, threads: int, pipe: int) -> None:
    import asyncio

    import distributed

    gone = asyncio.Event()
    asyncio.get_running_loop().add_reader(pipe, gone.set)  # readable at EOF: the client left
    async with distributed.Worker(address, nthreads=threads) as worker:
        waits = {asyncio.ensure_future(gone.wait()), asyncio.ensure_future(worker.finished())}
        _, pending = await asyncio.wait(waits, return_when=asyncio.FIRST_COMPLETED)
        for task in pending:
            task.cancel()


def direct_gathers(client: Any) -> bool | None:
    """Whether ``client`` fetches results from the workers straight (``direct_to_workers``):
    its own setting, else yes for a ``LocalCluster`` of this process, else Dask's default
    (through the scheduler: workers of a remote cluster may not be reachable from here).

    Through the scheduler, each result made two round trips in this process (client to
    scheduler, scheduler to worker) where one does: a ``LocalCluster``'s scheduler runs in
    the client's process, on the cores its workers need.
    """
    if client is None or client.direct_to_workers is not None:
        return None
    import distributed

    return True if isinstance(client.cluster, distributed.LocalCluster) else None
