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

import json
from pathlib import Path
from typing import Any

import pydantic
import yaml
from pydantic import BaseModel

from graphvision.errors import PipelineError, Problem, did_you_mean
from graphvision.graph.collector import collector_paused
from graphvision.graph.model import (
    NAME_PATTERN,
    REF_PATTERN,
    Graph,
    InputDecl,
    NodeDecl,
    Ref,
    output_name_problem,
)
from graphvision.graph.plugin_paths import PluginPaths, written_plugins
from graphvision.graph.schema import InputModel, NodeModel, PipelineModel
from graphvision.graph.yaml_reader import read_yaml

__all__ = [
    "dump_pipeline",
    "graph_to_dict",
    "load_pipeline",
    "parse_pipeline",
]


_SCALARS = (bool, int, float, str)
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
        at_key = item["loc"][-1:] == ("[key]",)  # the key itself, not the value under it
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
        elif item["type"] == "string_pattern_mismatch" and loc[0] == "outputs" and at_key:
            message = output_name_problem(loc[1])
        elif item["type"] == "string_pattern_mismatch":
            pattern = item.get("ctx", {}).get("pattern", "")
            message = _PATTERN_MESSAGES.get(pattern, message)
            if pattern == REF_PATTERN:  # a value: the place names its key, not it
                message += f", got {item['input']!r}"
        elif item["type"] == "too_short" and isinstance(item.get("input"), list):
            message = "an empty list: name at least one, or leave the key out"
        elif item["type"].endswith("_type") and isinstance(
            item.get("input"), bool | int | float | str
        ):
            message += f", got {json.dumps(item['input'])}{_yaml_number_hint(item['input'])}"
        line = 0
        parts = list(loc)
        while parts and not line:
            line = lines.get(".".join(parts), 0)
            parts.pop()
        problems.append(Problem(line, where, message, file))
    return problems


def _yaml_number_hint(value: object) -> str:
    """How to write a number YAML read as text: YAML 1.1 (PyYAML) takes ``1e-9`` and
    ``1.0e9`` for strings, since its floats need a dot and a signed exponent."""
    if not isinstance(value, str) or "e" not in value.lower():
        return ""
    try:
        float(value)
    except ValueError:
        return ""
    mantissa, exponent = value.lower().split("e", 1)
    mantissa += "" if "." in mantissa else ".0"
    exponent = exponent if exponent[:1] in "+-" else f"+{exponent}"
    return f" (YAML reads {value} as text: write {mantissa}e{exponent})"


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
    data, lines, problems = read_yaml(text, file)
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
        name: InputDecl(decl.type, decl.default, decl.description, list(decl.truth_of))
        for name, decl in model.inputs.items()
    }
    nodes = {
        name: NodeDecl(
            decl.op,
            {port: Ref.parse(ref) for port, ref in decl.in_.items()},
            dict(decl.params),
            decl.description,
            decl.timeout,
            list(decl.truth_of),
            decl.backend or "",
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
        backends=list(model.backends),
        source=file,
        lines=lines,
    )


def load_pipeline(path: str | Path, *, allow_outside_plugins: bool = False) -> Graph:
    """Read and parse a pipeline file; ``plugins:`` paths are resolved against its folder,
    and so are those added to ``graph.plugins`` later (:class:`~.plugin_paths.PluginPaths`).

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
        text = path.read_text(encoding="utf-8")  # YAML files are UTF-8, whatever the locale
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
        if not plugin.strip():  # Path("") is the current folder: every file in it would run
            problems.append(
                Problem(
                    graph.lines.get(f"plugins.{index}", graph.lines.get("plugins", 0)),
                    f"plugins.{index}",
                    "the plugin path is empty: name a plugin file or folder",
                    str(path),
                )
            )
        elif not allow_outside_plugins and not resolved.is_relative_to(folder):
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
    written, graph.plugins = graph.plugins, PluginPaths(folder=str(path.parent))
    graph.plugins.extend(written)  # placed in the file's folder, as those added later are
    return graph


def graph_to_dict(graph: Graph, path: str | Path | None = None) -> dict[str, Any]:
    """The canonical mapping of a graph, as written to YAML in the file ``path`` (its
    plugins named from there: :func:`~.plugin_paths.written_plugins`)."""
    data: dict[str, Any] = {"version": 1, "name": graph.name}
    if graph.description:
        data["description"] = graph.description
    if graph.plugins:
        data["plugins"] = written_plugins(graph.plugins, path)
    if graph.backends:
        data["backends"] = list(graph.backends)
    inputs = {}
    for name, decl in graph.inputs.items():
        entry: dict[str, Any] = {"type": decl.type}
        if decl.default is not None:
            entry["default"] = decl.default
        if decl.description:
            entry["description"] = decl.description
        if decl.truth_of:
            entry["truth_of"] = list(decl.truth_of)
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
        if node.timeout is not None:
            entry["timeout"] = node.timeout
        if node.truth_of:
            entry["truth_of"] = list(node.truth_of)
        if node.backend:
            entry["backend"] = node.backend
        nodes[name] = entry
    data["nodes"] = nodes
    data["outputs"] = {name: str(ref) for name, ref in graph.outputs.items()}
    return data


def dump_pipeline(graph: Graph, path: str | Path | None = None) -> str:
    """YAML text of ``graph``; :func:`parse_pipeline` reads it back to an equal graph.

    Parameters
    ----------
    graph : Graph
        The graph.
    path : str or Path, optional
        The file the text is for: its plugins are named from that file's folder (a plugin
        inside it relative to it, any other absolute: loading that file then asks for
        ``allow_outside_plugins``, as any pipeline whose plugins are outside its folder
        does). Without it, a loaded pipeline's plugins are named as its own file names
        them (relative to its folder: the text written beside it loads them), a built
        graph's as given.
    """
    data = graph_to_dict(graph, path)
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True, width=100)
