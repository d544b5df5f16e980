"""One studio session: the pipeline, its current parameters, its runs, and the events they emit.

A change (:meth:`Session.change`) is validated first, against the whole graph (an invalid
value is refused with the validator's message, nothing runs); it then starts a run in a
thread of its own. Every run asks for every node's outputs (the session's graph names
each node port as an extra output), so a node the change does not reach is loaded from
the cache and its value is at hand for the viewers, while only the nodes downstream of
the change compute.

A newer change supersedes a run in flight (and the page's cancel button cancels it): the
run's hooks refuse to start any further node of it, its events are marked with its id so
the page ignores them, and its values are never mixed with the newer run's: each run
keeps its own values, looked up by run id. On the ``processes`` executor (the default)
nodes run in the session's worker processes (:mod:`.workers`): a node of the stopped run
still running has its worker killed at once, so no stale work keeps the CPU busy, and a
worker that dies fails its node alone, naming it. On ``threads`` or ``sync`` a node
already running finishes (Python cannot stop a thread); its result is cached, not shown.
"""

from __future__ import annotations

import copy
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from graphvision.cache.memory_store import MemoryStore
from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph, compile_graph
from graphvision.errors import GraphvisionError, PipelineError, Problem, RunError
from graphvision.execution.record import RunHooks, RunRecord
from graphvision.execution.run import run
from graphvision.graph.model import Graph, Ref
from graphvision.nodes.registry import Registry
from graphvision.studio.describe import file_values
from graphvision.studio.workers import WorkerPool

__all__ = ["KEPT_RUNS", "Session", "StudioRun", "Superseded"]

KEPT_RUNS = 12  # runs whose values stay in memory (for the viewers and comparisons)
_UNFINISHED = ("queued", "running")
_PREFIX = "studio__"


class _TapCache(Cache):
    """The session's cache, noting in each thread the values a node stores, so that the
    node's hook can hand its outputs to the page as soon as it finishes."""

    def __init__(self, inner: Cache) -> None:
        super().__init__(inner.memory, inner.disk)
        self.local = threading.local()

    def put(self, key: str, port_type: Any, value: Any) -> int:
        size = super().put(key, port_type, value)
        self.taken().append(value)
        return size

    def taken(self) -> list[Any]:
        if not hasattr(self.local, "values"):
            self.local.values = []
        values: list[Any] = self.local.values
        return values


class Superseded(BaseException):  # not an error: the control flow of a cancel
    """Raised by a run's hooks to stop it: a newer change was made, or the page cancelled it."""


@dataclass(eq=False)
class StudioRun:
    """One run of the session: what it ran with, what happened to each node, its values."""

    id: int
    overrides: dict[str, Any]
    inputs: dict[str, Any]
    diff: dict[str, list[Any]]
    file: dict[str, Any] = field(default_factory=dict)  # the file's value of a diff's None
    status: str = "running"  # running, done, failed, superseded, cancelled
    began: float = field(default_factory=time.time)
    seconds: float = 0.0
    nodes: dict[str, dict[str, Any]] = field(default_factory=dict)
    values: dict[tuple[str, str], Any] = field(default_factory=dict)
    metrics: dict[str, Any] = field(default_factory=dict)
    error: str = ""
    record: RunRecord | None = None
    compiled: CompiledGraph | None = None
    stop: bool = False
    killed: list[int] = field(default_factory=list)  # workers ended when it was stopped

    def summary(self) -> dict[str, Any]:
        """What the page lists about the run (JSON)."""
        return {
            "id": self.id,
            "status": self.status,
            "overrides": self.overrides,
            "diff": self.diff,
            "file": self.file,
            "seconds": self.seconds,
            "began": self.began,
            "metrics": self.metrics,
            "error": self.error,
            "nodes": self.nodes,
            "kept": bool(self.values),
        }


class _Hooks(RunHooks):
    """Turn a run's progress into session events; stop the run once it is superseded."""

    def __init__(self, session: Session, studio_run: StudioRun) -> None:
        self.session, self.run = session, studio_run
        # node -> the nodes it reads that have not finished: it was handed to the workers
        # ahead of them (it starts when they finish), and stays queued until then
        self.ahead: dict[str, set[str]] = {}

    def _check(self) -> None:
        if self.run.stop:
            raise Superseded

    def run_started(self, *, pipeline: str, steps: list[str]) -> None:
        self._check()
        for name in steps:
            self.run.nodes[name] = {"status": "queued"}
        self.session.emit({"event": "queued", "run": self.run.id, "nodes": steps})

    def node_started(self, *, name: str, op: str) -> None:
        self._check()
        compiled, nodes = self.run.compiled, self.run.nodes
        if compiled is not None:
            sources = {source for source, _ in compiled.steps[name].inputs.values()}
            unfinished = {s for s in sources if nodes.get(s, {}).get("status") in _UNFINISHED}
            if unfinished:
                self.ahead[name] = unfinished
                return
        self._running(name)

    def _running(self, name: str) -> None:
        self.run.nodes[name] = {"status": "running", "since": time.time()}
        self.session.emit({"event": "node", "run": self.run.id, "node": name, "status": "running"})

    def node_finished(self, *, name: str, op: str, status: str, seconds: float) -> None:
        stored = self.session.cache.taken()
        if self.run.stop and status == "failed":  # its worker was ended: not its failure
            self.run.nodes[name] = {"status": "stopped", "seconds": seconds}
            stored.clear()
            raise Superseded
        self.run.nodes[name] = {"status": status, "seconds": seconds, "ended": time.time()}
        streamed = False
        if status == "computed" and self.run.compiled is not None and not self.run.stop:
            ports = list(self.run.compiled.steps[name].outputs)
            if len(stored) == len(ports):  # its outputs, stored just now by this thread
                self.run.values.update({(name, p): v for p, v in zip(ports, stored, strict=True)})
                streamed = True
        stored.clear()
        event = {"event": "node", "run": self.run.id, "node": name, "status": status,
                 "seconds": seconds, "value": streamed}  # fmt: skip
        if streamed and self.session.describer is not None:
            # the descriptions of the ports the page shows ride the event: the page asks
            # for the pictures at once, and for no description (sub-millisecond to make)
            event["values"] = self.session.describer(self.run, name)
        self.session.emit(event)
        self._check()
        if status == "computed":  # the nodes handed over ahead of it that now run
            for waiting, unfinished in list(self.ahead.items()):
                unfinished.discard(name)
                if not unfinished:
                    del self.ahead[waiting]
                    self._running(waiting)


class Session:
    """A pipeline being tuned: current overrides and inputs, the runs made, event listeners.

    Parameters
    ----------
    graph : Graph
        The pipeline as loaded (its file is where parameters are saved back).
    registry : Registry
        The plugins it runs with.
    inputs, overrides : dict, optional
        Graph inputs and ``node.param`` overrides to start from (``-i`` and ``--set``).
    cache : Cache, optional
        Where values are kept between runs (default: 1 GiB in memory).
    executor : {"processes", "threads", "sync"}
        Where nodes run: ``processes`` (the session's own worker processes, ended when
        their run is superseded; see :mod:`.workers`), or in this process.
    workers : int, optional
        Worker processes (default: the machine's cores).
    """

    def __init__(
        self,
        graph: Graph,
        registry: Registry,
        *,
        inputs: dict[str, Any] | None = None,
        overrides: dict[str, Any] | None = None,
        cache: Cache | None = None,
        executor: str = "processes",
        workers: int | None = None,
    ) -> None:
        self.graph, self.registry, self.executor = graph, registry, executor
        self.inputs = dict(inputs or {})
        self.overrides = dict(overrides or {})
        self.cache = _TapCache(cache or Cache(MemoryStore(2**30)))
        self.studio_graph = _every_port_an_output(graph, registry)
        self.compiled = self.check(self.overrides)
        self.file_compiled = self.check({}) if self.overrides else self.compiled
        self.runs: list[StudioRun] = []
        self.listeners: list[Callable[[dict[str, Any]], None]] = []
        # run, node -> the descriptions its ``node`` event carries, by port (set by the app)
        self.describer: Callable[[StudioRun, str], dict[str, Any]] | None = None
        self.lock = threading.RLock()
        self.threads: list[threading.Thread] = []
        self.pool = None
        if executor == "processes":
            functions = [step.spec.ref for step in self.compiled.steps.values()]
            self.pool = WorkerPool(workers, warm=functions)

    # -- events -----------------------------------------------------------------------

    def emit(self, event: dict[str, Any]) -> None:
        event["time"] = time.time()
        for listener in list(self.listeners):
            listener(event)

    # -- changes ----------------------------------------------------------------------

    def check(self, overrides: dict[str, Any]) -> CompiledGraph:
        """The graph compiled with ``overrides``, or PipelineError naming every problem."""
        graph = self.studio_graph.with_overrides(overrides) if overrides else self.studio_graph
        return compile_graph(graph, self.registry, provided=set(self.inputs))

    def change(
        self, overrides: dict[str, Any] | None = None, inputs: dict[str, Any] | None = None
    ) -> StudioRun:
        """Apply parameter changes (``None`` resets to the file's value) and inputs, then
        start a run; PipelineError (nothing changed, nothing runs) if a value is refused."""
        merged = dict(self.overrides)
        for key, value in (overrides or {}).items():
            if value is None:
                merged.pop(key, None)
            else:
                merged[key] = value
        try:
            compiled = self.check(merged)
        except KeyError as error:
            raise PipelineError([Problem(0, "", str(error.args[0]))]) from None
        with self.lock:
            self.compiled, self.overrides = compiled, merged
            self.inputs.update(inputs or {})
            return self.start()

    def start(self) -> StudioRun:
        """Start a run with the current values, superseding the one in flight."""
        with self.lock:
            previous = self.runs[-1] if self.runs else None
            if previous is not None and previous.status == "running":
                previous.stop = True
                previous.status = "superseded"
                self._end_workers(previous, "superseded")
                self.emit({"event": "run", "run": previous.id, "status": "superseded"})
            diff = _diff(previous.overrides if previous else {}, self.overrides)
            keys = [key for key, pair in diff.items() if None in pair]
            file = file_values(self.graph, self.file_compiled, keys)
            studio_run = StudioRun(
                len(self.runs) + 1, dict(self.overrides), dict(self.inputs), diff, file
            )
            self.runs.append(studio_run)
            for old in self.runs[:-KEPT_RUNS]:
                old.values.clear()
            compiled = studio_run.compiled = self.compiled
            thread = threading.Thread(
                target=self._run, args=(studio_run, compiled), daemon=True, name="studio-run"
            )
            self.threads = [t for t in self.threads if t.is_alive()] + [thread]
        self.emit({"event": "run", "run": studio_run.id, "status": "running", "diff": diff,
                   "file": file})  # fmt: skip
        thread.start()
        return studio_run

    def cancel(self) -> StudioRun | None:
        """Stop the run in flight (no further node of it starts)."""
        with self.lock:
            current = self.runs[-1] if self.runs else None
            if current is None or current.status != "running":
                return None
            current.stop, current.status = True, "cancelled"
            self._end_workers(current, "cancelled")
        self.emit({"event": "run", "run": current.id, "status": "cancelled"})
        return current

    def _end_workers(self, studio_run: StudioRun, why: str) -> None:
        """Kill the workers still running nodes of a stopped run (processes only)."""
        if self.pool is not None:
            studio_run.killed = self.pool.end_run(studio_run.id, f"its run was {why}")

    def close(self) -> None:
        """Stop the run in flight and end the worker processes (the studio stops)."""
        self.cancel()
        if self.pool is not None:
            self.pool.close()

    def _run(self, studio_run: StudioRun, compiled: CompiledGraph) -> None:
        began = time.perf_counter()
        result = None
        executor = self.pool.executor(studio_run.id) if self.pool else self.executor
        try:
            result = run(
                compiled, self.registry, inputs=studio_run.inputs, cache=self.cache,
                executor=executor, hooks=[_Hooks(self, studio_run)], keep_going=True,
            )  # fmt: skip
        except Superseded:
            pass
        except RunError as error:
            result = error.result  # type: ignore[attr-defined]
            studio_run.error = str(error)
            for name, failure in error.failures.items():
                studio_run.nodes.setdefault(name, {})["error"] = str(failure)
        except GraphvisionError as error:  # an input deleted, a file unreadable...
            studio_run.error = str(error)
        except Exception as error:  # a worker that died, a bug: the server keeps serving
            studio_run.error = f"{type(error).__name__}: {error}"
        studio_run.seconds = time.perf_counter() - began
        if studio_run.stop:  # superseded or cancelled: none of its values are shown
            studio_run.values.clear()
        elif result is not None:
            self._keep(studio_run, result.outputs, result.record)
        if studio_run.status == "running":
            studio_run.status = "failed" if studio_run.error else "done"
        self.emit(
            {"event": "run", "run": studio_run.id, "status": studio_run.status,
             "error": studio_run.error, "seconds": studio_run.seconds,
             "metrics": studio_run.metrics, "nodes": studio_run.nodes,
             "kept": bool(studio_run.values)}
        )  # fmt: skip

    def _keep(self, studio_run: StudioRun, outputs: dict[str, Any], record: RunRecord) -> None:
        studio_run.record = record
        for name, value in outputs.items():
            if name.startswith(_PREFIX):
                node, port = name[len(_PREFIX) :].split("__", 1)
                studio_run.values[(node, port)] = value
            elif _is_scalar(value):
                studio_run.metrics[name] = _plain(value)
        for done in record.nodes:
            entry = studio_run.nodes.setdefault(done.name, {})
            entry.update(status=done.status, seconds=done.seconds, keys=done.keys)
            if done.error:
                entry.setdefault("error", done.error)

    # -- reading ----------------------------------------------------------------------

    def find_run(self, run_id: int) -> StudioRun:
        if not 1 <= run_id <= len(self.runs):
            raise KeyError(f"no run {run_id} in this session (runs: 1 to {len(self.runs)})")
        return self.runs[run_id - 1]

    def latest_with_values(self) -> StudioRun | None:
        for studio_run in reversed(self.runs):
            if studio_run.values:
                return studio_run
        return None

    def wait(self, timeout: float = 60.0) -> None:
        """Wait for the runs in flight (tests, scripts)."""
        for thread in list(self.threads):
            thread.join(timeout)


def _every_port_an_output(graph: Graph, registry: Registry) -> Graph:
    """A copy of ``graph`` that names every node's every output port as an extra output."""
    studio = copy.deepcopy(graph)
    plain = compile_graph(graph, registry, provided=None)
    for name, step in plain.steps.items():
        for port in step.outputs:
            studio.outputs[f"{_PREFIX}{name}__{port}"] = Ref(name, port)
    return studio


def _diff(before: dict[str, Any], after: dict[str, Any]) -> dict[str, list[Any]]:
    """``key: [old, new]`` for every override that differs (None: the file's value)."""
    keys = sorted(before.keys() | after.keys())
    return {k: [before.get(k), after.get(k)] for k in keys if before.get(k) != after.get(k)}


def _is_scalar(value: Any) -> bool:
    import numpy as np

    return isinstance(value, bool | int | float | str | np.generic)


def _plain(value: Any) -> Any:
    return value.item() if hasattr(value, "item") else value
