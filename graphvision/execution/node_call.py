"""Calling a node function in this process: timed, in a frame named after the node, its
warnings naming it, and a child it forks ended instead of running the graph on."""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from typing import Any

from graphvision.execution import crash_note
from graphvision.execution.crash_note import call_named
from graphvision.execution.node_raised import node_failure, stop_within
from graphvision.execution.warnings import running
from graphvision.nodes.loading import note_plugin_line

__all__ = ["began_before", "call_labelled", "call_node"]


def call_node(
    func: Callable[..., Any], params: dict[str, Any], inputs: dict[str, Any], name: str = ""
) -> tuple[Any, float]:
    """Call a node function; return its result and wall time in seconds.

    A node that forks (``os.fork()``, or a library that does) and whose child
    returns here would have the child go on running the graph (on ``sync`` it
    wrote the output folder a second time; on threads its idle pool kept the
    command's pipes open, so the run never ended): the child is ended here,
    with one line naming the node. The node runs in a frame named after it
    (:mod:`~graphvision.execution.crash_note`: a fault handler's traceback names it). An
    error a local plugin's node raises notes the plugin's line it came from
    (:func:`~graphvision.nodes.loading.note_plugin_line`), for the run's message; one that is
    not an ``Exception`` is the node's failure all the same, unless it is the user's stop
    (:mod:`~graphvision.execution.node_raised`).
    """
    mark = getattr(func, "__graphvision_node__", None)
    op = mark.id if mark is not None else getattr(func, "__qualname__", "")
    label = f"node '{name}' ({op})" if name else f"node {op}"
    return call_labelled(func, {**inputs, **params}, label, op)


_TRAMPOLINES = crash_note._TRAMPOLINES  # the frames named after nodes, made once per label
# crash_note's running nodes and the process it noted its os._exit in (objects it changes in
# place, never rebinds), and the clock and thread id, read per node without a lookup more
_RUNNING, _INSTALLED_IN = crash_note._RUNNING, crash_note._INSTALLED_IN
_clock, _get_ident = time.perf_counter, threading.get_ident

_FORKS = [0]
"""How many forks made this process (``os.register_at_fork``): a forked child's count is
one more than its parent's was when it forked. Read per node instead of ``os.getpid()``,
a system call (1.2 µs here, two per node were a tenth of a trivial node's cost). A child
made by a C library's own ``fork()`` without ``PyOS_AfterFork_Child`` is not counted:
such a child cannot run Python safely anyway."""


def _count_fork() -> None:
    _FORKS[0] += 1


os.register_at_fork(after_in_child=_count_fork)


def call_labelled(
    func: Callable[..., Any], kwargs: dict[str, Any], label: str, op: str
) -> tuple[Any, float]:
    """:func:`call_node` with its arguments merged and its names made (a run makes them once
    per step): ``label`` names the frame, ``op`` the warnings.

    What :func:`~graphvision.execution.crash_note.call_named` does, one call less per node
    (after the first, which installs its ``os._exit`` note through it).
    """
    if not _INSTALLED_IN:
        return _first_call(func, kwargs, label, op)
    forks, ident = _FORKS[0], _get_ident()
    running.op, _RUNNING[ident] = op, label
    trampoline = _TRAMPOLINES.get(label) or crash_note._trampoline(label)
    began = _clock()
    try:
        result = trampoline(func, kwargs)
    except BaseException as error:
        _BEGAN[ident] = began
        note_plugin_line(error, func)
        if (stop := stop_within(error)) is not None and stop is not error:
            raise stop from None  # Ctrl-C, which the node's code turned into another error
        if not isinstance(error, Exception) and (failure := node_failure(error)) is not None:
            raise failure from error  # SystemExit, a BaseException of its own: the node's
        raise
    finally:
        if _FORKS[0] != forks:
            _end_forked_child(op)
        running.op = ""
        _RUNNING.pop(ident, None)
    return result, _clock() - began


_BEGAN: dict[int, float] = {}
"""When the node that last failed in each thread began (:func:`began_before`)."""


def began_before(seconds: float) -> float:
    """When a node that failed began: it ran ``seconds`` until now (``seconds`` < 0: it failed
    in :func:`call_labelled`, in this thread, which noted when it began). The caller then
    reads the clock once per node, not twice."""
    if seconds >= 0:
        return _clock() - seconds
    return _BEGAN.pop(_get_ident(), _clock())


def _first_call(
    func: Callable[..., Any], kwargs: dict[str, Any], label: str, op: str
) -> tuple[Any, float]:
    forks = _FORKS[0]
    running.op = op
    began = time.perf_counter()
    try:
        result = call_named(label, func, kwargs)
    except BaseException as error:
        _BEGAN[_get_ident()] = began
        note_plugin_line(error, func)
        if (stop := stop_within(error)) is not None and stop is not error:
            raise stop from None  # (as above)
        if not isinstance(error, Exception) and (failure := node_failure(error)) is not None:
            raise failure from error
        raise
    finally:
        if _FORKS[0] != forks:
            _end_forked_child(op)
        running.op = ""
    return result, time.perf_counter() - began


def _end_forked_child(op: str) -> None:
    """In a process a node forked that returned into graphvision: say so and exit."""
    os.write(
        2,
        f"graphvision: node op {op} forked a process that returned from the node; the "
        "child may not run the graph and is ended (exit its child itself: os._exit)\n".encode(),
    )
    os._exit(70)  # EX_SOFTWARE
