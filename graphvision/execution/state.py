r"""The state of one run (``RunState``): keys, plan, hand-out, finish.

The steps of a run and the states each node moves through are described in
:mod:`graphvision.execution.run`. The state lives in one dataclass, ``RunState``;
:func:`~graphvision.execution.plan.plan_steps` (a function of the graph, the keys and
the cache, changing nothing) decides cached or pending, ``RunState.plan`` records its
decision, ``start`` hands a pending node to the executor (encoded values for other
processes, the values themselves in this one; to an executor that chains tasks, such
as Dask's, as soon as the nodes it reads are submitted, their tasks standing for their
values), ``run_here`` runs a quick one in this thread, ``finish`` validates, freezes,
stores and releases, and the scheduler
(:func:`~graphvision.execution.scheduler.run_tasks`) only orders them. A node's record
(:class:`~graphvision.execution.record.NodeRecord`) is made when it ends; those that did
not start are made pending at the end (:meth:`RunState.records`).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping, Sequence
from collections.abc import Set as AbstractSet
from concurrent.futures import Future
from dataclasses import dataclass, field
from itertools import repeat
from operator import attrgetter, call, is_
from typing import Any

from numpy import ndarray

from graphvision.cache.keys import known_content_key
from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph, Schedule, Step
from graphvision.errors import GraphvisionError, PortValueError, error_text
from graphvision.execution.accept import accepted, invalid_output
from graphvision.execution.encoded import submit_encoded
from graphvision.execution.executors import (
    NODE_ERRORS,
    Executor,
    began_before,
    call_labelled,
    call_node,
    chains_tasks,
    encodes_values,
)
from graphvision.execution.inputs import value_bytes
from graphvision.execution.limits import NodeLimits, current_limits, start_on_own_thread
from graphvision.execution.plan import chain_keys, plan_steps
from graphvision.execution.record import (
    NodeRecord,
    RunHooks,
    RunRecord,
    RunResult,
    intermediates,
    wrapped_failure,
)
from graphvision.nodes.loading import plugin_line

__all__ = ["RunState"]

# About what handing a node to a thread and taking its result back costs (measured on
# a fan-out of trivial nodes): a node faster than this gains nothing from a thread.
_QUICK_SECONDS = 25e-6
_NONE = object()  # (a value not produced)
_NBYTES = attrgetter("nbytes")


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
    pending: set[str] = field(default_factory=set)
    limits: NodeLimits = field(default_factory=current_limits)  # time and memory per node

    def __post_init__(self) -> None:
        self.encoded = encodes_values(self.executor)  # the transport, read once
        self.chained = self.encoded and chains_tasks(self.executor)
        self.in_flight: dict[str, Any] = {}  # a chaining executor's futures not finished
        self.quick_ops: set[str] = self.compiled.quick_ops  # last ran under _QUICK_SECONDS
        self.timed = self.limits.timeout is not None or self.compiled.has_timeouts
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
            self.keys[(name, "")] = known_content_key(self.compiled.input_types[name], value)

    def key_steps(self, names: list[str]) -> None:
        """Chain the output keys of the steps ``names`` (:func:`chain_keys`)."""
        self.keys.update(chain_keys(self.compiled, self.keys, names))

    def plan(self, needed: list[str], wanted: list[tuple[str, str]]) -> list[str]:
        """Apply :func:`plan_steps`: record the loaded values as cached nodes (and tell the
        hooks), the steps only they read as unneeded; return the steps to compute in order
        (all ``needed`` without a cache)."""
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
        compute = set(found.compute)
        if len(compute | self.nodes.keys()) < len(needed):  # ancestors of loaded values only
            for name in needed:
                if name not in compute and name not in self.nodes:
                    self.nodes[name] = self.new_record(self.compiled.steps[name], "unneeded")
        return found.compute

    def prepare(
        self, compute: list[str], wanted: list[tuple[str, str]], schedule: Schedule
    ) -> Mapping[str, AbstractSet[str]]:
        """The steps to compute are pending (:meth:`records`); count how many of them read
        each value (so intermediates are dropped after their last reader), load the
        inputs keyed by reference that they read; return their dependencies among
        themselves. With nothing cached that is the graph's ``schedule`` as it is."""
        steps = self.compiled.steps
        if len(compute) == len(schedule.steps):  # compute is a part of the schedule's steps
            dependencies: Mapping[str, AbstractSet[str]] = schedule.dependencies  # as it is
            self.consumers = dict(schedule.readers)
            read = set(schedule.inputs)
        else:
            dependencies, read = self.count_readers(compute, wanted)
        self.pending = set(compute)  # their records are made when they end (records())
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
        keys, spec = self.keys, step.spec
        made = {port: keys[source] for port, source in step.output_sources}
        return NodeRecord(
            step.name, spec.id, status, 0.0, 0, "", dict(step.params), made, spec.backend
        )

    def record_of(self, step: Step, status: str) -> NodeRecord:
        """The node's record (made now if it has none), with ``status``."""
        node = self.nodes.get(step.name)
        if node is None:
            node = self.nodes[step.name] = self.new_record(step, status)
        node.status = status
        return node

    def records(self) -> list[NodeRecord]:
        """Every node's record in the graph's order: those still pending made now."""
        nodes, pending, listed = self.nodes, self.pending, []
        if pending <= nodes.keys():  # every node that was to run has its record (in C: no
            steps: Iterable[str] = self.compiled.steps  # Python step per node)
            if len(nodes) < len(self.compiled.steps):
                steps = filter(nodes.__contains__, steps)
            return list(map(nodes.__getitem__, steps))
        for name, step in self.compiled.steps.items():
            node = nodes.get(name)
            if node is None and name in pending:
                node = nodes[name] = self.new_record(step, "pending")
            if node is not None:
                listed.append(node)
        return listed

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
        func, inputs, params, label, op, only, exact = step.call_plan
        if self.hooks:
            for hook in self.hooks:
                hook.node_started(name=name, op=op)
        values, kwargs, seconds, outputs = self.values, {}, -1.0, None
        for port, source in inputs:  # (a loop: a comprehension is a call more)
            kwargs[port] = values[source]
        if params:
            kwargs.update(params)
        try:  # as on a worker: warnings and a fault name the node, a forked child is ended
            result, seconds = call_labelled(func, kwargs, label, op)
            if type(result) is exact:  # a scalar its port takes as it is (no call)
                pass
            elif only is None or not only[2]:
                outputs = accepted(step, result, 1, False)
            else:  # one scalar: nothing to split or freeze
                try:
                    result = only[1].validate(result)
                except PortValueError as error:
                    raise invalid_output(only[0], error) from None
        except NODE_ERRORS as error:  # (when it began: read once it failed, not per node)
            self.started[name] = began_before(seconds)
            return self.failed(step, error)
        if outputs is not None:
            return self.computed(step, outputs, seconds)
        # one scalar output: what :meth:`computed` does, in fewer steps (no call more per node;
        # what it reads is made once, :attr:`Step.scalar_plan`)
        name, op, source, port, kind, caches, read, backend = step.scalar_plan
        quick = self.quick_ops
        if seconds >= _QUICK_SECONDS:
            quick.discard(op)
        elif op not in quick:  # (a look-up, not a call, once it is known quick)
            quick.add(op)
        values[source] = result
        key, cache = self.keys[source], self.cache
        size = cache.put(key, kind, result) if caches and cache is not None else 0
        self.nodes[name] = NodeRecord(
            name, op, "computed", seconds, size, "", dict(params) if params else {}, {port: key},
            backend,
        )  # fmt: skip
        consumers, pinned = self.consumers, self.pinned  # release the inputs it read
        for source in read:
            left = consumers[source] = consumers[source] - 1
            if not left and source not in pinned:
                values.pop(source, None)
        if self.hooks:
            for hook in self.hooks:
                hook.node_finished(name=name, op=op, status="computed", seconds=seconds)
        return True

    def _submit_encoded(self, name: str, step: Step) -> Future:
        label = f"node '{name}' ({step.spec.id})"
        future = submit_encoded(
            self.executor,
            lambda: self.limits.worker_call(self.seconds_for(name), label),
            step,
            self.values,
            self.in_flight,
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
            result, seconds = future.result()  # (the future holds the result too)
            outputs = accepted(step, result, 2, self.encoded)
        except NODE_ERRORS as error:
            return self.failed(step, error)
        return self.computed(step, outputs, seconds)

    def failed(self, step: Step, error: BaseException) -> bool:
        node = self.record_of(step, "failed")
        node.seconds = time.perf_counter() - self.started[step.name]
        node.error = f"{error_text(error)}{plugin_line(error)}"
        self.failures[step.name] = wrapped_failure(step, error, self.values)
        self.release_inputs(step)
        for hook in self.hooks:
            hook.node_finished(
                name=step.name, op=step.spec.id, status="failed", seconds=node.seconds
            )
        return False

    def computed(self, step: Step, outputs: dict[str, Any], seconds: float) -> bool:
        """Store a step's accepted outputs (and in the cache), record it, release its inputs."""
        name, op, caches, backend, made_by = step.finish_plan
        if seconds < _QUICK_SECONDS:
            self.quick_ops.add(op)
        else:
            self.quick_ops.discard(op)
        cache = self.cache if caches else None
        values, keys, made, size = self.values, self.keys, {}, 0
        for port, source, kind, sized in made_by:  # (how each is sized: Step.finish_plan)
            value = values[source] = outputs[port]
            key = made[port] = keys[source]
            if cache is not None:
                size += cache.put(key, kind, value)
            elif sized == "array" and type(value) is ndarray:
                size += value.nbytes
            elif sized == "table" and type(value) is dict:
                size += sum(map(_NBYTES, value.values()))
            elif sized:
                size += value_bytes(kind, value)
        params = step.params
        self.nodes[name] = NodeRecord(
            name, op, "computed", seconds, size, "", dict(params) if params else {}, made, backend
        )
        consumers, pinned = self.consumers, self.pinned  # release the inputs it read
        for source in step.read:
            left = consumers[source] = consumers[source] - 1
            if not left and source not in pinned:
                values.pop(source, None)
        for hook in self.hooks:
            hook.node_finished(name=name, op=op, status="computed", seconds=seconds)
        return True

    def result(self, wanted: list[str]) -> RunResult:
        """The outputs produced (with their summaries in the record) as a :class:`RunResult`."""
        sources, summary = self.compiled.outputs, self.compiled.output_summaries
        found = list(map(self.values.get, map(sources.__getitem__, wanted), repeat(_NONE)))
        if any(map(is_, found, repeat(_NONE))):  # some were not produced
            pairs = [(name, value) for name, value in zip(wanted, found, strict=True)]
            wanted = [name for name, value in pairs if value is not _NONE]
            found = [value for _, value in pairs if value is not _NONE]
        produced = dict(zip(wanted, found, strict=True))  # (in C: no Python step per output)
        summaries = map(call, map(summary.__getitem__, wanted), found)
        self.record.outputs.update(zip(wanted, summaries, strict=True))
        kept = intermediates(self.compiled, self.values) if self.keep_intermediates else {}
        return RunResult(produced, self.record, self.compiled, self.failures, kept)
