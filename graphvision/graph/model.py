"""The graph model: graph inputs, nodes, outputs, and a Python builder.

A :class:`Graph` is plain data (it names ops, it does not hold functions), so
it can be written to YAML and read back unchanged, and validated against any
registry. The YAML front door lives in :mod:`graphvision.graph.pipeline_file`; both
produce this same object.

::

    g = Graph("denoise")
    image = g.input("image", "Image", default="sample:camera")
    gray = g.add("gray", "colour.to_gray", image=image)
    blur = g.add("blur", "filters.gaussian", image=gray, params={"sigma": 1.5})
    g.output("smooth", blur)
"""

from __future__ import annotations

import copy
import os
import re
import sys
import types
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from graphvision.errors import Problem, did_you_mean
from graphvision.graph.plugin_paths import PluginPaths

if TYPE_CHECKING:
    import networkx as nx


__all__ = [
    "NAME",
    "NAME_PATTERN",
    "REF_PATTERN",
    "Graph",
    "InputDecl",
    "NodeDecl",
    "Ref",
    "output_name_problem",
    "parse_backends",
]

NAME_PATTERN = r"^[A-Za-z_][A-Za-z0-9_]*$"
"""Names of graph inputs and nodes: identifiers (the one place this rule is written)."""
REF_PATTERN = r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)?$"
"""References: ``node`` or ``node.port``."""
NAME = re.compile(NAME_PATTERN)


def output_name_problem(name: str) -> str:
    """Why ``name`` cannot name an output: its files would be written as ``<name>.png``
    and so on, and anything but a plain name could reach outside the output folder."""
    return (
        f"output name {name!r} must be a plain name (letters, digits, _): it names the "
        "output's files, which must stay inside the output folder"
    )


PARAM_REFERENCE = re.compile(r"\$\{params\.([A-Za-z_][A-Za-z0-9_]*)\}")
"""``${params.NAME}`` in a node parameter: a pipeline param substituted when compiling."""


def parse_backends(text: str | Sequence[str] | None) -> list[str]:
    """``"opencv,numpy"`` or ``["opencv", "numpy"]`` as a list of names (None: empty).

    Raises
    ------
    ValueError
        Naming an empty entry (``''``, ``"opencv,"``): a slip that would otherwise run
        the pipeline's own order, or the reference, without a word.
    """
    if text is None:
        return []
    items = text.split(",") if isinstance(text, str) else list(text)
    names = [str(item).strip() for item in items]
    if "" in names:
        position = names.index("") + 1
        raise ValueError(
            f"the backend order {','.join(names)!r} has an empty entry ({position} of "
            f"{len(names)}): name each backend once, separated by commas (e.g. opencv,numpy)"
        )
    return names


@dataclass(frozen=True)
class Ref:
    """A reference to a graph input or a node output: ``node`` or ``node.port``.

    ``port`` is None for a graph input and for the single output of a node.
    Index a reference to name a port: ``g.add(...)["mask"]``.
    """

    node: str
    port: str | None = None

    @classmethod
    def parse(cls, text: str) -> Ref:
        node, _, port = str(text).partition(".")
        return cls(node, port or None)

    def __getitem__(self, port: str) -> Ref:
        return Ref(self.node, port)

    def __str__(self) -> str:
        return self.node if self.port is None else f"{self.node}.{self.port}"


@dataclass
class InputDecl:
    """A graph input: its port type name, an optional default, a description, and the
    inputs it is the ground truth of (``truth_of``: see :mod:`graphvision.execution.truth`)."""

    type: str
    default: Any = None
    description: str = ""
    truth_of: list[str] = field(default_factory=list)


@dataclass
class NodeDecl:
    """One node of a graph: the op it runs, where its inputs come from, its parameters,
    its time limit in seconds (``timeout:``; None: the run's, if any), and the inputs
    whose defaults its truth goes with (``truth_of``: :mod:`graphvision.execution.truth`)."""

    op: str
    inputs: dict[str, Ref] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)
    description: str = ""
    timeout: float | None = None
    truth_of: list[str] = field(default_factory=list)
    backend: str = ""
    """The backend this node must run with ('' follows the run's lookup order)."""


@dataclass
class Graph:
    """A pipeline as data. Build it in Python or load it from YAML."""

    name: str
    description: str = ""
    inputs: dict[str, InputDecl] = field(default_factory=dict)
    params: dict[str, Any] = field(default_factory=dict)
    nodes: dict[str, NodeDecl] = field(default_factory=dict)
    outputs: dict[str, Ref] = field(default_factory=dict)
    plugins: list[str] = field(default_factory=list)
    backends: list[str] = field(default_factory=list)
    """The backend lookup order of the pipeline (empty: the reference, ``numpy``)."""
    # Where the graph came from, for error messages; not part of equality.
    source: str = field(default="", compare=False)
    # Pipeline params whose ${params.NAME} references an override replaced: not "unused".
    overridden_params: set[str] = field(default_factory=set, compare=False, repr=False)
    # "node.param" -> the value an override set (so a problem with it names the override)
    overrides_applied: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)
    lines: dict[str, int] = field(default_factory=dict, compare=False, repr=False)
    # "nodes.NAME", "inputs.NAME", "outputs.NAME" -> (file, line) of the Python call that
    # added it (not from the YAML of ``source``: its problems are placed at the call)
    added_in_python: dict[str, tuple[str, int]] = field(
        default_factory=dict, compare=False, repr=False
    )

    def __setattr__(self, name: str, value: Any) -> None:
        """``plugins`` is held as a :class:`~.plugin_paths.PluginPaths`: a list given to a
        loaded pipeline's ``plugins`` is read from its file's folder, as the paths appended
        to it are; each item must be a path, and one path in place of the list is refused
        (it was taken letter by letter: ``.`` the pipeline's folder, ``/`` the root)."""
        if name == "plugins" and not isinstance(value, PluginPaths):
            held = self.__dict__.get("plugins")
            value, given = PluginPaths(folder=getattr(held, "folder", "")), value
            value.extend(given)
        object.__setattr__(self, name, value)

    # -- builder ------------------------------------------------------------------

    def input(
        self,
        name: str,
        type: str,
        default: Any = None,
        description: str = "",
        truth_of: list[str] | None = None,
    ) -> Ref:
        """Declare a graph input and return a reference to it; ``truth_of`` names the inputs
        it is the ground truth of (its default holds for their defaults only)."""
        self._check_new_name(name)
        self.inputs[name] = InputDecl(type, default, description, list(truth_of or []))
        self.added_in_python[f"inputs.{name}"] = _caller(self)
        return Ref(name)

    def add(
        self,
        name: str,
        op: str,
        /,
        params: dict[str, Any] | None = None,
        backend: str = "",
        **inputs: Ref | str,
    ) -> Ref:
        """Add node ``name`` running ``op``; keyword arguments connect its input ports;
        ``backend`` pins the implementation it runs (see :mod:`graphvision.nodes.backends`)."""
        self._check_new_name(name)
        refs = {
            port: ref if isinstance(ref, Ref) else Ref.parse(ref) for port, ref in inputs.items()
        }
        self.nodes[name] = NodeDecl(op, refs, dict(params or {}), backend=backend)
        self.added_in_python[f"nodes.{name}"] = _caller(self)
        return Ref(name)

    def output(self, name: str, ref: Ref | str) -> None:
        """Name ``ref`` as the graph output ``name``.

        An output's name becomes the stem of its files in an output folder, so
        it must be a plain identifier (no ``..``, separator or absolute path).
        """
        if not NAME.match(name):
            raise ValueError(output_name_problem(name))
        self.outputs[name] = ref if isinstance(ref, Ref) else Ref.parse(ref)
        self.added_in_python[f"outputs.{name}"] = _caller(self)

    def _check_new_name(self, name: str) -> None:
        if not NAME.match(name):
            raise ValueError(f"name '{name}' must be an identifier (letters, digits, _)")
        if name in self.inputs or name in self.nodes:
            raise ValueError(f"name '{name}' is already used in graph '{self.name}'")

    # -- views --------------------------------------------------------------------

    def _repr_svg_(self) -> str:
        """The graph's drawing, shown by Jupyter when a graph is the value of a cell."""
        from graphvision.graph.svg import graph_svg

        return graph_svg(self)

    def to_networkx(self) -> nx.DiGraph:
        """Nodes and graph inputs as vertices, one edge per connection (port names on edges)."""
        import networkx as nx  # imported on use: start-up of the CLI stays fast

        graph = nx.DiGraph()
        for name, input_decl in self.inputs.items():
            graph.add_node(name, kind="input", type=input_decl.type)
        for name, node_decl in self.nodes.items():
            graph.add_node(name, kind="node", op=node_decl.op)
        for name, node_decl in self.nodes.items():
            for port, ref in node_decl.inputs.items():
                if ref.node in graph:
                    graph.add_edge(ref.node, name, port=port, source_port=ref.port)
        return graph

    def with_overrides(self, overrides: dict[str, Any]) -> Graph:
        """A copy with ``{"node.param": value}`` set (``params.x`` sets a pipeline param).

        Raises
        ------
        KeyError
            Naming the first override whose node does not exist.
        """
        graph = copy.deepcopy(self)
        for key, value in overrides.items():
            target, _, param = key.partition(".")
            if not param:
                raise KeyError(f"override '{key}' must be node.param or params.name")
            if target == "params":
                graph.params[param] = value
                graph.overrides_applied[key] = value
            elif target in graph.nodes:
                old = graph.nodes[target].params.get(param)
                graph.overridden_params.update(PARAM_REFERENCE.findall(str(old)) if old else ())
                graph.nodes[target].params[param] = value
                graph.overrides_applied[key] = value
            else:
                raise KeyError(
                    f"override '{key}': no node '{target}'{did_you_mean(target, graph.nodes)}"
                )
        return graph

    def truth_problems(self) -> list[tuple[str, str]]:
        """(where, message) for each ``truth_of`` name that is not an input of the
        pipeline (not the input itself, on an input) or is named twice."""
        marked = [(f"inputs.{n}", n, d.truth_of) for n, d in self.inputs.items()] + [
            (f"nodes.{n}", n, d.truth_of) for n, d in self.nodes.items()
        ]
        problems = []
        for where, name, subjects in marked:
            others = [other for other in self.inputs if other != name]
            for subject in (s for s in subjects if s not in others):
                listed = f"{did_you_mean(subject, others)}; inputs: {', '.join(others) or 'none'}"
                problems.append((f"{where}.truth_of", f"'{subject}' is not another input{listed}"))
            for subject in sorted({s for s in subjects if subjects.count(s) > 1}):
                problems.append((f"{where}.truth_of", f"'{subject}' is named twice"))
        return problems

    def with_backends(self, backends: Sequence[str] | str | None) -> Graph:
        """A copy whose backend lookup order is ``backends`` (``"opencv,numpy"`` or a list;
        None: this graph itself). The order given for a run replaces the file's
        ``backends:``, so a problem with it is not placed at that line. An empty entry is a
        ValueError (:func:`parse_backends`), on every path: runs, batches, sweeps."""
        if backends is None:
            return self
        graph = copy.deepcopy(self)
        graph.backends = parse_backends(backends)
        graph.lines = {k: v for k, v in graph.lines.items() if k.partition(".")[0] != "backends"}
        return graph

    def problem(self, where: str, message: str) -> Problem:
        """A problem at the dotted location ``where``: at its YAML line, or, for a node, an
        input or an output added in Python, at the call that added it (named so)."""
        added = self.added_in_python.get(".".join(where.split(".")[:2]))
        if added is not None:
            return Problem(added[1], where, message, added[0], "added in Python")
        return Problem(self.line_of(where), where, message, self.source)

    def line_of(self, where: str) -> int:
        """The YAML line of the dotted location ``where`` (or of its closest parent)."""
        parts = where.split(".")
        while parts:
            line = self.lines.get(".".join(parts))
            if line:
                return line
            parts.pop()
        return 0


_ENGINE = os.path.join(Path(__file__).resolve().parent.parent, "")  # its files, not a sibling's


def _caller(graph: Graph) -> tuple[str, int]:
    """The file and line of the user's call (a script or a notebook cell) that added a part
    to ``graph`` through the builder method that calls this; ("", 0) if there is none.

    That is the first caller outside graphvision, unless it is a helper the graph was
    passed to (``def smooth(graph, name, sigma): return graph.add(...)``): then the call
    of the helper, going out while the graph is an argument of the function, so that each
    node a helper adds is placed where its own name and parameters were given. A builder
    that holds the graph itself (made there, or an attribute) is where its ``add`` is.
    """
    frame = sys._getframe(2)
    while frame is not None and frame.f_code.co_filename.startswith(_ENGINE):
        frame = frame.f_back  # type: ignore[assignment]
    while frame is not None and _passed(frame, graph):
        outer = frame.f_back
        if outer is None or outer.f_code.co_filename.startswith(_ENGINE):
            break
        frame = outer
    return (frame.f_code.co_filename, frame.f_lineno) if frame is not None else ("", 0)


def _passed(frame: types.FrameType, graph: Graph) -> bool:
    """Whether ``graph`` is one of the arguments of the function ``frame`` runs."""
    code = frame.f_code
    count = code.co_argcount + code.co_kwonlyargcount
    names = code.co_varnames[:count]
    return any(frame.f_locals.get(name) is graph for name in names)
