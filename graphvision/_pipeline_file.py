"""Pipeline files: YAML in, :class:`~graphvision.Graph` out, and back.

The file is checked in two steps. Here: YAML syntax, and the shape of each
section with one pydantic model per section (``extra="forbid"``). Then
:func:`graphvision.compile_graph` checks the graph against the registry. Both
steps report every problem at once, each with the file and line it comes from:
positions are read off the YAML node tree while loading.

The published JSON Schema (:func:`pipeline_json_schema`, ``graphvision
schema``) is generated from the same models, so an editor checks what the
loader checks.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Literal

import pydantic
import yaml
from pydantic import BaseModel, ConfigDict, Field

from ._errors import PipelineError, Problem, did_you_mean
from ._graph import Graph, InputDecl, NodeDecl, Ref

__all__ = ["dump_pipeline", "load_pipeline", "parse_pipeline", "pipeline_json_schema"]

REF_PATTERN = r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)?$"
NAME_PATTERN = r"^[A-Za-z_][A-Za-z0-9_]*$"


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True)


class InputModel(_Section):
    type: str = Field(description="Port type of the input, e.g. Image, GrayImage, Float.")
    default: Any = Field(
        None, description="Value used when the run gives none: a literal, a path, or 'sample:NAME'."
    )
    description: str = Field("", description="What the input is for.")


class NodeModel(_Section):
    op: str = Field(description="Id of the node to run, 'family.name' (see `graphvision nodes`).")
    in_: dict[str, str] = Field(
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
    inputs: dict[str, InputModel | str] = Field(
        default_factory=dict, description="Graph inputs: name -> {type, default} or a type name."
    )
    params: dict[str, Any] = Field(
        default_factory=dict, description="Pipeline-level values, used as '${params.NAME}'."
    )
    nodes: dict[str, NodeModel] = Field(description="The steps, by name.")
    outputs: dict[str, str] = Field(description="Output name -> 'node' or 'node.port'.")


def pipeline_json_schema() -> dict[str, Any]:
    """JSON Schema of pipeline files (for editors and ``graphvision schema``)."""
    schema = PipelineModel.model_json_schema(by_alias=True)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "graphvision pipeline"
    for section in ("nodes", "inputs"):
        schema["properties"][section]["propertyNames"] = {"pattern": NAME_PATTERN}
    schema["properties"]["outputs"]["additionalProperties"] = {
        "type": "string",
        "pattern": REF_PATTERN,
    }
    node = schema["$defs"]["NodeModel"]["properties"]["in"]
    node["additionalProperties"] = {"type": "string", "pattern": REF_PATTERN}
    return schema


def _positions(root: yaml.Node, problems: list[Problem], file: str) -> dict[str, int]:
    """Dotted path -> 1-based line, for every mapping key and sequence item."""
    lines: dict[str, int] = {}

    def walk(item: yaml.Node, path: list[str]) -> None:
        if isinstance(item, yaml.MappingNode):
            seen: set[str] = set()
            for key_node, value_node in item.value:
                key = str(key_node.value)
                where = ".".join([*path, key])
                if key in seen:
                    problems.append(
                        Problem(key_node.start_mark.line + 1, where, f"duplicate key '{key}'", file)
                    )
                seen.add(key)
                lines[where] = key_node.start_mark.line + 1
                walk(value_node, [*path, key])
        elif isinstance(item, yaml.SequenceNode):
            for index, value_node in enumerate(item.value):
                lines[".".join([*path, str(index)])] = value_node.start_mark.line + 1
                walk(value_node, [*path, str(index)])

    walk(root, [])
    return lines


def _model_problems(
    error: pydantic.ValidationError, lines: dict[str, int], file: str
) -> list[Problem]:
    problems = []
    for item in error.errors():
        loc = [str(p) for p in item["loc"] if not str(p).startswith(("InputModel", "str"))]
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
        line = 0
        parts = list(loc)
        while parts and not line:
            line = lines.get(".".join(parts), 0)
            parts.pop()
        problems.append(Problem(line, where, message, file))
    # pydantic reports a union (InputModel | str) failure twice; keep one per place
    unique = {(p.where, p.message): p for p in problems}
    return list(unique.values())


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
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        line = mark.line + 1 if mark else 0
        reason = getattr(error, "problem", None) or str(error)
        raise PipelineError(
            [Problem(line, "yaml", f"malformed YAML: {reason}", file)], file
        ) from None
    if not isinstance(data, dict) or root is None:
        raise PipelineError(
            [
                Problem(
                    1, "pipeline", "a pipeline file must be a YAML mapping (name, nodes, ...)", file
                )
            ],
            file,
        )
    problems: list[Problem] = []
    lines = _positions(root, problems, file)
    try:
        model = PipelineModel.model_validate(data)
    except pydantic.ValidationError as error:
        problems += _model_problems(error, lines, file)
        raise PipelineError(problems, file) from None
    for section in ("nodes", "inputs"):
        for name in getattr(model, section):
            if not isinstance(name, str) or not re.match(NAME_PATTERN, name):
                problems.append(
                    Problem(
                        lines.get(f"{section}.{name}", 0),
                        f"{section}.{name}",
                        "names must be identifiers (letters, digits, _)",
                        file,
                    )
                )
    if problems:
        raise PipelineError(problems, file)
    return _graph_from_model(model, file, lines)


def _graph_from_model(model: PipelineModel, file: str, lines: dict[str, int]) -> Graph:
    inputs = {
        name: InputDecl(decl)
        if isinstance(decl, str)
        else InputDecl(decl.type, decl.default, decl.description)
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
    for name, decl in graph.nodes.items():
        entry = {"op": decl.op}
        if decl.inputs:
            entry["in"] = {port: str(ref) for port, ref in decl.inputs.items()}
        if decl.params:
            entry["params"] = dict(decl.params)
        if decl.description:
            entry["description"] = decl.description
        nodes[name] = entry
    data["nodes"] = nodes
    data["outputs"] = {name: str(ref) for name, ref in graph.outputs.items()}
    return data


def dump_pipeline(graph: Graph) -> str:
    """YAML text of ``graph``; :func:`parse_pipeline` reads it back to an equal graph."""
    return yaml.safe_dump(graph_to_dict(graph), sort_keys=False, allow_unicode=True, width=100)
