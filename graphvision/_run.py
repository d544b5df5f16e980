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
6. hand the computed steps to :func:`~graphvision._scheduler.run_tasks` with
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
record.) The state lives in one dataclass, ``_Run``; :func:`plan_steps` (a function
of the graph, the keys and the cache, changing nothing) decides cached or pending,
``_Run.plan`` records its decision, ``start`` hands a pending node to the executor
(encoded values for other processes, the values themselves in this one; to an
executor that chains tasks, such as Dask's, as soon as the nodes it reads are
submitted, their tasks standing for their values),
``finish`` validates, freezes, stores and releases, and the scheduler
(:func:`~graphvision._scheduler.run_tasks`) only orders them.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import time
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from collections.abc import Set as AbstractSet
from concurrent.futures import Future
from dataclasses import asdict, dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ._blas import one_blas_thread
from ._cache import Cache, content_key, output_keys
from ._compile import CompiledGraph, Schedule, Step, compile_graph
from ._errors import (
    GraphvisionError,
    InputError,
    NodeExecutionError,
    PortValueError,
    RunError,
    UnknownNameError,
    did_you_mean,
)
from ._executors import (
    NODE_ERRORS,
    Executor,
    call_node,
    call_node_encoded,
    chains_tasks,
    encodes_values,
    executor_name,
    executor_width,
    make_executor,
)
from ._graph import Graph
from ._ports import PortType, TextPort, _ScalarPort, freeze
from ._provenance import describe_run
from ._registry import Registry
from ._scheduler import run_tasks
from ._warnings import running

__all__ = [
    "NodeRecord",
    "Plan",
    "RunHooks",
    "RunRecord",
    "RunResult",
    "plan_steps",
    "resolve_input",
    "run",
    "value_bytes",
]

# About what handing a node to a thread and taking its result back costs (measured on
# a fan-out of trivial nodes): a node faster than this gains nothing from a thread.
_QUICK_SECONDS = 25e-6


@dataclass(slots=True)
class NodeRecord:
    """What happened to one node: ``computed``, ``cached`` (loaded), ``failed``, ``skipped``
    (downstream of a failure) or ``pending`` (the run stopped before it ran).

    ``params`` are the validated parameters it ran with and ``keys`` the cache
    key of each output port; ``output_bytes`` counts loaded outputs too.
    """

    name: str
    op: str
    status: str
    seconds: float = 0.0
    output_bytes: int = 0
    error: str = ""
    params: dict[str, Any] = field(default_factory=dict)
    keys: dict[str, str] = field(default_factory=dict)


@dataclass
class RunRecord:
    """One run: what it ran on and with what (to reproduce it), and how each node went.

    Provenance (filled by :func:`run`): ``date`` (UTC, ISO 8601, at its end), the
    ``pipeline_file`` with its ``pipeline_sha256`` and the ``git_commit`` of
    its folder (with ``git_dirty`` when the file differs from it), every
    used input (``inputs``: what was given, the file's SHA-256 for a path,
    the content key), pipeline ``params`` and command-line ``overrides``, and
    ``versions`` of Python, graphvision, numpy, scipy and each plugin.
    ``files`` lists the files written for each output and ``file_sha256`` their
    digests (set by the writer: a re-run keeps a file whose value and bytes are
    unchanged, and ``graphvision report`` warns about a file edited since).
    """

    pipeline: str
    executor: str
    seconds: float = 0.0
    nodes: list[NodeRecord] = field(default_factory=list)
    outputs: dict[str, str] = field(default_factory=dict)
    date: str = ""
    pipeline_file: str = ""
    pipeline_sha256: str = ""
    git_commit: str = ""
    git_dirty: bool = False
    inputs: dict[str, dict[str, str]] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)
    overrides: dict[str, Any] = field(default_factory=dict)
    versions: dict[str, str] = field(default_factory=dict)
    files: dict[str, list[str]] = field(default_factory=dict)
    file_sha256: dict[str, str] = field(default_factory=dict)

    def count(self, status: str) -> int:
        return sum(n.status == status for n in self.nodes)

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=2, default=_json_default)

    def table(self) -> str:
        """The record as an aligned text table."""
        rows = [("node", "op", "status", "ms", "bytes")]
        rows += [
            (n.name, n.op, n.status, f"{n.seconds * 1e3:.1f}", str(n.output_bytes))
            for n in self.nodes
        ]
        widths = [max(len(r[i]) for r in rows) for i in range(5)]
        lines = [
            "  ".join(
                c.ljust(w) if i < 3 else c.rjust(w)
                for i, (c, w) in enumerate(zip(row, widths, strict=True))
            )
            for row in rows
        ]
        lines.append(
            f"{self.count('computed')} computed, {self.count('cached')} cached, "
            f"{self.count('failed')} failed, {self.count('skipped')} skipped "
            f"in {self.seconds:.3f} s ({self.executor})"
        )
        return "\n".join(lines)


def _json_default(value: Any) -> Any:
    """Parameters JSON cannot hold as they are: numpy values, tuples' items, paths."""
    if isinstance(value, np.generic | np.ndarray):
        return value.tolist()
    return str(value)


@dataclass
class RunResult:
    """Outputs produced, the run record, failures by node, and the compiled graph."""

    outputs: dict[str, Any]
    record: RunRecord
    compiled: CompiledGraph
    failures: dict[str, GraphvisionError] = field(default_factory=dict)
    intermediates: dict[str, tuple[type[PortType], Any]] = field(default_factory=dict)
    """With ``keep_intermediates=True``: every node output that is not a graph output, by
    ``node`` or ``node.port``, with its port type."""

    def _repr_html_(self) -> str:
        """The report's page, shown by Jupyter when a result is the value of a cell."""
        from ._html import html_report

        failures = {name: str(error) for name, error in self.failures.items()}
        return html_report(self.compiled, self.outputs, self.record, failures=failures)


class RunHooks:
    """Observe a run. Override what you need; every argument is keyword-only.

    ``run_finished`` is called from a ``finally`` block, with ``failed``.
    """

    def run_started(self, *, pipeline: str, steps: list[str]) -> None:
        """Before any node runs; ``steps`` are the nodes to compute."""

    def node_started(self, *, name: str, op: str) -> None:
        """A node was handed to the executor."""

    def node_finished(self, *, name: str, op: str, status: str, seconds: float) -> None:
        """A node was computed, loaded from the cache, or failed; or, after it was started
        ahead of its inputs (on Dask), skipped because one of them failed."""

    def run_finished(self, *, record: RunRecord, failed: bool) -> None:
        """After the run, whatever happened."""


def resolve_input(name: str, port_type: type[PortType], value: Any, registry: Registry) -> Any:
    """Turn a given value into a validated port value.

    A string for a non-``Text`` port is a reference: ``scheme:rest`` goes to the
    plugin source of that scheme (e.g. ``sample:camera``), a scalar port parses
    it as YAML (``--input sigma=2``), a ``.npz`` path is read by the port type
    as it writes its values (with the ``.json`` beside it, if any: a trained
    network, keypoints or boxes from an earlier run's output folder), anything
    else is a path for the ``file`` source. The loaded value, or an array the
    caller passed, then goes through the port's dtype policy
    (:meth:`PortType.coerce`), so a ``uint8`` array from OpenCV is the same
    image as the PNG it was read from.

    Raises
    ------
    InputError
        Naming the input, the value and what is wrong.
    """
    origin = f"'{value}'" if isinstance(value, str) else f"the {type(value).__name__} given"
    if isinstance(value, str) and not issubclass(port_type, TextPort):
        scheme, sep, rest = value.partition(":")
        try:
            if sep and scheme in registry.sources:
                value = registry.sources[scheme].func(rest)
            elif issubclass(port_type, _ScalarPort):
                value = yaml.safe_load(value)
            elif value.lower().endswith(".npz"):
                value = _read_written(port_type, Path(value))
            else:
                value = registry.source("file").func(value)
        except Exception as error:
            told = str(error)
            what = told if str(value) in told else f"cannot load '{value}': {told}"
            raise InputError(f"input '{name}': {what}") from error
    try:
        value = port_type.coerce(value, origin)
        return _freeze(port_type, port_type.validate(value))
    except PortValueError as error:
        raise InputError(f"input '{name}': {error}") from None
    except (Exception, RecursionError) as error:  # a port type's check undone by hostile data
        raise InputError(
            f"input '{name}': not a valid {port_type.type_name()} ({type(error).__name__}: "
            f"{str(error)[:200]})"
        ) from None


def _read_written(port_type: type[PortType], archive: Path) -> Any:
    """The value in an ``.npz`` ``port_type`` wrote (with the ``.json`` of its header
    beside it, if any), or an error naming the file and what it lacks."""
    if not archive.is_file():
        raise FileNotFoundError(f"no such file: {archive}")
    header = archive.with_suffix(".json")
    try:
        return port_type.read([archive, header] if header.is_file() else [archive])
    except (KeyError, TypeError, ValueError, OSError) as error:
        raise ValueError(
            f"{archive} is not a {port_type.type_name()} as graphvision writes it "
            f"({type(error).__name__}: {error})"
        ) from None


def value_bytes(port_type: type[PortType], value: Any) -> int:
    """Bytes of a value's arrays (what a run record counts per node; a scalar has none)."""
    if issubclass(port_type, _ScalarPort):
        return 0
    return sum(a.nbytes for a in port_type.encode(value)[0].values())


def _freeze(port_type: type[PortType], value: Any) -> Any:
    """The value over immutable copies of its arrays (see :func:`~graphvision._ports.freeze`).

    A node's inputs then cannot be changed by the node, whatever flags it
    sets: a mutating node fails, naming itself, and nothing else changes.
    The caller's own arrays (graph inputs given in Python) stay as they were.
    """
    if issubclass(port_type, _ScalarPort):
        return value
    arrays, meta = port_type.encode(value)
    return port_type.decode({name: freeze(a) for name, a in arrays.items()}, meta)


@dataclass(frozen=True)
class Plan:
    """What a run must do: the outputs found in the cache (value and seconds to load),
    and the steps to compute, in topological order."""

    loaded: dict[tuple[str, str], tuple[Any, float]]
    compute: list[str]


def plan_steps(
    compiled: CompiledGraph,
    keys: Mapping[tuple[str, str], str],
    wanted: Iterable[tuple[str, str]],
    known: Collection[tuple[str, str]],
    deferred: Collection[str],
    lookup: Callable[[str, type[PortType]], tuple[bool, Any]] | None,
) -> Plan:
    """Decide, from the outputs backwards, what is loaded from the cache and what runs.

    A wanted value that is ``known`` (a graph input, or already produced) or a
    ``deferred`` input (loaded when read) needs nothing; a cached node's
    output found by ``lookup(key, port_type)`` is loaded and its producers are
    not visited, so a fully cached re-run reads only the requested outputs;
    any other step is computed, and so are the producers of its inputs. The
    function reads the cache and changes nothing else.
    """
    compute: set[str] = set()
    loaded: dict[tuple[str, str], tuple[Any, float]] = {}
    stack = list(wanted)
    steps = compiled.steps
    while stack:
        source = stack.pop()
        name, port = source
        if source in known or source in loaded or name in compute or name in deferred:
            continue
        step = steps[name]
        if step.spec.cache and lookup is not None:
            began = time.perf_counter()
            hit, value = lookup(keys[source], step.outputs[port])
            if hit:
                loaded[source] = (value, time.perf_counter() - began)
                continue
        compute.add(name)
        stack.extend(step.inputs.values())
    return Plan(loaded, [name for name in steps if name in compute])


@dataclass(eq=False)
class _Run:
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
        self.quick_ops: set[str] = set()  # ops whose last call here took under _QUICK_SECONDS

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
        keys, steps = self.keys, self.compiled.steps
        for name in names:
            step = steps[name]
            inputs = {port: keys[source] for port, source in step.inputs.items()}
            made = output_keys(step.fingerprint, inputs, step.outputs)
            for port, key in zip(step.outputs, made, strict=True):
                keys[(name, port)] = key

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
        for name in compute:
            nodes[name] = self.new_record(steps[name], "pending")
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
        name, keys = step.name, self.keys
        return NodeRecord(
            name,
            step.spec.id,
            status,
            params=dict(step.params),
            keys={port: keys[(name, port)] for port in step.outputs},
        )

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
        return self.executor.submit(call_node, step.spec.func, step.params, inputs)

    def is_quick(self, name: str) -> bool:
        """Whether the step's op last ran here faster than a hand-off to a thread costs."""
        return self.compiled.steps[name].spec.id in self.quick_ops

    def run_here(self, name: str) -> bool:
        """Run a step in this thread and finish it (the scheduler does for a quick one);
        False when it failed."""
        step = self.compiled.steps[name]
        spec, values = step.spec, self.values
        for hook in self.hooks:
            hook.node_started(name=name, op=spec.id)
        inputs = {port: values[source] for port, source in step.inputs.items()}
        running.op = spec.id  # warnings name the node (as call_node does on a worker)
        began = time.perf_counter()
        try:
            result = spec.func(**inputs, **step.params)
            seconds = time.perf_counter() - began
            outputs = self.accept(step, result)
        except NODE_ERRORS as error:
            self.started[name] = began
            return self.failed(step, error)
        finally:
            running.op = ""
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
        future = self.executor.submit(
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
        for port, value in outputs.items():
            kind = step.outputs[port]
            self.values[(name, port)] = value
            if cache is not None:
                node.output_bytes += cache.put(self.keys[(name, port)], kind, value)
            elif not issubclass(kind, _ScalarPort):
                node.output_bytes += value_bytes(kind, value)
        self.release_inputs(step)
        for hook in self.hooks:
            hook.node_finished(name=name, op=op, status="computed", seconds=seconds)
        return True

    def accept(self, step: Step, result: Any) -> dict[str, Any]:
        if self.encoded:
            return {
                port: _freeze(kind, kind.decode(arrays, meta))
                for port, (kind, arrays, meta) in result.items()
            }
        if step.spec.output_tuple is None:  # one output: no tuple to split
            [(port, kind)] = step.outputs.items()
            try:
                return {port: _freeze(kind, kind.validate(result))}
            except PortValueError as error:
                raise PortValueError(f"node returned an invalid output '{port}': {error}") from None
        outputs = {}
        for port, value in step.spec.split_outputs(result).items():
            kind = step.outputs[port]
            try:
                outputs[port] = _freeze(kind, kind.validate(value))
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

    Raises
    ------
    PipelineError
        The graph is invalid (nothing ran).
    InputError
        A graph input could not be resolved (nothing ran).
    RunError
        Nodes failed; ``error.failures`` names them, ``error.result`` holds
        the outputs that were produced and the record.
    """
    graph, inputs, outputs, overrides = _checked_arguments(
        graph, inputs, outputs, overrides, cache, executor, workers
    )
    compiled, registry = _compiled(graph, registry, inputs, overrides)
    wanted = _wanted_outputs(compiled, outputs, inputs)
    schedule = compiled.schedule_for(wanted)
    given = _given_inputs(compiled, schedule, inputs)
    reference_keys = _referenced_inputs(compiled, given, registry)
    values = {
        name: partial(resolve_input, name, compiled.input_types[name], value, registry)
        if name in reference_keys
        else resolve_input(name, compiled.input_types[name], value, registry)
        for name, value in given.items()
    }
    state = _execute(
        compiled,
        values,
        schedule,
        wanted,
        cache,
        executor,
        workers,
        keep_going,
        hooks,
        keep_intermediates,
        reference_keys,
    )
    describe_run(state.record, compiled, registry, given, state.keys, overrides)
    result = state.result(wanted)
    if state.failures:
        failure = RunError(state.failures, state.record)
        failure.result = result  # type: ignore[attr-defined]  # read by callers as error.result
        raise failure
    return result


def _checked_arguments(
    graph: Any, inputs: Any, outputs: Any, overrides: Any, cache: Any, executor: Any, workers: Any
) -> tuple[Graph | CompiledGraph, dict[str, Any], list[str] | None, dict[str, Any]]:
    """The arguments of :func:`run` as it uses them, or a TypeError naming the wrong one."""
    from ._arguments import graph_argument, mapping_argument, names_argument, run_arguments

    run_arguments(cache, executor, workers)
    return (
        graph_argument(graph),
        mapping_argument(inputs, "inputs"),
        names_argument(outputs, "outputs"),
        mapping_argument(overrides, "overrides"),
    )


def _compiled(
    graph: Graph | CompiledGraph,
    registry: Registry | None,
    inputs: dict[str, Any],
    overrides: dict[str, Any],
) -> tuple[CompiledGraph, Registry]:
    """The graph, overrides applied, compiled (step 1); the registry it was checked against."""
    if isinstance(graph, CompiledGraph):
        if not overrides:
            return graph, registry or _discover_for(graph.graph)
        graph = graph.graph  # overrides change parameters: compile again
    registry = registry or _discover_for(graph)
    if overrides:
        try:
            graph = graph.with_overrides(overrides)
        except KeyError as error:
            raise UnknownNameError(str(error.args[0])) from None
    return compile_graph(graph, registry, provided=set(inputs)), registry


def _discover_for(graph: Graph) -> Registry:
    from ._plugins import discover_for  # the plugins are imported only for a run

    return discover_for(graph)


def _wanted_outputs(
    compiled: CompiledGraph, outputs: Sequence[str] | None, inputs: dict[str, Any]
) -> list[str]:
    """The outputs asked for, after checking every output and input name given."""
    wanted = list(outputs) if outputs is not None else list(compiled.outputs)
    for name in wanted:
        if name not in compiled.outputs:
            raise UnknownNameError(
                f"unknown output '{name}'{did_you_mean(name, compiled.outputs)}"
                f"; outputs: {', '.join(compiled.outputs)}"
            )
    for name in inputs:
        if name not in compiled.input_types:
            raise UnknownNameError(
                f"unknown input '{name}'{did_you_mean(name, compiled.input_types)}; "
                f"inputs: {', '.join(compiled.input_types) or 'none'}"
            )
    return wanted


def _given_inputs(
    compiled: CompiledGraph, schedule: Schedule, inputs: dict[str, Any]
) -> dict[str, Any]:
    """What is given for each graph input the wanted outputs read (step 2): value or default."""
    return {
        name: inputs.get(name, compiled.graph.inputs[name].default)
        for name in compiled.input_types
        if name in schedule.inputs
    }


def _referenced_inputs(
    compiled: CompiledGraph, given: dict[str, Any], registry: Registry
) -> dict[str, str]:
    """Input name -> key, for inputs given as a reference whose source keys it without loading.

    ``sample:astronaut`` is fixed by its name and scikit-image's version: the
    run keys it by that and loads it only if a node that reads it must run.
    """
    keys = {}
    for name, value in given.items():
        if not isinstance(value, str) or issubclass(compiled.input_types[name], TextPort):
            continue
        scheme, sep, rest = value.partition(":")
        spec = registry.sources.get(scheme) if sep else None
        if spec is None or spec.key is None:
            continue
        try:
            text = spec.key(rest)
        except Exception:  # loading reports the problem, with its message
            continue
        kind = compiled.input_types[name].type_name()
        digest = hashlib.blake2b(f"{kind}|{text}".encode(), digest_size=16).hexdigest()
        keys[name] = "r" + digest
    return keys


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
) -> _Run:
    """Steps 4 to 6: key, plan, schedule; the run's state, with its record, whatever happens.

    An executor made here is shut down here: after the run, or at once
    (without waiting for running nodes) when the run is interrupted.
    """
    own = isinstance(executor, str)
    pool = make_executor(executor, workers) if isinstance(executor, str) else executor
    state = _Run(compiled, cache, pool, hooks, RunRecord(compiled.graph.name, executor_name(pool)))
    began, failed = time.perf_counter(), True
    try:
        state.keep_intermediates = keep_intermediates
        state.key_inputs(values, reference_keys or {})
        state.key_steps(schedule.steps)
        sources = [compiled.outputs[o] for o in wanted]
        compute = state.plan(schedule.steps, sources)
        dependencies = state.prepare(compute, sources, schedule)
        for hook in hooks:
            hook.run_started(pipeline=compiled.graph.name, steps=compute)
        here = not state.encoded  # nodes run in this process: some may run in this thread
        # one BLAS thread while nodes run here, so a node's bits do not depend on its
        # neighbours (worker processes hold it for good; see graphvision._blas)
        with one_blas_thread() if here and compute else contextlib.nullcontext():
            skipped = run_tasks(
                dependencies,
                state.start,
                state.finish,
                keep_going=keep_going,
                run_here=state.run_here if here else None,
                quick=state.is_quick if here else None,
                limit=2 * executor_width(pool) if here else None,
                ahead=state.chained,
            )
        for step in skipped:  # downstream of a failure
            state.nodes[step].status = "skipped"
            if step in state.started:  # sent ahead (Dask): its start was reported, so its end is
                for hook in hooks:
                    hook.node_finished(
                        name=step, op=state.nodes[step].op, status="skipped", seconds=0.0
                    )
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
        state.record.nodes = [state.nodes[n] for n in compiled.steps if n in state.nodes]
        for hook in hooks:
            hook.run_finished(record=state.record, failed=failed)
    return state
