"""What a run yields: its record (per node: status, time, keys, sizes), its result
(outputs, failures, the compiled graph), and the hooks that observe it."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph, Step
from graphvision.errors import (
    GraphvisionError,
    NodeExecutionError,
)
from graphvision.execution.display import html_of
from graphvision.values.ports import PortType

__all__ = ["NodeRecord", "RunHooks", "RunRecord", "RunResult", "intermediates", "wrapped_failure"]


@dataclass(slots=True)
class NodeRecord:
    """What happened to one node: ``computed``, ``cached`` (loaded), ``failed``, ``skipped``
    (downstream of a failure), ``pending`` (the run stopped before it ran) or ``unneeded``
    (the requested outputs need it, but only through values loaded from the cache: a
    warm run does not run it; its ``keys`` are those its outputs would have).

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
    backend: str = "numpy"
    """The backend whose implementation of the op ran (or would run) the node."""


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
        rows = [("node", "op", "status", "ms", "bytes", "backend")]
        rows += [
            (n.name, n.op, n.status, f"{n.seconds * 1e3:.1f}", str(n.output_bytes), n.backend)
            for n in self.nodes
        ]
        widths = [max(len(r[i]) for r in rows) for i in range(6)]
        lines = [
            "  ".join(
                c.ljust(w) if i < 3 or i == 5 else c.rjust(w)
                for i, (c, w) in enumerate(zip(row, widths, strict=True))
            )
            for row in rows
        ]
        lines.append(
            f"{self.count('computed')} computed, {self.count('cached')} cached, "
            f"{self.count('failed')} failed, {self.count('skipped')} skipped"
            + (f", {unneeded} unneeded" if (unneeded := self.count("unneeded")) else "")
            + f" in {self.seconds:.3f} s ({self.executor})"
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
        """Shown by Jupyter when a result is the value of a cell (see :mod:`.display`)."""
        return html_of(self)


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


def intermediates(
    compiled: CompiledGraph, values: dict[tuple[str, str], Any]
) -> dict[str, tuple[type[PortType], Any]]:
    """Every node output held that is not a graph output (``keep_intermediates``), by
    ``node`` or ``node.port``."""
    steps, outputs = compiled.steps, set(compiled.outputs.values())
    return {
        (f"{name}.{port}" if len(steps[name].outputs) > 1 else name): (
            steps[name].outputs[port],
            value,
        )
        for (name, port), value in values.items()
        if name in steps and (name, port) not in outputs
    }


def wrapped_failure(
    step: Step, error: BaseException, values: dict[tuple[str, str], Any]
) -> NodeExecutionError:
    """A node's error as the run reports it: the node, its parameters, its inputs' summaries."""
    summary = {}
    for port, source in step.inputs.items():
        value = values.get(source)
        summary[port] = step.spec.inputs[port].type.summary(value) if value is not None else "?"
    wrapped = NodeExecutionError(
        step.name, step.spec.id, step.params, summary, f"{type(error).__name__}: {error}"
    )
    wrapped.__cause__ = error
    return wrapped
