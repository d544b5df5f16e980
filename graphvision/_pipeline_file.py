"""Pipeline files: YAML in, :class:`~graphvision.Graph` out, and back.

A file is read once. The YAML events are composed into a node tree by an
iterative composer that records every position and bounds the nesting
depth; the tree is then turned into Python data by one walk that records the
line of every key and counts every value it produces, aliases included, so a
"billion laughs" file (aliases of aliases) or a recursive alias is refused
in bounded time and memory, with the line of the offending alias. The data
is checked by one pydantic model per section (``extra="forbid"``, name and
reference patterns on the fields), and :func:`graphvision.compile_graph`
then checks the graph against the registry. Every problem is reported at
once, each with its file and line.

The published JSON Schema (:func:`pipeline_json_schema`, ``graphvision
schema``) is generated from the same models, so an editor checks what the
loader checks, by construction.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

import pydantic
import yaml
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, StringConstraints

from ._collector import collector_paused
from ._errors import PipelineError, Problem, did_you_mean
from ._graph import (
    NAME_PATTERN,
    REF_PATTERN,
    Graph,
    InputDecl,
    NodeDecl,
    Ref,
    output_name_problem,
)

__all__ = [
    "MAX_DEPTH",
    "dump_pipeline",
    "load_pipeline",
    "parse_pipeline",
    "parse_value",
    "pipeline_json_schema",
]

MAX_DEPTH = 64
"""Deepest nesting of mappings and sequences a pipeline file may have."""
MIN_VALUE_BUDGET = 100_000
"""Values a file may expand to through aliases, at least (10 per written value beyond)."""

Name = Annotated[str, StringConstraints(pattern=NAME_PATTERN)]
Reference = Annotated[str, StringConstraints(pattern=REF_PATTERN)]


_ONLY_NAMES: dict[str, Any] = {"additionalProperties": False}  # keys must match the name pattern


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True)


class InputModel(_Section):
    type: str = Field(description="Port type of the input, e.g. Image, GrayImage, Float.")
    default: Any = Field(
        None, description="Value used when the run gives none: a literal, a path, or 'sample:NAME'."
    )
    description: str = Field("", description="What the input is for.")


def _type_shorthand(value: Any) -> Any:
    """``image: Image`` is short for ``image: {type: Image}``."""
    return {"type": value} if isinstance(value, str) else value


Input = Annotated[
    InputModel, BeforeValidator(_type_shorthand, json_schema_input_type=InputModel | str)
]


class NodeModel(_Section):
    op: str = Field(description="Id of the node to run, 'family.name' (see `graphvision nodes`).")
    in_: dict[str, Reference] = Field(
        default_factory=dict,
        alias="in",
        description="Input port -> 'node', 'node.port' or a graph input name.",
    )
    params: dict[str, Any] = Field(
        default_factory=dict,
        description="Node parameters; '${params.NAME}' substitutes a pipeline param.",
    )
    description: str = Field("", description="What this step does in the pipeline.")


class PipelineModel(_Section):
    version: Literal[1] = Field(1, description="Pipeline file format version.")
    name: str = Field(description="Name of the pipeline.")
    description: str = Field("", description="What the pipeline does.")
    plugins: list[str] = Field(
        default_factory=list, description="Local plugin files or folders, relative to this file."
    )
    inputs: dict[Name, Input] = Field(
        default_factory=dict,
        description="Graph inputs: name -> {type, default} or a type name.",
        json_schema_extra=_ONLY_NAMES,
    )
    params: dict[str, Any] = Field(
        default_factory=dict, description="Pipeline-level values, used as '${params.NAME}'."
    )
    nodes: dict[Name, NodeModel] = Field(
        description="The steps, by name.", json_schema_extra=_ONLY_NAMES
    )
    outputs: dict[Name, Reference] = Field(
        description="Output name -> 'node' or 'node.port'; the name is the stem of its files.",
        json_schema_extra=_ONLY_NAMES,
    )


def pipeline_json_schema() -> dict[str, Any]:
    """JSON Schema of pipeline files (for editors and ``graphvision schema``)."""
    schema = PipelineModel.model_json_schema(by_alias=True)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "graphvision pipeline"
    return schema


# -- reading YAML once, bounded ----------------------------------------------------------

_Loader: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when installed
_MERGE = "tag:yaml.org,2002:merge"


class _RefusedError(Exception):
    """A file the reader will not read on: ``line`` and ``message`` say where and why."""

    def __init__(self, line: int, message: str) -> None:
        super().__init__(message)
        self.line, self.message = line, message


class _Open:
    """A mapping or sequence being read: its value, size so far, path, and pending key."""

    __slots__ = ("anchor", "key", "key_line", "merged", "path", "size", "value")

    def __init__(self, value: dict | list, path: list[str], anchor: str | None) -> None:
        self.value, self.path, self.anchor = value, path, anchor
        self.size = 1
        self.key: Any = _NO_KEY
        self.key_line = 0
        self.merged: dict[Any, Any] = {}


_NO_KEY = object()
_MERGE_KEY = object()


def _read_yaml(text: str, file: str) -> tuple[Any, dict[str, int], list[Problem]]:
    """(data, line of every key by dotted path, duplicate-key problems) from one pass.

    The YAML events are turned into Python values as they stream, with a
    stack instead of recursion (nesting beyond :data:`MAX_DEPTH` is refused
    at its line). An anchored value is kept with its size (how many values it
    holds); an alias reuses the value, shared rather than copied, and adds its
    size to the count of values the file expands to, which may not exceed
    ``max(MIN_VALUE_BUDGET, 10 × values written)``: a billion laughs is
    refused at the alias that crosses the bound, a recursive alias at once.
    """
    try:
        return _stream(text, file)
    except _RefusedError as refused:
        raise PipelineError([Problem(refused.line, "yaml", refused.message, file)], file) from None
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        line = mark.line + 1 if mark else 0
        reason = getattr(error, "problem", None) or str(error)
        raise PipelineError(
            [Problem(line, "yaml", f"malformed YAML: {reason}", file)], file
        ) from None


def _stream(text: str, file: str) -> tuple[Any, dict[str, int], list[Problem]]:
    loader = _Loader(text)
    anchors: dict[str, tuple[Any, int]] = {}
    open_anchors: set[str] = set()
    stack: list[_Open] = []
    lines: dict[str, int] = {}
    problems: list[Problem] = []
    root: Any = None
    written = expanded = documents = 0

    def attach(value: Any, size: int, line: int, is_scalar: bool) -> None:
        nonlocal root, expanded
        expanded += size
        if expanded > MIN_VALUE_BUDGET and expanded > 10 * written:
            raise _RefusedError(
                line, "the file expands to too many values (aliases of aliases?); refused"
            )
        if not stack:
            root = value
            return
        parent = stack[-1]
        parent.size += size
        if isinstance(parent.value, list):
            lines.setdefault(".".join([*parent.path, str(len(parent.value))]), line)
            parent.value.append(value)
        elif parent.key is _NO_KEY:
            if not is_scalar:
                raise _RefusedError(line, "mapping keys must be plain values, not collections")
            parent.key, parent.key_line = value, line
        else:
            key, parent.key = parent.key, _NO_KEY
            if key is _MERGE_KEY:  # `<<: *defaults` (explicit keys win)
                sources = value if isinstance(value, list) else [value]
                if not all(isinstance(source, dict) for source in sources):
                    raise _RefusedError(parent.key_line, "a merge key '<<' must name mappings")
                for source in sources:
                    parent.merged = {**source, **parent.merged}
                return
            where = ".".join([*parent.path, str(key)])
            if key in parent.value:
                problems.append(Problem(parent.key_line, where, f"duplicate key '{key}'", file))
            lines[where] = parent.key_line
            parent.value[key] = value

    def child_path() -> list[str]:
        if not stack:
            return []
        parent = stack[-1]
        if isinstance(parent.value, list):
            return [*parent.path, str(len(parent.value))]
        return [*parent.path, str(parent.key)]

    try:
        while not loader.check_event(yaml.StreamEndEvent):
            event = loader.get_event()
            kind = type(event)
            line = event.start_mark.line + 1
            if kind is yaml.ScalarEvent:
                written += 1
                value = _scalar(loader, event)
                if event.anchor:
                    anchors[event.anchor] = (value, 1)
                attach(value, 1, line, True)
            elif kind is yaml.MappingStartEvent or kind is yaml.SequenceStartEvent:
                written += 1
                if len(stack) >= MAX_DEPTH:
                    raise _RefusedError(line, f"nested deeper than {MAX_DEPTH} levels")
                container: dict | list = {} if kind is yaml.MappingStartEvent else []
                stack.append(_Open(container, child_path(), event.anchor))
                if event.anchor:
                    open_anchors.add(event.anchor)
            elif kind is yaml.MappingEndEvent or kind is yaml.SequenceEndEvent:
                done = stack.pop()
                value = done.value
                if done.merged and isinstance(value, dict):
                    value = {**done.merged, **value}
                if done.anchor:
                    open_anchors.discard(done.anchor)
                    anchors[done.anchor] = (value, done.size)
                attach(value, done.size, line, False)
            elif kind is yaml.AliasEvent:
                if event.anchor in open_anchors:
                    raise _RefusedError(line, f"alias *{event.anchor} refers to itself")
                if event.anchor not in anchors:
                    raise _RefusedError(line, f"alias *{event.anchor} names no anchor before it")
                value, size = anchors[event.anchor]
                attach(value, size, line, not isinstance(value, dict | list))
            elif kind is yaml.DocumentStartEvent:
                documents += 1
                if documents > 1:
                    raise _RefusedError(line, "a pipeline file holds one YAML document")
    finally:
        loader.dispose()
    return root, lines, problems


def _scalar(loader: Any, event: yaml.ScalarEvent) -> Any:
    """The Python value of a scalar event, as the safe loader would construct it."""
    if event.style and event.implicit[1]:  # quoted, no tag: a string as written
        return event.value
    tag = loader.resolve(yaml.ScalarNode, event.value, event.implicit)
    if tag == "tag:yaml.org,2002:str":
        return event.value
    if tag == _MERGE:
        return _MERGE_KEY
    node = yaml.ScalarNode(tag, event.value, event.start_mark, event.end_mark, event.style)
    return loader.construct_object(node)


def parse_value(text: str, where: str = "command line") -> Any:
    """One YAML value (``2``, ``true``, ``[1, 2]``, ``{a: 1}``), read with the same bounds.

    Raises
    ------
    PipelineError
        Naming what is wrong with the text.
    """
    data, _, problems = _read_yaml(text, where)
    if problems:
        raise PipelineError(problems, where)
    return data


# -- structure ------------------------------------------------------------------------

_PATTERN_MESSAGES = {
    NAME_PATTERN: "names must be identifiers (letters, digits, _)",
    REF_PATTERN: "a reference must be 'node' or 'node.port' (identifiers)",
}


def _model_problems(
    error: pydantic.ValidationError, lines: dict[str, int], file: str
) -> list[Problem]:
    problems = []
    for item in error.errors():
        loc = [str(p) for p in item["loc"] if p != "[key]"]
        where = ".".join(loc) or "pipeline"
        message = item["msg"]
        if item["type"] == "extra_forbidden":
            parent_model = _model_at(loc[:-1])
            options = (
                [f.alias or n for n, f in parent_model.model_fields.items()] if parent_model else []
            )
            message = f"unknown key '{loc[-1]}'{did_you_mean(loc[-1], options)}"
            if options:
                message += f"; allowed: {', '.join(options)}"
        elif item["type"] == "missing":
            message = f"missing required key '{loc[-1]}'"
        elif item["type"] == "string_pattern_mismatch" and loc[0] == "outputs" and len(loc) == 2:
            message = output_name_problem(loc[1])
        elif item["type"] == "string_pattern_mismatch":
            message = _PATTERN_MESSAGES.get(item.get("ctx", {}).get("pattern", ""), message)
        line = 0
        parts = list(loc)
        while parts and not line:
            line = lines.get(".".join(parts), 0)
            parts.pop()
        problems.append(Problem(line, where, message, file))
    return problems


def _model_at(loc: list[str]) -> type[BaseModel] | None:
    if not loc:
        return PipelineModel
    if loc[0] == "nodes" and len(loc) == 2:
        return NodeModel
    if loc[0] == "inputs" and len(loc) == 2:
        return InputModel
    return None


def parse_pipeline(text: str, file: str = "<string>") -> Graph:
    """Parse pipeline YAML text into a :class:`Graph`.

    Raises
    ------
    PipelineError
        With every syntax and structure problem, each located by file and line.
    """
    with collector_paused():
        return _parse(text, file)


def _parse(text: str, file: str) -> Graph:
    data, lines, problems = _read_yaml(text, file)
    if not isinstance(data, dict):
        raise PipelineError(
            [
                Problem(
                    1, "pipeline", "a pipeline file must be a YAML mapping (name, nodes, ...)", file
                )
            ],
            file,
        )
    try:
        model = PipelineModel.model_validate(data)
    except pydantic.ValidationError as error:
        problems += _model_problems(error, lines, file)
    if problems:
        raise PipelineError(problems, file)
    return _graph_from_model(model, file, lines)


def _graph_from_model(model: PipelineModel, file: str, lines: dict[str, int]) -> Graph:
    inputs = {
        name: InputDecl(decl.type, decl.default, decl.description)
        for name, decl in model.inputs.items()
    }
    nodes = {
        name: NodeDecl(
            decl.op,
            {port: Ref.parse(ref) for port, ref in decl.in_.items()},
            dict(decl.params),
            decl.description,
        )
        for name, decl in model.nodes.items()
    }
    return Graph(
        name=model.name,
        description=model.description,
        inputs=inputs,
        params=dict(model.params),
        nodes=nodes,
        outputs={name: Ref.parse(ref) for name, ref in model.outputs.items()},
        plugins=list(model.plugins),
        source=file,
        lines=lines,
    )


def load_pipeline(path: str | Path, *, allow_outside_plugins: bool = False) -> Graph:
    """Read and parse a pipeline file; ``plugins:`` paths are resolved against its folder.

    Reading a pipeline never runs its code: its ``plugins:`` are only listed
    here (``graph.plugins``); a run imports them. A plugin must lie inside the
    pipeline's folder (after symbolic links are followed), so that running a
    pipeline someone sent imports only the code that came with it.

    Parameters
    ----------
    path : str or Path
        The pipeline file.
    allow_outside_plugins : bool
        Accept ``plugins:`` outside the pipeline's folder (``../x.py``, absolute
        paths, links leading out): the command line's ``--allow-outside-plugins``.

    Raises
    ------
    PipelineError
        If the file cannot be read, or with every problem in it.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as error:
        reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
        problem = Problem(0, "file", f"cannot read pipeline: {reason}", str(path))
        raise PipelineError(
            [problem], str(path), f"cannot read pipeline {path}: {reason}"
        ) from None
    graph = parse_pipeline(text, str(path))
    folder = path.parent.resolve()
    problems = []
    for index, plugin in enumerate(graph.plugins):
        resolved = (folder / plugin).resolve()
        if not allow_outside_plugins and not resolved.is_relative_to(folder):
            problems.append(
                Problem(
                    graph.lines.get(f"plugins.{index}", graph.lines.get("plugins", 0)),
                    f"plugins.{index}",
                    f"plugin '{plugin}' is outside the pipeline's folder ({resolved}); a run "
                    "imports only plugins beside its pipeline: move it there, or pass "
                    "--allow-outside-plugins if you trust it",
                    str(path),
                )
            )
    if problems:
        raise PipelineError(problems, str(path))
    graph.plugins = [
        str(path.parent / p) if not Path(p).is_absolute() else p for p in graph.plugins
    ]
    return graph


def graph_to_dict(graph: Graph) -> dict[str, Any]:
    """The canonical mapping of a graph, as written to YAML."""
    data: dict[str, Any] = {"version": 1, "name": graph.name}
    if graph.description:
        data["description"] = graph.description
    if graph.plugins:
        data["plugins"] = list(graph.plugins)
    inputs = {}
    for name, decl in graph.inputs.items():
        entry: dict[str, Any] = {"type": decl.type}
        if decl.default is not None:
            entry["default"] = decl.default
        if decl.description:
            entry["description"] = decl.description
        inputs[name] = entry
    data["inputs"] = inputs
    if graph.params:
        data["params"] = dict(graph.params)
    nodes = {}
    for name, node in graph.nodes.items():
        entry = {"op": node.op}
        if node.inputs:
            entry["in"] = {port: str(ref) for port, ref in node.inputs.items()}
        if node.params:
            entry["params"] = dict(node.params)
        if node.description:
            entry["description"] = node.description
        nodes[name] = entry
    data["nodes"] = nodes
    data["outputs"] = {name: str(ref) for name, ref in graph.outputs.items()}
    return data


def dump_pipeline(graph: Graph) -> str:
    """YAML text of ``graph``; :func:`parse_pipeline` reads it back to an equal graph."""
    return yaml.safe_dump(graph_to_dict(graph), sort_keys=False, allow_unicode=True, width=100)
