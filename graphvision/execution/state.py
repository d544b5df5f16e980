r"""The state of one run (``RunState``): keys, plan, hand-out, finish.

:func:`run` does, in order:

1. compile the graph (every problem reported at once, before anything runs);
2. prune it to what the requested outputs need;
3. resolve graph inputs (literals, paths, ``sample:NAME``...) and key them by
   content;
4. chain the Merkle keys of every node output without computing anything;
5. plan from the outputs backwards: an output found in the cache is loaded
   and its producers are not visited, so a fully cached re-run reads only the
   requested outputs; everything else is computed;
6. hand the computed steps to :func:`~graphvision.execution.scheduler.run_tasks` with
   the chosen executor, validating, freezing and caching each result, and
   releasing each intermediate value once its last consumer has run.

Hooks (:class:`RunHooks`) observe it; the run record is always produced.

Each node of the run moves through these states (``NodeRecord.status``)::

    (planned) --cache hit--> cached
        |
        +--> pending --started by the scheduler--> running --> computed
                |                                        \--> failed
                +--an upstream node failed--> skipped
                +--the run was interrupted--> pending (stays)

(``running`` is known to the scheduler and the hooks, not written in the
record.) The state lives in one dataclass, ``RunState``; :func:`plan_steps` (a function
of the graph, the keys and the cache, changing nothing) decides cached or pending,
``RunState.plan`` records its decision, ``start`` hands a pending node to the executor
(encoded values for other processes, the values themselves in this one; to an
executor that chains tasks, such as Dask's, as soon as the nodes it reads are
submitted, their tasks standing for their values),
``finish`` validates, freezes, stores and releases, and the scheduler
(:func:`~graphvision.execution.scheduler.run_tasks`) only orders them.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from collections.abc import Set as AbstractSet
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any

from graphvision.cache.keys import content_key
from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph, Schedule, Step
from graphvision.errors import (
    GraphvisionError,
    NodeExecutionError,
    PortValueError,
)
from graphvision.execution.executors import (
    NODE_ERRORS,
    Executor,
    call_labelled,
    call_node,
    call_node_encoded,
    chains_tasks,
    encodes_values,
)
from graphvision.execution.inputs import freeze_value, value_bytes
from graphvision.execution.limits import current_limits, start_on_own_thread
from graphvision.execution.plan import chain_keys, plan_steps
from graphvision.execution.record import NodeRecord, RunHooks, RunRecord, RunResult
from graphvision.values.scalars import _ScalarPort

__all__ = ["RunState"]

# About what handing a node to a thread and taking its result back costs (measured on
# a fan-out of trivial nodes): a node faster than this gains nothing from a thread.
_QUICK_SECONDS = 25e-6


@dataclass(eq=False)
class RunState:
    """The whole state of one run, in one place (see the module docstring for its machine).

    ``values`` holds graph inputs and node outputs by ``(node, port)`` (port
    ``""`` for a graph input) until their last reader has run; ``keys`` their
    cache keys; ``nodes`` what happened to each node; ``deferred`` the loaders
    of inputs keyed by reference, not loaded yet; ``consumers`` how many nodes
    still read each value; ``pinned`` the values kept to the end (outputs).
    """

    compiled: CompiledGraph
    cache: Cache | None
    executor: Executor
    hooks: Sequence[RunHooks]
    record: RunRecord
    values: dict[tuple[str, str], Any] = field(default_factory=dict)
    keys: dict[tuple[str, str], str] = field(default_factory=dict)
    nodes: dict[str, NodeRecord] = field(default_factory=dict)
    failures: dict[str, GraphvisionError] = field(default_factory=dict)
    started: dict[str, float] = field(default_factory=dict)
    consumers: dict[tuple[str, str], int] = field(default_factory=dict)
    pinned: set[tuple[str, str]] = field(default_factory=set)
    deferred: dict[str, Any] = field(default_factory=dict)
    keep_intermediates: bool = False

    def __post_init__(self) -> None:
        self.encoded = encodes_values(self.executor)  # the transport, read once
        self.chained = self.encoded and chains_tasks(self.executor)
        # With a chaining executor, its futures (each with a ``task``) of the steps not finished.
        self.in_flight: dict[str, Any] = {}
        # ops whose last call here took under _QUICK_SECONDS (learnt by the graph's last runs)
        self.quick_ops: set[str] = self.compiled.quick_ops
        self.limits = current_limits()  # time and memory per node (execution.limits)
        nodes = self.compiled.graph.nodes.values()
        self.timed = self.limits.timeout is not None or any(n.timeout is not None for n in nodes)
        # sync runs tasks in this thread anyway: each node without a time limit runs here
        self.inline = bool(getattr(self.executor, "in_calling_thread", False))

    def seconds_for(self, name: str) -> float | None:
        """The node's time limit: its own ``timeout:`` or the run's, the lower."""
        timed = self.timed  # with no limit anywhere, nothing to look up
        return self.limits.seconds_for(self.compiled.graph.nodes[name].timeout) if timed else None

    def release_inputs(self, step: Step) -> None:
        consumers = self.consumers
        for source in step.inputs.values():
            consumers[source] -= 1
            if consumers[source] == 0 and source not in self.pinned:
                self.values.pop(source, None)

    def key_inputs(self, values: dict[str, Any], reference_keys: dict[str, str]) -> None:
        """Key each graph input by content, or by reference (its value then loads later)."""
        for name, value in values.items():
            if name in reference_keys:
                self.keys[(name, "")] = reference_keys[name]
                self.deferred[name] = value  # a loader
                continue
            self.values[(name, "")] = value
            self.keys[(name, "")] = content_key(self.compiled.input_types[name], value)

    def key_steps(self, names: list[str]) -> None:
        """Chain the output keys of the steps ``names`` (:func:`chain_keys`)."""
        self.keys.update(chain_keys(self.compiled, self.keys, names))

    def plan(self, needed: list[str], wanted: list[tuple[str, str]]) -> list[str]:
        """Apply :func:`plan_steps`: record the loaded values as cached nodes (and tell the
        hooks); return the steps to compute in order (all ``needed`` without a cache)."""
        if self.cache is None:
            return needed
        found = plan_steps(
            self.compiled, self.keys, wanted, self.values.keys(), self.deferred.keys(),
            self.cache.get,
        )  # fmt: skip
        for source, (value, seconds) in found.loaded.items():
            name, port = source
            self.values[source] = value
            step = self.compiled.steps[name]
            node = self.nodes.get(name)
            if node is None:
                node = self.nodes[name] = self.new_record(step, "cached")
            node.seconds += seconds
            node.output_bytes += value_bytes(step.outputs[port], value)
        for node in self.nodes.values():
            for hook in self.hooks:
                hook.node_finished(
                    name=node.name, op=node.op, status="cached", seconds=node.seconds
                )
        return found.compute

    def prepare(
        self, compute: list[str], wanted: list[tuple[str, str]], schedule: Schedule
    ) -> Mapping[str, AbstractSet[str]]:
        """The steps to compute get their records (pending); count how many of them read
        each value (so intermediates are dropped after their last reader), load the
        inputs keyed by reference that they read; return their dependencies among
        themselves. With nothing cached that is the graph's ``schedule`` as it is."""
        steps, nodes = self.compiled.steps, self.nodes
        if len(compute) == len(schedule.steps):  # compute is a part of the schedule's steps
            dependencies: Mapping[str, AbstractSet[str]] = schedule.dependencies
            self.consumers = dict(schedule.readers)
            read = set(schedule.inputs)
        else:
            dependencies, read = self.count_readers(compute, wanted)
        new_record = self.new_record
        for name in compute:
            nodes[name] = new_record(steps[name], "pending")
        self.pinned = set(wanted)
        if self.keep_intermediates:
            self.pinned.update((name, port) for name in compute for port in steps[name].outputs)
        for name in sorted(read & self.deferred.keys()):
            self.values[(name, "")] = self.deferred.pop(name)()
        return dependencies

    def count_readers(
        self, compute: list[str], wanted: list[tuple[str, str]]
    ) -> tuple[dict[str, set[str]], set[str]]:
        """For some of the steps: their dependencies, their readers (``consumers``) and the
        graph inputs they or the wanted outputs read."""
        steps, consumers = self.compiled.steps, self.consumers
        dependencies: dict[str, set[str]] = {}
        read = {name for name, port in wanted if not port}
        for name in compute:
            sources = steps[name].inputs.values()
            dependencies[name] = {src for src, _ in sources if src in dependencies}
            for source in sources:
                consumers[source] = consumers.get(source, 0) + 1
                if not source[1]:
                    read.add(source[0])
        return dependencies, read

    def new_record(self, step: Step, status: str) -> NodeRecord:
        """A node's record, with the parameters it runs with and its outputs' keys."""
        name, keys, spec = step.name, self.keys, step.spec
        made = {port: keys[(name, port)] for port in step.outputs}
        return NodeRecord(name, spec.id, status, 0.0, 0, "", dict(step.params), made, spec.backend)

    # -- execution --------------------------------------------------------------------

    def start(self, name: str) -> Future:
        """Hand a step to the run's executor (encoded values for other processes; to a
        chaining one, before its inputs are computed, their tasks standing for them)."""
        step = self.compiled.steps[name]
        for hook in self.hooks:
            hook.node_started(name=name, op=step.spec.id)
        self.started[name] = time.perf_counter()
        if self.encoded:
            return self._submit_encoded(name, step)
        inputs = {port: self.values[source] for port, source in step.inputs.items()}
        seconds, label = self.seconds_for(name), f"node '{name}' ({step.spec.id})"
        if seconds is not None:  # on a thread of its own, left to itself at the limit
            return start_on_own_thread(
                call_node, (step.spec.func, step.params, inputs, name), seconds, label
            )
        return self.executor.submit(call_node, step.spec.func, step.params, inputs, name)

    def is_quick(self, name: str) -> bool:
        """Whether the step's op last ran here faster than a hand-off to a thread costs, or
        the executor runs tasks in this thread anyway (``sync``); never a node with a time
        limit (it could not be left at its limit)."""
        quick = self.inline or self.compiled.steps[name].spec.id in self.quick_ops
        return quick and (not self.timed or self.seconds_for(name) is None)

    def run_here(self, name: str) -> bool:
        """Run a step in this thread and finish it (the scheduler does for a quick one);
        False when it failed."""
        step = self.compiled.steps[name]
        for hook in self.hooks:
            hook.node_started(name=name, op=step.spec.id)
        values = self.values
        kwargs = {port: values[source] for port, source in step.inputs.items()}
        kwargs.update(step.params)
        began = time.perf_counter()
        try:  # as on a worker: warnings and a fault name the node, a forked child is ended
            result, seconds = call_labelled(step.spec.func, kwargs, *step.call_names)
            outputs = self.accept(step, result)
        except NODE_ERRORS as error:
            self.started[name] = began
            return self.failed(step, error)
        return self.computed(step, outputs, seconds)

    def _submit_encoded(self, name: str, step: Step) -> Future:
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
            if source in self.values:
                kind = step.spec.inputs[port].type
                payload[port] = (kind, *kind.encode(self.values[source]))
            else:  # submitted ahead: the producer's task stands for its result
                upstream[port] = (self.in_flight[source[0]].task, source[1])
        call = self.limits.worker_call(self.seconds_for(name), f"node '{name}' ({step.spec.id})")
        future = self.executor.submit(
            *call,
            call_node_encoded,
            step.spec.ref,
            step.params,
            payload,
            step.outputs,
            step.spec.output_tuple is not None,
            upstream,
        )
        if self.chained:
            self.in_flight[name] = future
        return future

    def finish(self, name: str, future: Future) -> bool:
        """Finish a step the executor ran; False when it failed."""
        step = self.compiled.steps[name]
        if self.chained:
            self.in_flight.pop(name, None)
        try:
            result, seconds = future.result()
            outputs = self.accept(step, result)
        except NODE_ERRORS as error:
            return self.failed(step, error)
        return self.computed(step, outputs, seconds)

    def failed(self, step: Step, error: BaseException) -> bool:
        node = self.nodes[step.name]
        node.status, node.seconds = "failed", time.perf_counter() - self.started[step.name]
        node.error = f"{type(error).__name__}: {error}"
        self.failures[step.name] = self.wrap(step, error)
        self.release_inputs(step)
        for hook in self.hooks:
            hook.node_finished(
                name=step.name, op=step.spec.id, status="failed", seconds=node.seconds
            )
        return False

    def computed(self, step: Step, outputs: dict[str, Any], seconds: float) -> bool:
        """Store a step's accepted outputs (and in the cache), release its inputs."""
        name, op = step.name, step.spec.id
        node = self.nodes[name]
        node.status, node.seconds = "computed", seconds
        if seconds < _QUICK_SECONDS:
            self.quick_ops.add(op)
        else:
            self.quick_ops.discard(op)
        cache = self.cache if step.spec.cache else None
        values = self.values
        for port, value in outputs.items():
            kind = step.outputs[port]
            values[(name, port)] = value
            if cache is not None:
                node.output_bytes += cache.put(self.keys[(name, port)], kind, value)
            elif not issubclass(kind, _ScalarPort):
                node.output_bytes += value_bytes(kind, value)
        consumers, pinned = self.consumers, self.pinned  # release the inputs it read
        for source in step.inputs.values():
            consumers[source] -= 1
            if consumers[source] == 0 and source not in pinned:
                values.pop(source, None)
        for hook in self.hooks:
            hook.node_finished(name=name, op=op, status="computed", seconds=seconds)
        return True

    def accept(self, step: Step, result: Any) -> dict[str, Any]:
        if self.encoded:
            return {
                port: freeze_value(kind, kind.decode(arrays, meta))
                for port, (kind, arrays, meta) in result.items()
            }
        only = step.only_output
        if only is not None:  # one output: no tuple to split
            port, kind, scalar = only
            try:
                value = kind.validate(result)
                return {port: value if scalar else freeze_value(kind, value)}
            except PortValueError as error:
                raise PortValueError(f"node returned an invalid output '{port}': {error}") from None
        outputs = {}
        for port, value in step.spec.split_outputs(result).items():
            kind = step.outputs[port]
            try:
                outputs[port] = freeze_value(kind, kind.validate(value))
            except PortValueError as error:
                raise PortValueError(f"node returned an invalid output '{port}': {error}") from None
        return outputs

    def result(self, wanted: list[str]) -> RunResult:
        """The outputs produced (with their summaries in the record) as a :class:`RunResult`."""
        produced = {}
        for name in wanted:
            source = self.compiled.outputs[name]
            if source in self.values:
                produced[name] = self.values[source]
                self.record.outputs[name] = self.compiled.output_type(name).summary(produced[name])
        kept = {
            (f"{name}.{port}" if len(self.compiled.steps[name].outputs) > 1 else name): (
                self.compiled.steps[name].outputs[port],
                value,
            )
            for (name, port), value in self.values.items()
            if self.keep_intermediates
            and name in self.compiled.steps
            and (name, port) not in self.compiled.outputs.values()
        }
        return RunResult(produced, self.record, self.compiled, self.failures, kept)

    def wrap(self, step: Step, error: BaseException) -> NodeExecutionError:
        summary = {}
        for port, source in step.inputs.items():
            value = self.values.get(source)
            summary[port] = step.spec.inputs[port].type.summary(value) if value is not None else "?"
        wrapped = NodeExecutionError(
            step.name, step.spec.id, step.params, summary, f"{type(error).__name__}: {error}"
        )
        wrapped.__cause__ = error
        return wrapped
