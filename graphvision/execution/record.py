"""What a run yields: its record (per node: status, time, keys, sizes), its result
(outputs, failures, the compiled graph), and the hooks that observe it."""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, fields, is_dataclass
from json.encoder import encode_basestring_ascii
from typing import Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph, Step
from graphvision.errors import GraphvisionError, NodeExecutionError, error_text
from graphvision.execution.display import html_of
from graphvision.nodes.loading import plugin_line
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
        """The record as JSON indented by 2: ``json.dumps(dataclasses.asdict(record),
        indent=2)`` (each node an object, fields in their order), built field by field
        (``asdict`` deep-copies every value before ``json`` reads it) and written by
        :func:`_indented` (``json``'s indenting encoder is its pure-Python one): together
        four fifths of a batch file's record."""
        data = {name: getattr(self, name) for name in _RUN_FIELDS}
        data["nodes"] = [
            {name: getattr(node, name) for name in _NODE_FIELDS} for node in self.nodes
        ]
        return _indented(data)

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


_RUN_FIELDS = tuple(f.name for f in fields(RunRecord))
_NODE_FIELDS = tuple(f.name for f in fields(NodeRecord))


def _json_default(value: Any) -> Any:
    """Parameters JSON cannot hold as they are: numpy values, tuples' items, paths; a
    dataclass as :func:`dataclasses.asdict` makes it (as the record's own fields)."""
    if isinstance(value, np.generic | np.ndarray):
        return value.tolist()
    if is_dataclass(value) and not isinstance(value, type):
        return asdict(value)
    return str(value)


_FLOATS = {math.inf: "Infinity", -math.inf: "-Infinity"}


def _indented(value: Any, indent: str = "\n") -> str:
    """``json.dumps(value, indent=2, default=_json_default)``, the same text, from one
    recursive function in place of ``json``'s generators (3 times faster on a record):
    the same tests in the same order (a bool before an int, a float subclass as a float,
    anything else through :func:`_json_default`), ASCII strings, NaN and infinities as
    ``json`` writes them, ``": "`` after a key and ``","`` ending a line. A value that
    holds itself is not refused by name (``json``'s ``Circular reference``): a record
    never does."""
    if isinstance(value, str):
        return encode_basestring_ascii(value)
    if value is None or value is True or value is False:
        return "null" if value is None else "true" if value else "false"
    if isinstance(value, int):
        return int.__repr__(value)
    if isinstance(value, float):
        return "NaN" if value != value else _FLOATS.get(value) or float.__repr__(value)
    inner = indent + "  "
    if isinstance(value, list | tuple):
        items = [inner + _indented(item, inner) for item in value]
        return f"[{','.join(items)}{indent}]" if items else "[]"
    if isinstance(value, dict):
        items = [f"{inner}{_key(key)}: {_indented(item, inner)}" for key, item in value.items()]
        return f"{{{','.join(items)}{indent}}}" if items else "{}"
    return _indented(_json_default(value), indent)


def _key(key: Any) -> str:
    """A dictionary key as ``json`` writes it: a string, or a number, bool or None as text."""
    if isinstance(key, str):
        return encode_basestring_ascii(key)
    if key is None or isinstance(key, bool | int | float):
        return encode_basestring_ascii(json.dumps(key))
    raise TypeError(f"keys must be str, int, float, bool or None, not {type(key).__name__}")


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
    """A node's error as the run reports it: the node, its parameters, its inputs' summaries,
    and the line of a local plugin it came from (``NameError: ... (/me/my_nodes.py:17)``)."""
    summary = {}
    for port, source in step.inputs.items():
        value = values.get(source)
        summary[port] = step.spec.inputs[port].type.summary(value) if value is not None else "?"
    wrapped = NodeExecutionError(
        step.name,
        step.spec.id,
        step.params,
        summary,
        f"{error_text(error)}{plugin_line(error)}",
    )
    wrapped.__cause__ = error
    return wrapped
