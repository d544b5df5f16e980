"""Time and memory limits per node: a node over its limit fails alone, naming itself and
the limit (issue 29 item 4).

Where the limits come from, for each node:

* **time**: the node's ``timeout:`` in the pipeline file (``NodeDecl.timeout``) and the
  run's ``node_timeout`` (``--node-timeout``, the ``GRAPHVISION_NODE_TIMEOUT`` environment
  variable), the lower of the two when both are given: a pipeline cannot give itself more
  time than the user allows;
* **memory**: the run's ``node_memory`` (``--node-memory``, ``GRAPHVISION_NODE_MEMORY``),
  on ``processes`` only: what a worker process may allocate while it runs the node, on
  top of what it holds when the node starts (``resource.RLIMIT_AS`` in the worker).

What happens at the limit depends on where the node runs:

``processes``
    The worker ends itself at the limit (a node stuck in C code cannot be stopped any
    other way), leaving a note for the parent, which fails the node with
    :class:`NodeLimitError` and replaces the worker; the other nodes go on. A node
    over its memory limit gets a ``MemoryError`` in its worker and fails the same way.
``threads`` and ``sync``
    A node with a time limit runs on a thread of its own; at the limit the node fails
    and the run goes on without it, but Python cannot stop a thread: the node's code
    goes on running in the background until it returns (its result is dropped), and the
    process does not wait for it when it exits. A memory limit is refused there: a
    process shares one address space between all its nodes.
``dask``
    Limits are refused (Dask's workers are not ours to end).
"""

from __future__ import annotations

import contextlib
import os
import resource
import tempfile
import threading
import uuid
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from contextvars import ContextVar
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from graphvision.compiler.compiled import CompiledGraph
from graphvision.errors import InputError, PipelineError
from graphvision.execution.crash_note import real_exit

__all__ = [
    "MEMORY_VARIABLE",
    "TIMEOUT_VARIABLE",
    "NodeLimitError",
    "NodeLimits",
    "call_in_worker",
    "current_limits",
    "ended_by_limit",
    "node_limits",
    "refuse_declared_limits",
    "start_on_own_thread",
]

TIMEOUT_VARIABLE = "GRAPHVISION_NODE_TIMEOUT"
MEMORY_VARIABLE = "GRAPHVISION_NODE_MEMORY"


class NodeLimitError(RuntimeError):
    """A node ran past its time limit or over its memory limit (it failed alone)."""


@dataclass(frozen=True)
class NodeLimits:
    """The run's limits: ``timeout`` seconds for every node, ``memory`` bytes a worker
    process may allocate while it runs a node (None: no limit)."""

    timeout: float | None = None
    memory: int | None = None

    def seconds_for(self, declared: float | None) -> float | None:
        """A node's time limit: the lower of its own ``timeout:`` and the run's."""
        given = [t for t in (declared, self.timeout) if t is not None]
        return min(given) if given else None

    def worker_call(self, seconds: float | None, label: str) -> tuple[Any, ...]:
        """What to submit before a node's own call on processes: :func:`call_in_worker` and
        its first arguments, a note path of the node's own among them (nothing unlimited)."""
        if seconds is None and self.memory is None:
            return ()
        return (call_in_worker, str(_NOTES / uuid.uuid4().hex), seconds, self.memory, label)

    def check_executor(self, name: str) -> None:
        """Refuse the run's limits where they cannot be kept (see the module docstring; a
        pipeline's own ``timeout:`` on Dask is :func:`refuse_declared_limits`')."""
        if name == "dask" and (self.timeout or self.memory):
            raise ValueError("node time and memory limits apply on sync, threads and processes")
        if self.memory is not None and name != "processes":
            raise ValueError(
                "a node memory limit needs --executor processes (nodes in one process share "
                "its memory)"
            )


_LIMITS: ContextVar[NodeLimits | None] = ContextVar("graphvision_node_limits", default=None)


def _positive(value: Any, what: str, kind: type) -> Any:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
        raise ValueError(f"{what} must be a positive number, got {value!r}")
    return kind(value)


def _from_environment(variable: str, kind: type) -> Any:
    """The limit ``variable`` sets (None unset); an InputError, a user's mistake, naming it
    and its value when it is not a positive number."""
    text = os.environ.get(variable, "")
    try:
        return _positive(kind(float(text)), variable, kind) if text else None
    except (ValueError, OverflowError):
        raise InputError(f"{variable}={text!r} is not a positive number") from None


def current_limits() -> NodeLimits:
    """The limits in force: :func:`node_limits`'s, else the environment's."""
    given = _LIMITS.get()
    if given is not None:
        return given
    timeout = _from_environment(TIMEOUT_VARIABLE, float)
    memory = _from_environment(MEMORY_VARIABLE, int)
    if timeout is None and memory is None:  # (none set: one frozen value, not one per run)
        return _UNLIMITED
    return NodeLimits(timeout, memory)


_UNLIMITED = NodeLimits()


def node_limits(
    timeout: float | None, memory: int | None
) -> contextlib.AbstractContextManager[None]:
    """Within the block, :func:`current_limits` is ``timeout``/``memory`` where given (with
    neither, nothing is entered: no generator made and run per run)."""
    if timeout is None and memory is None:
        return _UNCHANGED
    return _limited(timeout, memory)


_UNCHANGED = contextlib.nullcontext()


@contextlib.contextmanager
def _limited(timeout: float | None, memory: int | None) -> Iterator[None]:
    base = current_limits()
    token = _LIMITS.set(
        NodeLimits(
            _positive(timeout, "node_timeout", float) or base.timeout,
            _positive(memory, "node_memory", int) or base.memory,
        )
    )
    try:
        yield
    finally:
        _LIMITS.reset(token)


def _over_time(label: str, seconds: float) -> str:
    return (
        f"{label} ran past its time limit of {seconds:g} s (the node's timeout:, or --node-timeout)"
    )


# -- threads and sync: a thread of the node's own ------------------------------------------


def start_on_own_thread(
    fn: Callable[..., Any], args: tuple[Any, ...], seconds: float, label: str
) -> Future:
    """Run ``fn(*args)`` on a daemon thread; the future fails with :class:`NodeLimitError`
    after ``seconds`` if it has not finished (the thread is then left to itself)."""
    future: Future = Future()
    future.set_running_or_notify_cancel()
    lock = threading.Lock()

    def settle(result: Any = None, error: BaseException | None = None) -> None:
        with lock:
            if future.done():
                return
            if error is not None:
                future.set_exception(error)
            else:
                future.set_result(result)

    def work() -> None:
        try:
            result = fn(*args)
        except BaseException as error:  # a SystemExit too fails the node alone
            settle(error=error)
        else:
            settle(result)
        finally:
            timer.cancel()

    timer = threading.Timer(
        seconds, lambda: settle(error=NodeLimitError(_over_time(label, seconds)))
    )
    timer.daemon = True
    timer.start()
    threading.Thread(target=work, daemon=True, name=f"graphvision {label}").start()
    return future


# -- processes: the worker ends itself, leaving a note ---------------------------------------

_NOTES = Path(tempfile.gettempdir()) / f"graphvision-limits-{os.getpid()}"
"""Where a worker leaves the note saying why it ended (in the parent's name)."""


def call_in_worker(
    note: str, seconds: float | None, memory: int | None, label: str, fn: Callable, *args: Any
) -> Any:
    """In a worker process: ``fn(*args)`` under the node's limits.

    Memory: ``RLIMIT_AS`` is set to what the worker holds now plus ``memory`` and
    put back afterwards. Time: a watchdog thread writes ``note`` and ends the worker
    at ``seconds`` (the parent reads the note: :func:`ended_by_limit`).
    """
    watchdog = None
    if seconds is not None:
        watchdog = threading.Timer(seconds, _end_worker, (note, _over_time(label, seconds)))
        watchdog.daemon = True
        watchdog.start()
    before = resource.getrlimit(resource.RLIMIT_AS)
    if memory is not None:
        cap = _address_space() + memory
        hard = before[1]
        resource.setrlimit(resource.RLIMIT_AS, (cap if hard < 0 else min(cap, hard), hard))
    try:
        return fn(*args)
    except MemoryError as error:
        if memory is None:
            raise
        raise NodeLimitError(
            f"{label} went over its memory limit of {memory / 2**20:g} MiB (--node-memory): "
            f"{error or 'MemoryError'}"
        ) from None
    finally:
        if watchdog is not None:
            watchdog.cancel()
        if memory is not None:
            resource.setrlimit(resource.RLIMIT_AS, before)


def _address_space() -> int:
    """Bytes of address space this process holds now (``VmSize``)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmSize:"):
            return int(line.split()[1]) * 1024
    return 0  # not Linux: the cap is then ``memory`` itself


def _end_worker(note: str, message: str) -> None:
    """Leave ``message`` at ``note`` for the parent, then end this worker at once."""
    with contextlib.suppress(OSError):
        Path(note).parent.mkdir(mode=0o700, exist_ok=True)
        Path(note).write_text(message)
    real_exit(124)  # as timeout(1) does (no note of the running node: the parent says it)


def ended_by_limit(fn: Callable, args: tuple[Any, ...]) -> NodeLimitError | None:
    """Why the worker running ``fn(*args)`` ended, when a limit ended it (else None)."""
    if fn is not call_in_worker or not args:
        return None
    note = Path(args[0])
    try:
        message = note.read_text()
    except OSError:
        return None
    note.unlink(missing_ok=True)
    with contextlib.suppress(OSError):
        note.parent.rmdir()  # the last note read
    return NodeLimitError(f"{message}; its worker process was ended and replaced")


def refuse_declared_limits(compiled: CompiledGraph, executor: str) -> None:
    """A ``timeout:`` in the pipeline on Dask (whose workers are not ours to end): one
    problem per node, at its line, before anything runs."""
    if executor != "dask":
        return
    graph = compiled.graph
    problems = [
        graph.problem(
            f"nodes.{name}.timeout",
            "node time limits apply on sync, threads and processes, not dask "
            "(remove it or choose another --executor)",
        )
        for name, node in graph.nodes.items()
        if node.timeout is not None
    ]
    if problems:
        raise PipelineError(problems, graph.source)
