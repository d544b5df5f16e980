"""The graph as the page draws it: nodes, edges, ops' documentation and parameter widgets.

Each parameter is sent with its JSON schema (the op's pydantic model), its current value,
and the key a change of it sets: ``node.param``, or ``params.NAME`` when the pipeline
file gives it as ``${params.NAME}`` (so saving writes the pipeline param back). An
integer parameter that must be odd (the shared ``OddSize`` check, which JSON Schema
cannot say) is marked ``x-odd`` by asking its validator about an even value.
"""

from __future__ import annotations

import inspect
import re
from typing import Any

import pydantic

from graphvision.compiler.compile import CompiledGraph, Step
from graphvision.graph.model import Graph

__all__ = ["describe_graph", "file_values", "param_widgets"]

_REFERENCE = re.compile(r"^\$\{params\.(\w+)\}$")


def describe_graph(graph: Graph, compiled: CompiledGraph, inputs: dict[str, Any]) -> dict:
    """JSON of the pipeline for the page (everything but values)."""
    nodes: list[dict[str, Any]] = []
    edges: list[dict[str, Any]] = []
    for name, decl in graph.inputs.items():
        given = inputs.get(name, decl.default)
        nodes.append(
            {"id": name, "kind": "input", "type": decl.type, "value": _text(given),
             "description": decl.description}
        )  # fmt: skip
    for name, step in compiled.steps.items():
        nodes.append(_node(graph, step))
        for port, (source, source_port) in step.inputs.items():
            edges.append({"from": source, "from_port": source_port, "to": name, "port": port})
    outputs = {
        name: [producer, port]
        for name, (producer, port) in compiled.outputs.items()
        if not name.startswith("studio__")
    }
    return {
        "name": graph.name,
        "description": graph.description,
        "source": graph.source,
        "params": graph.params,
        "nodes": nodes,
        "edges": edges,
        "outputs": outputs,
    }


def _node(graph: Graph, step: Step) -> dict[str, Any]:
    spec = step.spec
    return {
        "id": step.name,
        "kind": "node",
        "op": spec.id,
        "version": spec.version,
        "summary": spec.summary,
        "doc": inspect.cleandoc(spec.doc),
        "inputs": {port: p.type_label() for port, p in spec.inputs.items()},
        "outputs": {port: kind.type_name() for port, kind in step.outputs.items()},
        "params": param_widgets(graph, step),
    }


def param_widgets(graph: Graph, step: Step) -> list[dict[str, Any]]:
    """One entry per parameter: name, schema, current value, the key a change sets."""
    spec = step.spec
    schema = spec.params_schema()
    written = graph.nodes[step.name].params
    widgets = []
    for param, prop in schema.get("properties", {}).items():
        reference = _REFERENCE.match(str(written.get(param, "")))
        key = f"params.{reference.group(1)}" if reference else f"{step.name}.{param}"
        prop = _resolved(prop, schema)
        if prop.get("type") == "integer" and _must_be_odd(spec, param, step.params.get(param)):
            prop["x-odd"] = True
        widgets.append({"name": param, "schema": prop, "value": step.params.get(param),
                        "key": key})  # fmt: skip
    return widgets


def file_values(graph: Graph, compiled: CompiledGraph, keys: list[str]) -> dict[str, Any]:
    """The value each key (``node.param``, ``params.NAME``) has in the pipeline file (its
    default when the file does not write it): what a change set back to the file runs with,
    for the runs table (``0.2 → 0.5``). ``compiled`` is the file's graph, without overrides."""
    found = {}
    for key in keys:
        target, _, param = key.partition(".")
        if target == "params":
            found[key] = graph.params.get(param)
        elif target in compiled.steps:
            found[key] = compiled.steps[target].params.get(param)
    return found


def _resolved(prop: dict[str, Any], schema: dict[str, Any]) -> dict[str, Any]:
    """A property with its ``$ref`` (pydantic puts enums in ``$defs``) spelled out."""
    ref = prop.get("$ref") or next(
        (item.get("$ref") for item in prop.get("allOf", []) if "$ref" in item), None
    )
    if ref:
        target = schema.get("$defs", {}).get(ref.rsplit("/", 1)[-1], {})
        prop = {**target, **{k: v for k, v in prop.items() if k not in ("$ref", "allOf")}}
    return dict(prop)


def _must_be_odd(spec: Any, param: str, value: Any) -> bool:
    if not isinstance(value, int) or isinstance(value, bool):
        return False
    try:
        spec.params_model.model_validate({param: value + 1 if value % 2 else value})
    except pydantic.ValidationError as error:
        return any("odd" in str(item["msg"]) for item in error.errors())
    return False


def _text(value: Any) -> Any:
    return value if isinstance(value, str | int | float | bool) or value is None else str(value)
