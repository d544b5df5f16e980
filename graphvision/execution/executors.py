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
    graphvision and the plugins (:mod:`~graphvision.execution.worker_start`), that survives
    a dying worker (:mod:`~graphvision.execution.process_executor`).
    The node function travels as a :class:`~graphvision.nodes.node.FunctionRef`
    (imported by name in the worker, local plugin files by path); values travel in
    their port type's encoding (named arrays and a JSON header), never pickled.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Protocol

from graphvision.execution.node_call import began_before, call_labelled, call_node
from graphvision.execution.node_imports import import_ahead
from graphvision.execution.process_executor import ProcessExecutor
from graphvision.execution.worker_died import WorkerDiedError
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
        return ProcessExecutor(workers)
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
    puts the result there. What the node raises goes back as the executor sends what a
    task raises: pickled with its copy (:func:`~graphvision.execution.sendable.sent_back`).
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
