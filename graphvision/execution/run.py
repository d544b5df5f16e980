r"""Running a graph: inputs, keys, cache plan, execution, record.

:func:`run` does, in order:

1. compile the graph (every problem reported at once, before anything runs);
2. prune it to what the requested outputs need;
3. resolve graph inputs (literals, paths, ``sample:NAME``...) and key them by
   content;
4. chain the Merkle keys of every node output without computing anything;
5. plan from the outputs backwards: an output found in the cache is loaded
   and its producers are not visited, so a fully cached re-run reads only the
   requested outputs; everything else is computed;
6. import, in this thread, what the computed nodes import inside their bodies when
   they run in this process (two threads importing one package at once can fail:
   :mod:`~graphvision.execution.node_imports`); hand the computed steps to
   :func:`~graphvision.execution.scheduler.run_tasks` with the chosen executor,
   validating, freezing and caching each result, and releasing each intermediate
   value once its last consumer has run.

Hooks (:class:`RunHooks`) observe it; the run record is always produced.

Each node of the run moves through these states (``NodeRecord.status``)::

    (planned) --cache hit--> cached
        |
        +--only values loaded from the cache read it--> unneeded
        |
        +--> pending --started by the scheduler--> running --> computed
                |                                        \--> failed
                +--an upstream node failed--> skipped
                +--the run was interrupted--> pending (stays)

(``running`` is known to the scheduler and the hooks, not written in the record.) The
state lives in one dataclass, ``RunState``; :func:`plan_steps` (a function of the graph,
the keys and the cache, changing nothing) decides cached or pending, ``RunState.plan``
records its decision, ``start`` hands a pending node to the executor (encoded values for
other processes, the values themselves in this one; to an executor that chains tasks,
such as Dask's, as soon as the nodes it reads are submitted, their tasks standing for
their values), ``finish`` validates, freezes, stores and releases, and the scheduler
(:func:`~graphvision.execution.scheduler.run_tasks`) only orders them.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from collections.abc import Set as AbstractSet
from typing import Any

from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph, Schedule, compile_graph
from graphvision.errors import RunError, UnknownNameError
from graphvision.execution.arguments import (
    checked_run_arguments,
    input_values,
    refuse_unknown_inputs,
)
from graphvision.execution.arguments import given_inputs as _given_inputs
from graphvision.execution.arguments import wanted_outputs as _wanted_outputs
from graphvision.execution.blas import BlasLimit
from graphvision.execution.executors import (
    Executor,
    encodes_values,
    executor_name,
    executor_width,
    make_executor,
)
from graphvision.execution.heap import keep_freed_memory
from graphvision.execution.limits import (
    NodeLimits,
    current_limits,
    node_limits,
    refuse_declared_limits,
)
from graphvision.execution.node_imports import import_ahead_of
from graphvision.execution.peak_memory import check_peak_memory, running_at_once
from graphvision.execution.plan import referenced_inputs as _referenced_inputs
from graphvision.execution.provenance import describe_run
from graphvision.execution.record import RunHooks, RunRecord, RunResult
from graphvision.execution.scheduler import EVERY_TASK, run_tasks
from graphvision.execution.state import RunState
from graphvision.execution.truth import outputs_with_truth
from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry
from graphvision.values.budget import pixel_budget

__all__ = ["run"]


def run(
    graph: Graph | CompiledGraph,
    registry: Registry | None = None,
    *,
    inputs: dict[str, Any] | None = None,
    outputs: Sequence[str] | None = None,
    overrides: dict[str, Any] | None = None,
    executor: str | Executor = "threads",
    workers: int | None = None,
    cache: Cache | None = None,
    keep_going: bool = False,
    hooks: Sequence[RunHooks] = (),
    keep_intermediates: bool = False,
    max_pixels: int | None = None,
    node_timeout: float | None = None,
    node_memory: int | None = None,
    max_memory: int | None = None,
    backends: Sequence[str] | str | None = None,
) -> RunResult:
    """Run a pipeline and return its outputs and run record.

    Parameters
    ----------
    graph : Graph or CompiledGraph
        The pipeline (validated here if it is a Graph).
    registry : Registry, optional
        Defaults to the installed plugins plus the graph's ``plugins:``.
    inputs : dict, optional
        Values of graph inputs: arrays, scalars, or strings (paths, ``sample:NAME``).
    outputs : sequence of str, optional
        The outputs to produce (default: all); only what they need runs.
    overrides : dict, optional
        ``{"node.param": value, "params.name": value}`` applied before validation.
    executor : {"threads", "sync", "processes"} or Executor
        Where nodes run. An executor instance is used and not shut down.
    cache : Cache, optional
        Where results are looked up and stored; None disables caching.
    keep_going : bool
        After a failure, still run every branch that does not depend on it.
    hooks : sequence of RunHooks
        Observers of the run.
    keep_intermediates : bool
        Keep every node output of the run in ``result.intermediates`` (instead
        of dropping each after its last reader), e.g. to look at them in the report.
    max_pixels : int, optional
        The pixel budget of every image and array the run reads (default: the
        ``GRAPHVISION_MAX_PIXELS`` environment variable, else 100 megapixels);
        a file declaring more is refused before it is decoded.
    node_timeout : float, optional
        Seconds any node may run (default: ``GRAPHVISION_NODE_TIMEOUT``); a node's own
        ``timeout:`` lower than this applies to it. A node past its limit fails alone.
    node_memory : int, optional
        Bytes a worker process may allocate while it runs a node (``executor="processes"``
        only; default: ``GRAPHVISION_NODE_MEMORY``). See :mod:`graphvision.execution.limits`.
    max_memory : int, optional
        Bytes the run may take (default: ``GRAPHVISION_MAX_MEMORY``, else the memory
        available): a run whose peak, estimated from its inputs' shapes before it
        starts, exceeds it is refused (:mod:`graphvision.execution.peak_memory`).
    backends : sequence of str, optional
        The backend lookup order (``["opencv", "numpy"]`` or ``"opencv,numpy"``): each
        node runs the first implementation of its op found along it (a node's
        ``backend:`` pins one). None takes the pipeline's ``backends:``, else the
        reference, ``numpy``. A CompiledGraph is compiled again for another order.

    Raises
    ------
    PipelineError
        The graph is invalid (nothing ran).
    InputError
        A graph input could not be resolved, or the run would not fit in memory
        (nothing ran).
    RunError
        Nodes failed; ``error.failures`` names them, ``error.result`` holds
        the outputs that were produced and the record.
    """
    graph, inputs, outputs, overrides, limits = checked_run_arguments(
        graph, inputs, outputs, overrides, (cache, executor, workers), max_pixels, max_memory
    )
    limit = BlasLimit()  # one BLAS thread while nodes run here (see graphvision.execution.blas)
    if _runs_here(executor):  # the memory nodes free here is reused without page faults
        keep_freed_memory()  # (execution.heap)
    try:
        return _run(
            graph, registry, inputs, outputs, overrides, executor, workers, cache, keep_going,
            hooks, keep_intermediates, max_pixels, node_timeout, node_memory, max_memory,
            backends, (limit, limits),
        )  # fmt: skip
    finally:
        limit.release()  # BLAS has its threads back when the run returns


def _run(
    graph: Graph | CompiledGraph,
    registry: Registry | None,
    inputs: dict[str, Any],
    outputs: list[str] | None,
    overrides: dict[str, Any],
    executor: str | Executor,
    workers: int | None,
    cache: Cache | None,
    keep_going: bool,
    hooks: Sequence[RunHooks],
    keep_intermediates: bool,
    max_pixels: int | None,
    node_timeout: float | None,
    node_memory: int | None,
    max_memory: int | None,
    backends: Sequence[str] | str | None,
    held: tuple[BlasLimit, NodeLimits],
) -> RunResult:
    """:func:`run` after its arguments are checked; ``held``: the BLAS limit (released by the
    caller) and the node limits the environment sets, as read by the check."""
    limit, limits = held
    compiled, registry = _compiled(graph, registry, inputs, overrides, backends)
    wanted, schedule = _wanted_and_schedule(compiled, outputs, inputs)
    given = _given_inputs(compiled, schedule, inputs)
    reference_keys = _referenced_inputs(compiled, given, registry)
    with pixel_budget(max_pixels), node_limits(node_timeout, node_memory):
        where = executor_name(executor)
        refuse_declared_limits(compiled, where)
        if node_timeout is not None or node_memory is not None:  # (else as read by the check)
            limits = current_limits()
        limits.check_executor(where)  # (read once: the state takes them)
        values = input_values(compiled, given, inputs, reference_keys, registry)
        width = running_at_once(executor, workers)
        check_peak_memory(compiled, schedule, values, width, max_memory)
        state = _execute(
            compiled, values, schedule, wanted, cache, executor, workers, keep_going, hooks,
            keep_intermediates, reference_keys, limit, limits,
        )  # fmt: skip
    describe_run(state.record, compiled, registry, given, state.keys, overrides)
    result = state.result(wanted)
    if state.failures:
        failure = RunError(state.failures, state.record)
        failure.result = result  # type: ignore[attr-defined]  # read by callers as error.result
        raise failure
    return result


def _wanted_and_schedule(
    compiled: CompiledGraph, outputs: list[str] | None, inputs: dict[str, Any]
) -> tuple[list[str], Schedule]:
    """The outputs the run produces (each name checked, those whose ground truth is missing
    left out) and what computing them involves; every output and the schedule made once per
    compiled graph when no output is named, no input given is unknown and no input is the
    truth of another (the checks then have nothing to say)."""
    every = outputs is None and not compiled.truth_marks  # (inputs: a dict's keys, in C)
    if every and inputs.keys() <= compiled.input_types.keys():
        return list(compiled.outputs), compiled.full_schedule
    wanted = _wanted_outputs(compiled, outputs, inputs)
    wanted = outputs_with_truth(compiled, wanted, set(inputs), asked=outputs is not None)
    return wanted, compiled.schedule_for(wanted)


def _runs_here(executor: str | Executor) -> bool:
    """Whether the executor runs nodes in this process."""
    if isinstance(executor, str):
        return executor in ("sync", "threads")
    return not encodes_values(executor)


def _compiled(
    graph: Graph | CompiledGraph,
    registry: Registry | None,
    inputs: dict[str, Any],
    overrides: dict[str, Any],
    backends: Sequence[str] | str | None = None,
) -> tuple[CompiledGraph, Registry]:
    """The graph, overrides applied, compiled (step 1); the registry it was checked against."""
    if isinstance(graph, CompiledGraph):
        if not overrides and backends is None:
            return graph, registry or _discover_for(graph.graph)
        graph = graph.graph  # overrides change parameters, an order the implementations
    if backends is not None:  # the run's order replaces the file's
        graph = graph.with_backends(backends)
    registry = registry or _discover_for(graph)
    if overrides:
        try:
            graph = graph.with_overrides(overrides)
        except KeyError as error:
            raise UnknownNameError(str(error.args[0])) from None
    refuse_unknown_inputs(inputs, graph.inputs)  # (named before an input it lacks)
    return compile_graph(graph, registry, provided=set(inputs)), registry


def _discover_for(graph: Graph) -> Registry:
    from graphvision.nodes.plugins import discover_for, warn_of_failed_plugins  # (for a run)

    registry = discover_for(graph)
    warn_of_failed_plugins(registry)
    return registry


def _execute(
    compiled: CompiledGraph,
    values: dict[str, Any],
    schedule: Schedule,
    wanted: list[str],
    cache: Cache | None,
    executor: str | Executor,
    workers: int | None,
    keep_going: bool,
    hooks: Sequence[RunHooks],
    keep_intermediates: bool = False,
    reference_keys: dict[str, str] | None = None,
    limit: BlasLimit | None = None,
    limits: NodeLimits | None = None,
) -> RunState:
    """Steps 4 to 6: key, plan, schedule; the run's state, with its record, whatever happens.

    An executor made here is shut down here: after the run, or at once
    (without waiting for running nodes) when the run is interrupted. BLAS runs on one
    thread from the first node to the last (``limit``; lifted after them, and for sure by
    the caller).
    """
    limit = limit or BlasLimit()
    own = isinstance(executor, str)
    pool = make_executor(executor, workers) if isinstance(executor, str) else executor
    state = RunState(
        compiled,
        cache,
        pool,
        hooks,
        RunRecord(compiled.graph.name, executor_name(pool)),
        limits=limits or current_limits(),
    )
    began, failed = time.perf_counter(), True
    try:
        state.keep_intermediates = keep_intermediates
        state.key_inputs(values, reference_keys or {})
        state.key_steps(schedule.steps)
        sources = list(map(compiled.outputs.__getitem__, wanted))
        if keep_intermediates:  # every value of the run, loaded from the cache if it is there
            sources += [(n, port) for n in schedule.steps for port in compiled.steps[n].outputs]
        compute = state.plan(schedule.steps, sources)
        dependencies = state.prepare(compute, sources, schedule)
        for hook in hooks:
            hook.run_started(pipeline=compiled.graph.name, steps=compute)
        if not state.encoded:  # nodes run in this process: what they import, first, here
            import_ahead_of(compiled.steps, compute)
        skipped = _run_steps(state, schedule, dependencies, compute, keep_going, limit)
        _mark_skipped(state, skipped, hooks)
        failed = bool(state.failures)
    except BaseException:  # Ctrl-C, or a bug: do not wait for the nodes still running
        if own:
            pool.shutdown(wait=False, cancel_futures=True)
            own = False
        raise
    finally:
        if own:
            pool.shutdown(wait=True)
        state.record.seconds = time.perf_counter() - began
        state.record.nodes = state.records()
        for hook in hooks:
            hook.run_finished(record=state.record, failed=failed)
    return state


def _run_steps(
    state: RunState,
    schedule: Schedule,
    dependencies: Mapping[str, AbstractSet[str]],
    compute: list[str],
    keep_going: bool,
    limit: BlasLimit,
) -> list[str]:
    """Step 6: the steps to compute through the scheduler; the steps skipped."""
    here = not state.encoded  # nodes run in this process: some may run in this thread
    # one BLAS thread while nodes run here, so a node's bits do not depend on its
    # neighbours (worker processes hold it for good; see graphvision.execution.blas)
    if here and compute:
        limit.hold()
    try:
        return run_tasks(
            dependencies,
            state.start,
            state.finish,
            keep_going=keep_going,
            run_here=state.run_here if here else None,
            quick=_quick(state) if here else None,
            limit=2 * executor_width(state.executor) if here else None,
            ahead=state.chained,
            counted=(schedule.waiting, schedule.dependents)
            if dependencies is schedule.dependencies
            else None,
            quick_ops=(state.compiled.step_ops, state.quick_ops)
            if here and not state.inline and not state.timed
            else None,
        )
    finally:
        limit.release()


def _quick(state: RunState) -> Callable[[str], bool]:
    """Which nodes run in this thread: all of them on ``sync`` without time limits."""
    return EVERY_TASK if state.inline and not state.timed else state.is_quick


def _mark_skipped(state: RunState, skipped: list[str], hooks: Sequence[RunHooks]) -> None:
    """Nodes downstream of a failure are skipped; one sent ahead (Dask) had its start
    reported, so its end is too."""
    for step in skipped:
        node = state.record_of(state.compiled.steps[step], "skipped")
        if step in state.started:
            for hook in hooks:
                hook.node_finished(name=step, op=node.op, status="skipped", seconds=0.0)
