"""Running nodes on a Dask cluster: :class:`DaskExecutor`.

The executor hands each node to ``dask.distributed`` as one task. It keeps the transport
of the ``processes`` executor: the node function travels as a
:class:`~graphvision.nodes.node.FunctionRef` (the worker imports it by module and name, a
local plugin file by its path), and values travel in their port type's array encoding
(named arrays and a JSON header), never as pickled Python objects. Results come back to
the client, which validates them and stores them in its own cache: the cache never has to
be on storage the workers share, and a value is written once, by one process, with the
cache's atomic rename.

A node is submitted as soon as the nodes it reads are (``chains_tasks``: the run starts
tasks ahead, see :func:`~graphvision.execution.scheduler.run_tasks`), with their Dask
futures in its arguments in place of their values: Dask passes results from worker to
worker, and a chain runs at the cluster's pace while the client takes each result as it
lands (a round trip through the client per node made a chain cost 1.9 times raw Dask's).

Results are fetched where it costs least. A task submitted while others are in flight
has its result awaited on the client's event loop, so many results are fetched at once
(a blocking fetch per task, one after another, made independent tasks cost twice what
raw Dask's ``gather`` costs); a task submitted alone (a chain) is fetched by Dask's
callback thread, one thread hop fewer. On a ``LocalCluster`` of this process, results come
from the workers straight, not through the scheduler
(:func:`~graphvision.execution.dask_fork.direct_gathers`).

Without a client or an address, the executor starts a ``LocalCluster`` in a background
thread when something first needs it: the files a batch's client runs while the workers
are not ready (:mod:`graphvision.execution.batch_lanes`: ``client_files``, on for Dask)
run meanwhile; what needs the cluster waits for it. A batch runs its first file before,
then forks the cluster's workers from the client when that is safe
(:mod:`graphvision.execution.dask_fork`), so they import nothing. A value shared
(:meth:`DaskExecutor.share`) is copied to every worker, so that Dask spreads the tasks
that read it (:mod:`graphvision.execution.dask_shared`); shared before the cluster has
started, it travels with the first task that reads it. A
batch's files go several to a task (:mod:`graphvision.execution.dask_files`). A worker
importing a script that starts a cluster again is refused (``batch_guard``).

A worker that dies while it runs a node is replaced by Dask and the node is run again on
another worker (``retries``), so one lost worker costs one node, not the run. Dask is an
optional dependency (``pip install graphvision[dask]``), imported only when this executor
is made.
"""

from __future__ import annotations

import atexit
import functools
import os
import threading
import time
import weakref
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from graphvision.errors import GraphvisionError
from graphvision.execution.batch_guard import guard_hint, refuse_in_bootstrap
from graphvision.execution.dask_files import FILES_PER_TASK, GROUPS_PER_THREAD, FileGroups
from graphvision.execution.dask_fork import (
    ForkedWorkers,
    direct_gathers,
    start_forked_cluster,
    start_local_cluster,
)
from graphvision.execution.dask_results import Landed, fetch_on_loop, settle
from graphvision.execution.dask_shared import SharedValue
from graphvision.execution.dask_worker import on_worker
from graphvision.execution.worker_died import died_on_dask
from graphvision.execution.worker_start import fork_context

__all__ = [
    "SCHEDULER_VARIABLE",
    "WIDTH_SECONDS",
    "DaskExecutor",
    "DaskUnavailableError",
    "TaskFuture",
]

SCHEDULER_VARIABLE = "GRAPHVISION_DASK_SCHEDULER"
WIDTH_SECONDS = 1.0  # a given cluster's width is asked of its scheduler at most this often


class DaskUnavailableError(GraphvisionError):
    """Dask is not installed, or its scheduler cannot be reached."""


class DaskExecutor:
    """Nodes as tasks on a Dask cluster (an existing one, or a local one it starts).

    Parameters
    ----------
    client : distributed.Client, optional
        Use this client's cluster; the executor does not close it.
    address : str, optional
        Connect to the scheduler at this address (``tcp://host:port``);
        default ``$GRAPHVISION_DASK_SCHEDULER``. Without either, a
        ``LocalCluster`` is started (in the background) and closed by :meth:`shutdown`.
    workers : int
        Worker processes of a local cluster.
    threads_per_worker : int
        Threads in each worker of a local cluster.
    timeout : float
        Seconds to wait for the scheduler before giving up.
    retries : int
        How many times a node whose worker died (or that raised) is run again.
    """

    encodes_values = True
    chains_tasks = True
    client_files = True  # a batch's client runs files while the workers warm up
    files_per_task = FILES_PER_TASK  # a batch's files go several to a task
    name = "dask"

    def __init__(
        self,
        client: Any = None,
        *,
        address: str | None = None,
        workers: int = 2,
        threads_per_worker: int = 1,
        timeout: float = 10.0,
        retries: int = 1,
    ) -> None:
        try:
            import distributed
        except ImportError as error:
            raise DaskUnavailableError(
                "the dask executor needs Dask: pip install 'graphvision[dask]'"
            ) from error
        self.retries = retries
        self._in_flight = 0
        self._in_flight_lock = threading.Lock()
        self._begin_lock = threading.Lock()  # the cluster started once (not under the above)
        self._cluster: Any = None
        self._client: Any = client
        self._owns_client = client is None
        self._width = 0  # a local cluster's, known before it has started
        self._asked = (0, -WIDTH_SECONDS)  # a given cluster's width, and when it was asked
        self._started = threading.Event()
        self._start_error: BaseException | None = None
        self._closing = False
        self._starter: threading.Thread | None = None
        self._files = FileGroups(self)  # a batch's files, a few to a task
        self._forked: ForkedWorkers | None = None  # the local cluster's, forked from here
        self._ready: Future = Future()  # a forked worker has joined the cluster
        address = address or os.environ.get(SCHEDULER_VARIABLE) or None
        if client is None and address:
            try:
                self._client = distributed.Client(address, timeout=timeout)
            except Exception as error:  # unreachable, refused, or not an address at all
                raise DaskUnavailableError(
                    f"cannot reach the Dask scheduler at {address} within {timeout:g} s "
                    f"({type(error).__name__}); check the address, or leave out "
                    f"--scheduler and ${SCHEDULER_VARIABLE} to start a local cluster"
                ) from None
        self._direct = direct_gathers(self._client)  # the own cluster's client: its own
        if self._client is not None:
            self._started.set()
            return
        self._width, self._shape = workers * threads_per_worker, (workers, threads_per_worker)

    def _begin(self) -> None:
        """Start the local cluster in the background, once (on first need: a batch's first
        file runs before it, so that its workers can be forked after it)."""
        with self._begin_lock:
            if self._starter is not None or self._started.is_set():
                return
            if self._closing:  # shut down before it started: the client says so
                self._started.set()
                return
            refuse_in_bootstrap("a local Dask cluster")  # in a worker importing the script
            _STARTING.add(self)
            _wait_for_starts_at_exit()
            self._starter = threading.Thread(
                target=self._start_local, daemon=True, name="graphvision-dask-cluster"
            )
            self._starter.start()

    def _start_local(self) -> None:
        """Start the local cluster (in the background: a batch's client runs files
        meanwhile); a cluster that started after :meth:`shutdown` is closed at once."""
        try:
            if self._forked is not None:
                self._cluster, self._client = start_forked_cluster(self._forked, self._ready)
            else:
                self._cluster, self._client = start_local_cluster(*self._shape)
        except BaseException as error:  # reported where the client is first needed
            self._start_error = error
        finally:
            self._started.set()
        try:
            if self._closing:
                self._close()
        finally:
            _STARTING.discard(self)

    @property
    def client(self) -> Any:
        """The ``distributed.Client`` (a local cluster's, once it has started)."""
        self._begin()
        self._started.wait()
        if self._client is None:
            error = self._start_error
            if error is None:
                raise DaskUnavailableError("this Dask executor has been shut down")
            hint = guard_hint() if self._forked is None else ""  # spawned workers
            raise DaskUnavailableError(
                f"the local Dask cluster did not start ({type(error).__name__}: {error}){hint}"
            ) from error
        return self._client

    @property
    def width(self) -> int:
        """Tasks the cluster runs at once: the threads of all its workers.

        A given cluster's is asked of its scheduler at most once every
        :data:`WIDTH_SECONDS` (a batch reads it each time it sends a task: a
        round trip through the scheduler each time took 0.7 s of a 200-file
        coins batch's client, while it held the batch's files back).
        """
        if self._width:
            return self._width
        width, asked = self._asked
        if time.monotonic() - asked >= WIDTH_SECONDS:
            width = max(1, sum(self.client.nthreads().values()))
            self._asked = (width, time.monotonic())
        return width

    @property
    def files_at_once(self) -> int:
        """Files a batch keeps in flight: enough to fill every task of several files that
        may be in flight (:mod:`graphvision.execution.dask_files`)."""
        return self.width * GROUPS_PER_THREAD * FILES_PER_TASK

    def fork_workers(self) -> bool:
        """Fork the local cluster's workers from this process now, when its cluster has not
        started and a fork is safe (a batch, after its first file:
        :mod:`graphvision.execution.dask_fork`); whether it did."""
        with self._begin_lock:
            if self._starter is not None or self._started.is_set() or fork_context() is None:
                return False
            self._forked = ForkedWorkers(*self._shape)
        self._ready.set_running_or_notify_cancel()
        self._begin()
        return True

    def share(self, value: Any) -> Any:
        """``value`` sent to the cluster once and held by every worker; the handle stands for
        it in :meth:`submit`'s arguments (a batch's job, sent once rather than with every
        file: :mod:`graphvision.execution.dask_shared`). A local cluster still starting
        gets it with the first task that reads it."""
        handle = SharedValue(self, value)
        if self._started.is_set():
            handle.sent()
        return handle

    def _sent(self, arg: Any) -> Any:
        """``arg``, or the task that holds it on the cluster when it is a shared value."""
        return arg.sent() if isinstance(arg, SharedValue) else arg

    def warm(self, fn: Callable[..., Any], /, *args: Any) -> list[Future]:
        """Have every worker run ``fn(*args)`` now, as a task of its own (a batch's imports
        and plugin loading, done on each worker while its first file runs in the client);
        a future for each, done as that worker is. A task, not ``Client.run``: that runs in
        the worker's event loop, which stopped answering the scheduler for the seconds it
        took."""
        from distributed import fire_and_forget

        futures: list[Future] = []
        for address in self.client.scheduler_info()["workers"]:
            task = self.client.submit(
                fn, *args, workers=[address], allow_other_workers=True, pure=False
            )
            fire_and_forget(task)
            future = TaskFuture(task)
            future.set_running_or_notify_cancel()
            task.add_done_callback(lambda done, future=future: self._settle(done, future))
            futures.append(future)
        return futures

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future:
        """Run ``fn(*args)`` as a Dask task; a ``concurrent.futures`` future of its result.

        The future's ``task`` (the Dask future) may stand for the result in a
        later ``submit``'s arguments: Dask passes the result from worker to
        worker, without waiting for the client.
        """
        if _is(fn, "run_file_task") and len(args) == 3:  # a batch's file: a few to a task
            return self._files.submit(fn, *args)
        if _is(fn, "warm_worker") and self._forked is not None:  # warm: forked after a file
            return self._ready
        args = tuple(self._sent(arg) for arg in args)
        task = self.client.submit(on_worker, fn, *args, pure=False, retries=self.retries)
        future = TaskFuture(task)
        future.set_running_or_notify_cancel()
        with self._in_flight_lock:
            alone = self._in_flight == 0
            self._in_flight += 1
        future.add_done_callback(self._landed)
        if alone:
            task.add_done_callback(lambda done: self._settle(done, future))
        else:  # the run reports an error as that node's failure
            self.when_done(task, lambda value, error: settle(future, value, error))
        return future

    def when_done(self, task: Any, landed: Landed, running: str = "node") -> None:
        """``landed(result, None)`` or ``landed(None, error)`` on the client's event loop once
        ``task`` is done (:func:`~graphvision.execution.dask_results.fetch_on_loop`)."""
        fetch_on_loop(self.client, task, self._direct, landed, running)

    def result(self, task: Any, running: str = "node") -> Any:
        """A finished Dask task's result, fetched from its worker straight when the workers are
        this process's ``LocalCluster``'s (:func:`~graphvision.execution.dask_fork.direct_gathers`).
        """
        try:
            return task.client.gather(task, direct=self._direct)
        except BaseException as error:
            told = died_on_dask(error, running)
            if told is error:
                raise
            raise told from None

    def _settle(self, task: Any, future: Future) -> None:
        """``future`` takes ``task``'s result or its error (the run reports it as the node's)."""
        try:
            future.set_result(self.result(task))
        except BaseException as error:
            future.set_exception(error)

    def _landed(self, _: Future) -> None:
        with self._in_flight_lock:
            self._in_flight -= 1

    def __enter__(self) -> DaskExecutor:  # ``with``: shut down at the end, as a pool is
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Close the client and the local cluster this executor started (not a given client);
        a local cluster still starting is closed as soon as it has (waited for with
        ``wait``)."""
        self._closing = True
        self._files.close()
        starter = self._starter
        if starter is not None and starter.is_alive():
            if not wait:
                return  # the starting thread closes it (the interpreter's exit waits for it)
            starter.join()
        self._close()

    def _close(self) -> None:
        with self._in_flight_lock:  # once, whoever gets here first
            client, cluster, self._cluster = self._client, self._cluster, None
            if self._owns_client:
                self._client = None
        if self._owns_client and client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
        if self._forked is not None:
            self._forked.close()


_STARTING: weakref.WeakSet[DaskExecutor] = weakref.WeakSet()  # local clusters still starting


@functools.cache  # once, after distributed's own exit hook: exit hooks run last first
def _wait_for_starts_at_exit() -> None:
    atexit.register(_let_clusters_start)


def _let_clusters_start() -> None:
    """At the interpreter's exit, wait for local clusters still starting, so that Dask's exit
    hook closes them whole (a half-started one raised there)."""
    for executor in list(_STARTING):
        if executor._starter is not None:
            executor._starter.join(timeout=60)


def _is(fn: Any, name: str) -> bool:
    """Whether ``fn`` is :mod:`graphvision.execution.file_task`'s function ``name`` (by name:
    that module imports the run, which imports the executors)."""
    module = "graphvision.execution.file_task"
    return getattr(fn, "__module__", None) == module and getattr(fn, "__name__", None) == name


class TaskFuture(Future):
    """A ``concurrent.futures`` future of a Dask task, holding the task (``task``)."""

    def __init__(self, task: Any) -> None:
        super().__init__()
        self.task = task
