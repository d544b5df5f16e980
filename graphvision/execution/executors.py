"""Executors: where node functions run.

An executor is anything with ``submit(fn, *args) -> Future`` and
``shutdown()``, so ``concurrent.futures`` pools fit as they are. Choose one
by name with :func:`make_executor`:

``sync``
    In the calling thread, one node at a time (debugging, profiling).
``threads`` (default)
    A thread pool; numpy and scipy release the GIL in their kernels.
``processes``
    A process pool, its workers forked from a server that has imported
    graphvision and the plugins (:mod:`~graphvision.execution.worker_start`).
    The node function travels as a :class:`~graphvision.nodes.node.FunctionRef`
    (imported by name in the worker, local plugin files by path); values travel in
    their port type's encoding (named arrays and a JSON header), never pickled.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Protocol

from graphvision.execution.batch_guard import guard_hint
from graphvision.execution.limits import ended_by_limit
from graphvision.execution.node_call import began_before, call_labelled, call_node
from graphvision.execution.node_imports import import_ahead
from graphvision.execution.warnings import show_warning
from graphvision.execution.worker_start import (
    ClientStdio,
    context,
    fork_context,
    process_pool,
    start_server,
)
from graphvision.nodes.spec import FunctionRef
from graphvision.values.ports import PortType, freeze_all

__all__ = [
    "EXECUTORS",
    "NODE_ERRORS",
    "Executor",
    "SyncExecutor",
    "WorkerDiedError",
    "began_before",
    "call_labelled",
    "call_node",
    "call_node_encoded",
    "chains_tasks",
    "encodes_values",
    "executor_name",
    "executor_width",
    "make_executor",
]

EXECUTORS: tuple[str, ...] = ("sync", "threads", "processes", "dask")
# What a node may raise that fails that node alone: exceptions, and the exits and generator
# closings a node's code can raise by mistake (KeyboardInterrupt stays the user's Ctrl-C).
NODE_ERRORS: tuple[type[BaseException], ...] = (Exception, SystemExit, GeneratorExit)


class Executor(Protocol):
    """What the run needs of an executor: ``submit``, ``shutdown``, and its transport.

    ``encodes_values`` is the transport: True when nodes run in other
    processes, so that a node travels as a :class:`FunctionRef` and values in
    their port type's array encoding (:func:`call_node_encoded`); False when
    they run in this process and get the values themselves (:func:`call_node`).

    An executor may also declare ``chains_tasks = True`` (read with
    :func:`chains_tasks`): each future it returns then has a ``task``, a handle
    that its ``submit`` accepts inside the arguments in place of the task's
    result, so a node can be submitted before its inputs reach this process
    (the Dask executor; a chain then runs at the cluster's pace, not at that of
    a round trip through the client per node).
    """

    encodes_values: bool

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future: ...

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None: ...


class _Done(Future):
    """A future that is done when it is made: no lock, no condition, callbacks run at once.

    ``concurrent.futures.Future`` pays for the thread synchronisation it
    offers; a result computed in the calling thread needs none of it, and on a
    chain of tiny nodes that cost is a large part of the engine's per-node time.
    """

    def __init__(self, result: Any = None, error: BaseException | None = None) -> None:
        self._value, self._error = result, error

    def done(self) -> bool:
        return True

    def cancelled(self) -> bool:
        return False

    def result(self, timeout: float | None = None) -> Any:
        if self._error is not None:
            raise self._error
        return self._value

    def exception(self, timeout: float | None = None) -> BaseException | None:
        return self._error

    def add_done_callback(self, fn: Callable[[Future], object]) -> None:
        fn(self)


class SyncExecutor:
    """Runs each task at once in the calling thread and returns a done future."""

    encodes_values = False
    width = 1
    name = "sync"
    in_calling_thread = True  # the run calls quick nodes itself, without a future

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future:
        try:
            return _Done(fn(*args))
        except NODE_ERRORS as error:  # the scheduler reports it as a node failure
            return _Done(error=error)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        return None


class _Threads(ThreadPoolExecutor):
    encodes_values = False
    name = "threads"

    @property
    def width(self) -> int:
        """Tasks run at once."""
        return int(self._max_workers)


_DIED = "the worker process running this node died (killed, or out of memory)"


class WorkerDiedError(RuntimeError):
    """The worker process running a node died (killed, out of memory), also on the retry."""


def _died(how: str) -> WorkerDiedError:
    """:class:`WorkerDiedError` saying ``how``, naming the main guard when the script lacks
    it: the retry's worker comes from the fork server and imports the script first."""
    return WorkerDiedError(f"{_DIED}, {how}{guard_hint()}")


class _Processes:
    """A process pool that survives a dying worker.

    When a worker dies, ``concurrent.futures`` breaks the whole pool and fails
    every node running in it. Here the pool is replaced and each node whose
    future broke runs again, once, in a worker of its own: a node that kills
    its worker again fails (it is the culprit), the others complete. Workers ignore Ctrl-C (the
    parent handles it) and exit when their parent process is gone, even after
    ``kill -9``.
    """

    encodes_values = True
    name = "processes"
    files_per_task = 8  # files a batch's lane sends as one task (execution.batch_lanes)

    def __init__(self, workers: int) -> None:
        self._workers = workers
        self.width = workers
        self._lock = threading.Lock()
        start_server(start=False)  # the server imports graphvision (a batch adds its plugins)
        self._pool = self._new_pool()

    def _new_pool(self, workers: int = 0) -> ProcessPoolExecutor:
        setup = (dict(os.environ), ClientStdio())
        return process_pool(workers or self._workers, context(), _worker_setup, setup)

    def preload(self, modules: list[str]) -> None:
        """Start the workers' server in the background, importing ``modules`` too (the
        plugin modules a batch uses) when it has not started yet."""
        start_server(modules)

    def fork_workers(self) -> bool:
        """Have the workers be forks of this process, all started at the next task (when it
        is safe now: :func:`~graphvision.execution.worker_start.fork_context`; a pool made
        again after a worker died uses the server); False when not."""
        forked = fork_context()
        if forked is None:
            return False
        setup = (dict(os.environ), ClientStdio())
        with self._lock:
            old, self._pool = (
                self._pool,
                process_pool(self._workers, forked, _worker_setup, setup),
            )
        old.shutdown(wait=False)
        return True

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future:
        outer: Future = Future()
        outer.set_running_or_notify_cancel()
        pool = self._pool
        try:
            inner = pool.submit(fn, *args)
        except BrokenProcessPool:
            pool = self._replace(pool)
            inner = pool.submit(fn, *args)
        except (OSError, EOFError) as error:  # no worker starts (the fork server killed, say)
            outer.set_exception(WorkerDiedError(f"no worker process could start ({error!r})"))
            return outer

        def settle(done: Future) -> None:
            if isinstance(done.exception(), BrokenProcessPool):
                self._replace(pool)
                ended = ended_by_limit(fn, args)  # a node past its limit is not retried
                if ended is not None:
                    outer.set_exception(ended)
                elif getattr(fn, "settles_its_files", False):  # the caller retries each file
                    outer.set_exception(_died("running a task of several files"))
                else:
                    self._retry_alone(outer, fn, args)
            else:
                _copy(done, outer)

        inner.add_done_callback(settle)
        return outer

    def _retry_alone(self, outer: Future, fn: Callable[..., Any], args: tuple) -> None:
        """Run a node whose pool broke again, in a worker of its own.

        The pool breaks for every node it was running when one worker died, so
        the retry is isolated: a node that kills its worker again is the one
        at fault and fails; the others complete.
        """
        alone = self._new_pool(workers=1)
        try:
            retry = alone.submit(fn, *args)
        except Exception as error:  # no worker starts (the fork server killed, say): say so
            alone.shutdown(wait=False)
            why = f"{type(error).__name__}: {error}"
            outer.set_exception(_died(f"and no worker could start again ({why})"))
            return

        def settle(done: Future) -> None:
            alone.shutdown(wait=False)
            if isinstance(done.exception(), BrokenProcessPool):
                outer.set_exception(
                    ended_by_limit(fn, args) or _died("and again when retried alone")
                )
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
        self._pool.shutdown(wait=wait, cancel_futures=cancel_futures)


def _copy(source: Future, target: Future) -> None:
    error = source.exception()
    if error is not None:
        target.set_exception(error)
    else:
        target.set_result(source.result())


def _worker_setup(environment: dict[str, str], _: ClientStdio) -> None:
    """In each worker: the client's environment variables, standard output and error (a
    worker forked from the server has the server's), leave Ctrl-C to the client, end on
    SIGTERM as a worker does (a fork of the client carries its handler, which stopped the
    whole batch when one worker was sent SIGTERM), exit when
    the client is gone (even after ``kill -9``), and print warnings as the command line
    does (one line naming the node)."""
    import warnings

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


def executor_name(executor: Any) -> str:
    """What records call the executor: ``sync``, ``threads``, ``processes``, ``dask``, or the
    class name of one that does not say."""
    if isinstance(executor, str):
        return executor
    return str(getattr(executor, "name", "") or type(executor).__name__)


def executor_width(executor: Any) -> int:
    """How many tasks the executor runs at once (its ``width``; a plain thread pool's
    ``max_workers``; 1 when it does not say)."""
    width = getattr(executor, "width", None) or getattr(executor, "_max_workers", None) or 1
    return max(1, int(width))


def chains_tasks(executor: Any) -> bool:
    """Whether the executor takes its futures' ``task`` as inputs (see :class:`Executor`)."""
    return bool(getattr(executor, "chains_tasks", False))


def encodes_values(executor: Any) -> bool:
    """The executor's transport (see :class:`Executor`); a plain ``concurrent.futures``
    thread pool, which does not declare one, runs in this process."""
    return bool(getattr(executor, "encodes_values", False))


def make_executor(name: str = "threads", workers: int | None = None) -> Executor:
    """An executor by name: ``sync``, ``threads``, ``processes`` or ``dask`` (a local cluster)."""
    if name == "dask":
        from graphvision.execution.dask import DaskExecutor

        return DaskExecutor(workers=workers or 2)
    if name == "sync":
        return SyncExecutor()
    workers = workers or os.cpu_count() or 1  # (a file read: 14 µs, not for ``sync``)
    if name == "threads":
        return _Threads(max_workers=workers, thread_name_prefix="graphvision")
    if name == "processes":
        return _Processes(workers)
    raise ValueError(f"unknown executor '{name}'; choose one of {', '.join(EXECUTORS)}")


Payload = dict[str, tuple[type[PortType], dict, dict]]


def call_node_encoded(
    ref: FunctionRef,
    params: dict[str, Any],
    inputs: Payload,
    outputs: dict[str, type[PortType]],
    output_tuple: bool,
    upstream: dict[str, tuple[tuple[Payload, float], str]] | None = None,
) -> tuple[Payload, float]:
    """:func:`call_node` for another process: inputs and outputs travel encoded.

    ``upstream`` holds the inputs submitted before they were computed: by
    port, the producing task's result (what this function returned there) and
    the producer's output port. A chaining executor (:func:`chains_tasks`)
    puts the result there.
    """
    func = ref.resolve()
    import_ahead([func])  # its imports one thread at a time (a Dask worker's threads)
    if upstream:
        sent = {port: produced[source] for port, ((produced, _), source) in upstream.items()}
        inputs = {**inputs, **sent}
    values = {  # read-only for good, as under threads
        port: kind.decode(freeze_all(arrays), meta) for port, (kind, arrays, meta) in inputs.items()
    }
    result, seconds = call_node(func, params, values)
    parts = dict(zip(outputs, result, strict=True)) if output_tuple else {"out": result}
    encoded: Payload = {}
    for port, value in parts.items():
        kind = outputs[port]
        arrays, meta = kind.encode(kind.validate(value))
        encoded[port] = (kind, arrays, meta)
    return encoded, seconds
