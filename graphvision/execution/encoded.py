"""Handing a node to an executor of other processes: its inputs encoded in their port
types' arrays, or the tasks of the nodes that make them (a chaining executor, such as
Dask's), after what the node's limits put first."""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from graphvision.compiler.compiled import Step
from graphvision.execution.executors import Executor, call_node_encoded
from graphvision.values.ports import Placed

__all__ = ["submit_encoded"]


def submit_encoded(
    executor: Executor,
    call: Callable[[], tuple[Any, ...]],
    step: Step,
    values: dict[tuple[str, str], Any],
    in_flight: dict[str, Any],
) -> Future:
    """Hand ``step`` to an executor of other processes: its inputs encoded (or, submitted
    ahead of them, their producers' tasks from ``in_flight``), after what ``call()`` puts
    first (the node's limits); a node defined in ``__main__`` is refused."""
    if step.spec.ref.module == "__main__" and not step.spec.ref.path:
        refused: Future = Future()
        refused.set_exception(
            RuntimeError(
                "the node is defined in __main__ (a script or a notebook), which "
                "worker processes cannot import: put it in a module file and load "
                "that with gv.discover([path]) or --plugins PATH, or use threads"
            )
        )
        return refused
    payload, upstream = {}, {}
    for port, source in step.inputs.items():
        if source in values:  # with where each array lies (frozen there at the same offsets)
            kind = step.spec.inputs[port].type
            arrays, meta = kind.encode(values[source])
            payload[port] = (kind, Placed.of(arrays), meta)
        else:  # submitted ahead: the producer's task stands for its result
            upstream[port] = (in_flight[source[0]].task, source[1])
    return executor.submit(
        *call(),
        call_node_encoded,
        step.spec.ref,
        step.params,
        payload,
        step.outputs,
        step.spec.output_tuple is not None,
        upstream,
    )
