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

from ._errors import PipelineError, Problem, did_you_mean
from ._graph import NAME_PATTERN, REF_PATTERN, Graph, InputDecl, NodeDecl, Ref

__all__ = ["MAX_DEPTH", "dump_pipeline", "load_pipeline", "parse_pipeline", "pipeline_json_schema"]

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
    outputs: dict[str, Reference] = Field(description="Output name -> 'node' or 'node.port'.")


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
    """A file the reader will not expand: ``line`` and ``message`` say where and why."""

    def __init__(self, line: int, message: str) -> None:
        super().__init__(message)
        self.line, self.message = line, message


def _compose(text: str) -> tuple[yaml.Node | None, int]:
    """The document's node tree (aliases shared, not copied) and its node count.

    Iterative, so nesting deeper than :data:`MAX_DEPTH` is refused at the
    line where it happens instead of exhausting the interpreter's stack.
    """
    loader = _Loader(text)
    anchors: dict[str, yaml.Node] = {}
    stack: list[list[Any]] = []  # [collection node, pending mapping key]
    root: yaml.Node | None = None
    count = documents = 0

    def attach(node: yaml.Node) -> None:
        nonlocal root
        if not stack:
            root = node
        elif isinstance(stack[-1][0], yaml.SequenceNode):
            stack[-1][0].value.append(node)
        elif stack[-1][1] is None:
            stack[-1][1] = node
        else:
            stack[-1][0].value.append((stack[-1][1], node))
            stack[-1][1] = None

    try:
        while not loader.check_event(yaml.StreamEndEvent):
            event = loader.get_event()
            line = event.start_mark.line + 1
            if isinstance(event, yaml.DocumentStartEvent):
                documents += 1
                if documents > 1:
                    raise _RefusedError(line, "a pipeline file holds one YAML document")
            elif isinstance(event, yaml.AliasEvent):
                if event.anchor not in anchors:
                    raise _RefusedError(line, f"alias *{event.anchor} names no anchor before it")
                attach(anchors[event.anchor])
            elif isinstance(event, yaml.ScalarEvent):
                tag = loader.resolve(yaml.ScalarNode, event.value, event.implicit)
                node: yaml.Node = yaml.ScalarNode(
                    tag, event.value, event.start_mark, event.end_mark, event.style
                )
                count += 1
                if event.anchor:
                    anchors[event.anchor] = node
                attach(node)
            elif isinstance(event, yaml.SequenceStartEvent | yaml.MappingStartEvent):
                if len(stack) >= MAX_DEPTH:
                    raise _RefusedError(line, f"nested deeper than {MAX_DEPTH} levels")
                kind = (
                    yaml.SequenceNode
                    if isinstance(event, yaml.SequenceStartEvent)
                    else yaml.MappingNode
                )
                tag = loader.resolve(kind, None, event.implicit)
                node = kind(tag, [], event.start_mark, event.end_mark, event.flow_style)
                count += 1
                if event.anchor:
                    anchors[event.anchor] = node
                attach(node)
                stack.append([node, None])
            elif isinstance(event, yaml.SequenceEndEvent | yaml.MappingEndEvent):
                stack.pop()
    finally:
        loader.dispose()
    return root, count


class _Reader:
    """Python data from a node tree, counting every value and recording key lines."""

    def __init__(self, budget: int) -> None:
        self.budget = budget
        self.lines: dict[str, int] = {}
        self.problems: list[tuple[int, str, str]] = []
        self.scalars = yaml.SafeLoader("")

    def read(self, node: yaml.Node, path: list[str], depth: int = 0) -> Any:
        self.budget -= 1
        if self.budget < 0:
            raise _RefusedError(
                node.start_mark.line + 1,
                "the file expands to too many values (aliases of aliases?); refused",
            )
        if depth > MAX_DEPTH:
            raise _RefusedError(
                node.start_mark.line + 1, "an alias refers to itself, or nesting is too deep"
            )
        if isinstance(node, yaml.ScalarNode):
            try:
                return self.scalars.construct_object(node)
            except yaml.YAMLError as error:
                raise _RefusedError(node.start_mark.line + 1, f"bad value: {error}") from None
        if isinstance(node, yaml.SequenceNode):
            items = []
            for index, item in enumerate(node.value):
                self.lines.setdefault(".".join([*path, str(index)]), item.start_mark.line + 1)
                items.append(self.read(item, [*path, str(index)], depth + 1))
            return items
        mapping: dict[Any, Any] = {}
        merged: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            line = key_node.start_mark.line + 1
            if key_node.tag == _MERGE:  # `<<: *defaults` (explicit keys win)
                for source in (
                    value_node.value if isinstance(value_node, yaml.SequenceNode) else [value_node]
                ):
                    value = self.read(source, path, depth + 1)
                    if not isinstance(value, dict):
                        raise _RefusedError(line, "a merge key '<<' must name mappings")
                    merged = {**value, **merged}
                continue
            if not isinstance(key_node, yaml.ScalarNode):
                raise _RefusedError(line, "mapping keys must be plain values, not collections")
            key = self.read(key_node, path, depth + 1)
            where = ".".join([*path, str(key)])
            if key in mapping:
                self.problems.append((line, where, f"duplicate key '{key}'"))
            self.lines[where] = line
            mapping[key] = self.read(value_node, [*path, str(key)], depth + 1)
        return {**merged, **mapping}


def _read_yaml(text: str, file: str) -> tuple[Any, dict[str, int], list[Problem]]:
    """(data, key lines, duplicate-key problems), or PipelineError for unreadable YAML."""
    try:
        root, count = _compose(text)
        if root is None:
            return None, {}, []
        reader = _Reader(max(MIN_VALUE_BUDGET, 10 * count))
        data = reader.read(root, [])
    except _RefusedError as refused:
        raise PipelineError([Problem(refused.line, "yaml", refused.message, file)], file) from None
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        line = mark.line + 1 if mark else 0
        reason = getattr(error, "problem", None) or str(error)
        raise PipelineError(
            [Problem(line, "yaml", f"malformed YAML: {reason}", file)], file
        ) from None
    problems = [Problem(line, where, message, file) for line, where, message in reader.problems]
    return data, reader.lines, problems


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


def load_pipeline(path: str | Path) -> Graph:
    """Read and parse a pipeline file; ``plugins:`` paths are resolved against its folder.

    Raises
    ------
    PipelineError
        If the file cannot be read, or with every problem in it.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as error:
        raise PipelineError(
            [Problem(0, "file", f"cannot read pipeline: {error}", str(path))], str(path)
        ) from None
    graph = parse_pipeline(text, str(path))
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
