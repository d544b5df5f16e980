"""What compiling a graph gives: the steps, in order, and the schedules runs read.

A :class:`CompiledGraph` is made by :func:`graphvision.compiler.compile.compile_graph`;
nothing in it changes once made, so runs, sweeps and batches share it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from graphvision.graph.model import Graph
from graphvision.nodes.fingerprint import node_fingerprint
from graphvision.nodes.spec import NodeSpec
from graphvision.values.ports import ArrayPort, PortType, is_plain_array_port
from graphvision.values.scalars import FloatPort, _ScalarPort, is_plain_table_port

__all__ = ["CompiledGraph", "Schedule", "Step"]


_PLAIN_SCALARS = (_ScalarPort.validate.__func__, FloatPort.validate.__func__)  # type: ignore[attr-defined]
"""The ``validate`` of the built-in scalar ports: each returns a value of exactly its
``python_type`` at once."""


def _sizing(kind: type[PortType]) -> str:
    """How a run counts the bytes of a value of ``kind`` (see :attr:`Step.finish_plan`)."""
    if is_plain_array_port(kind):
        return "array"
    if is_plain_table_port(kind):
        return "table"
    return "" if issubclass(kind, _ScalarPort) else "encoded"


@dataclass(frozen=True)
class Step:
    """A node ready to run: its spec, validated parameters and where each input comes from.

    ``inputs`` maps port -> (producer, output port); the output port is '' for a graph
    input. ``outputs`` are the output types with the node's type variables bound.
    """

    name: str
    spec: NodeSpec
    params: dict[str, Any]
    inputs: dict[str, tuple[str, str]]
    outputs: dict[str, type[PortType]]

    @cached_property
    def fingerprint(self) -> str:
        """What the node is (id, version, code, parameters), for its cache keys."""
        spec = self.spec
        return node_fingerprint(spec.key_id, spec.version, spec.source_hash, self.params)

    @cached_property
    def call_names(self) -> tuple[str, str]:
        """What names a call of the node, made once for every run: the label of its frame
        (``node 'name' (op)``) and the op its warnings name (the function's node id)."""
        mark = getattr(self.spec.func, "__graphvision_node__", None)
        op = mark.id if mark is not None else getattr(self.spec.func, "__qualname__", "")
        return f"node '{self.name}' ({op})", op

    @cached_property
    def call_plan(
        self,
    ) -> tuple[Any, tuple[tuple[str, tuple[str, str]], ...], dict[str, Any], str, str, Any, Any]:
        """What a run reads to call the node, in one tuple made once: the function, each
        input port with the value it reads, the parameters, the frame's label, the op its
        warnings name, :attr:`only_output`, and the type whose exact instances its one scalar
        output port takes as they are (its ``validate`` is a built-in scalar's, which returns
        them at once), else None."""
        label, op = self.call_names
        only, exact = self.only_output, None
        if only is not None and only[2] and only[1].validate.__func__ in _PLAIN_SCALARS:  # type: ignore[attr-defined]
            exact = only[1].python_type  # type: ignore[attr-defined]
        func, inputs = self.spec.func, tuple(self.inputs.items())
        return func, inputs, self.params, label, op, only, exact

    @cached_property
    def scalar_plan(
        self,
    ) -> tuple[
        str, str, tuple[str, str], str, type[PortType], bool, tuple[tuple[str, str], ...], str
    ]:
        """What a run reads to store the node's one scalar output, in one tuple made once:
        the node's name, its op, the value it makes and its port, the port's type, whether
        the node is cached, the values it read (:attr:`read`) and its backend."""
        assert self.only_output is not None  # (a node with one output only)
        port, kind = self.only_output[0], self.only_output[1]
        spec = self.spec
        return (
            self.name,
            spec.id,
            (self.name, port),
            port,
            kind,
            spec.cache,
            self.read,
            spec.backend,
        )

    @cached_property
    def read(self) -> tuple[tuple[str, str], ...]:
        """The values the node reads, one per input port (a value read twice counts twice)."""
        return tuple(self.inputs.values())

    @cached_property
    def output_sources(self) -> tuple[tuple[str, tuple[str, str]], ...]:
        """Each output port with the value it makes, ``(port, (node, port))``, made once for
        every run."""
        return tuple((port, (self.name, port)) for port in self.outputs)

    @cached_property
    def finish_plan(
        self,
    ) -> tuple[str, str, bool, str, tuple[tuple[str, tuple[str, str], type[PortType], str], ...]]:
        """What a run reads to store the node's outputs, in one tuple made once: the node's
        name, its op, whether it is cached, its backend, and each output's port, the value it
        makes, its type and how its size is counted: ``"array"`` (its one array's
        ``nbytes``), ``"table"`` (its columns' ``nbytes``, as ``TablePort`` encodes it), ``""``
        (a scalar: none) or ``"encoded"`` (the arrays its type encodes it as)."""
        sized = tuple(
            (port, (self.name, port), kind, _sizing(kind)) for port, kind in self.outputs.items()
        )
        spec = self.spec
        return self.name, spec.id, spec.cache, spec.backend, sized

    @cached_property
    def only_output(self) -> tuple[str, type[PortType], bool, bool] | None:
        """The port and type of the node's one output when it returns it alone (no tuple),
        whether it is a scalar (a value with no arrays to freeze), and whether the value is
        its one array (an ``ArrayPort`` that encodes it as it is: it may be frozen in place,
        :func:`~graphvision.values.memory.frozen_in_place`)."""
        if self.spec.output_tuple is not None:
            return None
        [(port, kind)] = self.outputs.items()
        plain = (
            issubclass(kind, ArrayPort)
            and kind.encode.__func__ is ArrayPort.encode.__func__  # type: ignore[attr-defined]
            and kind.decode.__func__ is ArrayPort.decode.__func__  # type: ignore[attr-defined]
        )
        return port, kind, issubclass(kind, _ScalarPort), plain


@dataclass(frozen=True)
class Schedule:
    """What computing some outputs from nothing involves, fixed by the graph alone.

    ``steps`` in topological order; ``inputs`` the graph inputs they (or the
    outputs themselves) read; ``dependencies`` each step's producers among the
    steps; ``readers`` how many of the steps read each value (``(node, port)``,
    port ``''`` for a graph input). A run reads it and changes nothing in it.
    """

    steps: list[str]
    inputs: frozenset[str]
    dependencies: dict[str, frozenset[str]]
    readers: dict[tuple[str, str], int]

    @cached_property
    def dependents(self) -> dict[str, tuple[str, ...]]:
        """Each step's readers among the steps, in the steps' order (made once; the
        scheduler walks it)."""
        found: dict[str, list[str]] = {name: [] for name in self.steps}
        for name in self.steps:
            for dependency in self.dependencies[name]:
                found[dependency].append(name)
        return {name: tuple(readers) for name, readers in found.items()}

    @cached_property
    def waiting(self) -> dict[str, int]:
        """How many steps each step waits for (the scheduler counts a copy down)."""
        return {name: len(self.dependencies[name]) for name in self.steps}


@dataclass(frozen=True)
class CompiledGraph:
    """A validated graph: steps in topological order, typed inputs and outputs."""

    graph: Graph
    steps: dict[str, Step]
    input_types: dict[str, type[PortType]]
    outputs: dict[str, tuple[str, str]]

    @cached_property
    def last_keys(self) -> dict[tuple[Any, ...], tuple[list[str], dict[tuple[str, str], str]]]:
        """The output keys the last run of these steps chained, by the steps and their
        graph inputs' keys (a run reads and writes it: keys are a function of these alone)."""
        return {}

    @cached_property
    def quick_ops(self) -> set[str]:
        """The ops the runs of this graph found quicker than handing them to a thread costs
        (:mod:`graphvision.execution.state` keeps it): where the next run starts."""
        return set()

    @cached_property
    def first_found(self) -> dict[str, Any]:
        """What the first run of this graph found of its pipeline file (path, SHA-256, git
        state: :mod:`graphvision.execution.provenance` keeps it), for its later runs: they
        run the graph as it was loaded."""
        return {}

    @cached_property
    def has_timeouts(self) -> bool:
        """Whether some node declares its own ``timeout:``."""
        return any(node.timeout is not None for node in self.graph.nodes.values())

    @cached_property
    def ops(self) -> frozenset[str]:
        """The ops the steps run (a run's provenance lists their plugins' versions)."""
        return frozenset(step.spec.id for step in self.steps.values())

    @cached_property
    def truth_marks(self) -> list[tuple[str, tuple[str, ...]]]:
        """The graph inputs and nodes marked as the truth of some inputs, with those inputs."""
        graph = self.graph
        marked = [(n, tuple(d.truth_of)) for n, d in graph.inputs.items() if d.truth_of]
        return marked + [(n, tuple(d.truth_of)) for n, d in graph.nodes.items() if d.truth_of]

    @cached_property
    def step_ops(self) -> dict[str, str]:
        """Each step's op id (what a run learns is quick is an op), made once."""
        return {name: step.spec.id for name, step in self.steps.items()}

    @cached_property
    def output_types(self) -> dict[str, type[PortType]]:
        """Each output's port type (:meth:`output_type`), made once."""
        return {name: self.output_type(name) for name in self.outputs}

    @cached_property
    def output_summaries(self) -> dict[str, Callable[[Any], str]]:
        """Each output's summary function (its port type's ``summary``), made once."""
        return {name: kind.summary for name, kind in self.output_types.items()}

    def output_type(self, name: str) -> type[PortType]:
        producer, port = self.outputs[name]
        if producer in self.input_types:
            return self.input_types[producer]
        return self.steps[producer].outputs[port]

    def schedule_for(self, outputs: list[str]) -> Schedule:
        """What computing ``outputs`` from nothing involves (see :class:`Schedule`); the
        one for all outputs is made once per compiled graph and shared by its runs."""
        if len(outputs) == len(self.outputs) and set(outputs) == self.outputs.keys():
            return self.full_schedule
        return self._schedule(outputs)

    @cached_property
    def full_schedule(self) -> Schedule:
        return self._schedule(list(self.outputs))

    def _schedule(self, outputs: list[str]) -> Schedule:
        """One pass over the steps from the last (they are in topological order, so
        every reader of a step comes after it), one from the first."""
        wanted = {self.outputs[o][0] for o in outputs}
        needed = []
        for name, step in reversed(self.steps.items()):
            if name in wanted:
                needed.append(name)
                wanted.update([src for src, _ in step.inputs.values()])
        needed.reverse()
        dependencies: dict[str, frozenset[str]] = {}
        readers: dict[tuple[str, str], int] = {}
        for name in needed:
            sources = self.steps[name].inputs.values()
            dependencies[name] = frozenset([src for src, _ in sources if src in dependencies])
            for source in sources:
                readers[source] = readers.get(source, 0) + 1
        inputs = frozenset(name for name in self.input_types if name in wanted)
        return Schedule(needed, inputs, dependencies, readers)
