"""Executors: where node functions run.

An executor is anything with ``submit(fn, *args) -> Future`` and
``shutdown()``, so ``concurrent.futures`` pools fit as they are. Choose one
by name with :func:`make_executor`:

``sync``
    In the calling thread, one node at a time (debugging, profiling).
``threads`` (default)
    A thread pool; numpy and scipy release the GIL in their kernels.
``processes``
    A process pool (``spawn``). The node function travels as a
    :class:`~graphvision._node.FunctionRef` (imported by name in the worker,
    local plugin files by path) and values travel in their port type's
    encoding (named arrays and a JSON header), never as pickled objects.
"""

from __future__ import annotations

import multiprocessing
import os
import time
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from typing import Any, Protocol

from ._node import FunctionRef
from ._ports import PortType, freeze

__all__ = [
    "EXECUTORS",
    "Executor",
    "SyncExecutor",
    "call_node",
    "call_node_encoded",
    "make_executor",
]

EXECUTORS: tuple[str, ...] = ("sync", "threads", "processes")


class Executor(Protocol):
    """The one method the scheduler needs (plus shutdown)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future: ...

    def shutdown(self, wait: bool = True) -> None: ...


class SyncExecutor:
    """Runs each task at once in the calling thread and returns a done future."""

    encodes_values = False

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args))
        except BaseException as error:  # the scheduler reports it as a node failure
            future.set_exception(error)
        return future

    def shutdown(self, wait: bool = True) -> None:
        return None


class _Threads(ThreadPoolExecutor):
    encodes_values = False


class _Processes(ProcessPoolExecutor):
    encodes_values = True


def make_executor(name: str = "threads", workers: int | None = None) -> Executor:
    """An executor by name: ``sync``, ``threads`` or ``processes``."""
    workers = workers or os.cpu_count() or 1
    if name == "sync":
        return SyncExecutor()
    if name == "threads":
        return _Threads(max_workers=workers, thread_name_prefix="graphvision")
    if name == "processes":
        return _Processes(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    raise ValueError(f"unknown executor '{name}'; choose one of {', '.join(EXECUTORS)}")


def call_node(
    func: Callable[..., Any], params: dict[str, Any], inputs: dict[str, Any]
) -> tuple[Any, float]:
    """Call a node function; return its result and wall time in seconds."""
    began = time.perf_counter()
    result = func(**inputs, **params)
    return result, time.perf_counter() - began


Payload = dict[str, tuple[type[PortType], dict, dict]]


def call_node_encoded(
    ref: FunctionRef,
    params: dict[str, Any],
    inputs: Payload,
    outputs: dict[str, type[PortType]],
    output_tuple: bool,
) -> tuple[Payload, float]:
    """:func:`call_node` for another process: inputs and outputs travel encoded."""
    func = ref.resolve()
    values = {  # read-only for good, as under threads
        port: kind.decode({name: freeze(a) for name, a in arrays.items()}, meta)
        for port, (kind, arrays, meta) in inputs.items()
    }
    result, seconds = call_node(func, params, values)
    parts = dict(zip(outputs, result, strict=True)) if output_tuple else {"out": result}
    encoded: Payload = {}
    for port, value in parts.items():
        kind = outputs[port]
        arrays, meta = kind.encode(kind.validate(value))
        encoded[port] = (kind, arrays, meta)
    return encoded, seconds
