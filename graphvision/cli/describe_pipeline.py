"""``graphvision describe PIPELINE.yaml``: what a pipeline takes and gives, without running it.

Its inputs (type, default), its parameters (default, where each is used and
the bounds those node parameters accept), its outputs (type, source) and the
families of its nodes. The pipeline is read as ``graph`` reads it: the
installed families it uses are loaded (their nodes' types and bounds), its own
``plugins:`` are listed, never imported (describing a pipeline runs none of its
code; ``validate``, which checks what ``run`` would run, imports them).
"""

from __future__ import annotations

import argparse
import json
import sys
import textwrap
from pathlib import Path
from typing import TYPE_CHECKING, Any

from graphvision.cli.common import registry_for
from graphvision.cli.exits import EXIT_OK

if TYPE_CHECKING:
    from graphvision.graph.model import Graph, Ref
    from graphvision.nodes.registry import Registry

PIPELINE_SUFFIXES = (".yaml", ".yml")


def names_a_pipeline(text: str) -> bool:
    """``describe``'s argument is a pipeline file: a YAML suffix, or an existing file."""
    return text.lower().endswith(PIPELINE_SUFFIXES) or Path(text).is_file()


def cmd_describe_pipeline(args: argparse.Namespace) -> int:
    from graphvision.graph.pipeline_file import load_pipeline

    graph = load_pipeline(args.op, allow_outside_plugins=args.allow_outside_plugins)
    registry = registry_for(args, graph, run_its_plugins=False)
    info = pipeline_description(graph, registry)
    if args.json:
        print(json.dumps(info, indent=2, default=str))
    else:
        print("\n".join(_text(info)))
    if info["problems"]:
        print(
            f"note: {args.op} is not valid as it stands ({len(info['problems'])} problem(s)); "
            f"`graphvision validate {args.op}` lists them",
            file=sys.stderr,
        )
    return EXIT_OK


def pipeline_description(graph: Graph, registry: Registry) -> dict[str, Any]:
    """Inputs, parameters, outputs and families of ``graph`` as JSON-able data."""
    from graphvision.compiler.compile import compile_graph
    from graphvision.errors import PipelineError

    problems: list[str] = []
    output_types: dict[str, str] = {}
    try:
        compiled = compile_graph(graph, registry)
        output_types = {name: compiled.output_type(name).type_name() for name in compiled.outputs}
    except PipelineError as error:
        problems = [str(problem) for problem in error.problems]
    return {
        "name": graph.name,
        "file": graph.source,
        "description": " ".join(graph.description.split()),
        "inputs": {
            name: {
                "type": decl.type,
                "default": decl.default,
                "description": decl.description,
                "truth_of": list(decl.truth_of),
            }
            for name, decl in graph.inputs.items()
        },
        "params": {
            name: {"default": value, "used_by": _uses(graph, registry, name)}
            for name, value in graph.params.items()
        },
        "outputs": {
            name: {
                "type": output_types.get(name) or _declared_type(graph, registry, ref),
                "from": str(ref),
            }
            for name, ref in graph.outputs.items()
        },
        "families": _families(graph, registry),
        "plugins": list(graph.plugins),
        "problems": problems,
    }


def _uses(graph: Graph, registry: Registry, name: str) -> list[dict[str, Any]]:
    """Each node parameter that takes ``${params.NAME}``, with the bounds its node accepts."""
    reference = f"${{params.{name}}}"
    uses = []
    for node, decl in graph.nodes.items():
        for param, value in decl.params.items():
            for path, text in _strings(value, f"{node}.{param}"):
                if reference not in text:
                    continue
                spec = registry.nodes.get(decl.op)
                whole = text.strip() == reference and path == f"{node}.{param}"
                schema = spec.params_schema()["properties"].get(param, {}) if spec else {}
                uses.append(
                    {"param": path, "op": decl.op, "accepts": _bounds(schema) if whole else ""}
                )
    return uses


def _strings(value: Any, path: str) -> list[tuple[str, str]]:
    """Every string inside a parameter value, with its place (``node.param.key.0``)."""
    if isinstance(value, str):
        return [(path, value)]
    if isinstance(value, dict):
        return [found for k, v in value.items() for found in _strings(v, f"{path}.{k}")]
    if isinstance(value, list):
        return [found for i, v in enumerate(value) for found in _strings(v, f"{path}.{i}")]
    return []


def _bounds(schema: dict[str, Any]) -> str:
    """A parameter's JSON schema in words: ``integer, 3 to 1001``, ``one of: dark, bright``."""
    if "anyOf" in schema:
        kinds = [_bounds(option) for option in schema["anyOf"]]
        return " or ".join(kind for kind in kinds if kind)
    if "enum" in schema:
        return "one of: " + ", ".join(str(v) for v in schema["enum"])
    if schema.get("type") == "null":
        return "null"
    kind = str(schema.get("type", "any value"))
    if "minimum" in schema and "maximum" in schema:
        return f"{kind} from {schema['minimum']} to {schema['maximum']}"
    signs = {"minimum": "≥", "exclusiveMinimum": ">", "maximum": "≤", "exclusiveMaximum": "<"}
    limits = [f"{sign} {schema[key]}" for key, sign in signs.items() if key in schema]
    return f"{kind} {' and '.join(limits)}" if limits else kind


def _declared_type(graph: Graph, registry: Registry, ref: Ref) -> str:
    """An output's type from its node's declaration, when the graph does not compile."""
    from graphvision.nodes.marks import SINGLE_OUTPUT

    node, port = ref.node, ref.port
    if node in graph.inputs:
        return graph.inputs[node].type
    spec = registry.nodes.get(graph.nodes[node].op) if node in graph.nodes else None
    kind = spec.outputs.get(port or SINGLE_OUTPUT) if spec else None
    return kind.type_name() if kind is not None else "unknown (its op is not loaded)"


def _families(graph: Graph, registry: Registry) -> dict[str, dict[str, Any]]:
    """Each family the nodes use: its nodes, and the plugin that provides it (if loaded)."""
    families: dict[str, dict[str, Any]] = {}
    for node, decl in graph.nodes.items():
        family = decl.op.partition(".")[0]
        entry = families.setdefault(family, {"plugin": "", "nodes": {}})
        entry["nodes"][node] = decl.op
        spec = registry.nodes.get(decl.op)
        if spec is not None:
            entry["plugin"] = spec.plugin
    return families


def _text(info: dict[str, Any]) -> list[str]:
    lines = [f"{info['name']} ({info['file']})" if info["file"] else info["name"]]
    if info["description"]:
        lines += textwrap.wrap(info["description"], 88, initial_indent="  ", subsequent_indent="  ")
    lines += ["", "inputs (-i NAME=VALUE):"]
    for name, entry in info["inputs"].items():
        default = "required" if entry["default"] is None else f"default {entry['default']}"
        truth = entry["truth_of"]
        truth_note = f", ground truth of {', '.join(truth)} (give it with them)" if truth else ""
        lines.append(f"  {name}: {entry['type']}, {default}{truth_note}")
    lines += [*([] if info["inputs"] else ["  none"]), "", "parameters (-s params.NAME=VALUE):"]
    for name, entry in info["params"].items():
        lines.append(f"  {name}: default {json.dumps(entry['default'], default=str)}")
        for use in entry["used_by"]:
            accepts = f": {use['accepts']}" if use["accepts"] else ""
            lines.append(f"    used by {use['param']} ({use['op']}){accepts}")
        if not entry["used_by"]:
            lines.append("    used by no node")
    if not info["params"]:
        lines.append("  none (any node's parameter: -s NODE.PARAM=VALUE)")
    lines += ["", "outputs (-o NAME):"]
    lines += [f"  {n}: {e['type']}, from {e['from']}" for n, e in info["outputs"].items()]
    lines += ["", f"nodes ({sum(len(f['nodes']) for f in info['families'].values())}) by family:"]
    for family, entry in info["families"].items():
        where = f"plugin {entry['plugin']}" if entry["plugin"] else "not loaded"
        nodes = ", ".join(f"{node} ({op})" for node, op in entry["nodes"].items())
        lines += textwrap.wrap(
            f"{family} ({where}): {nodes}",
            88,
            initial_indent="  ",
            subsequent_indent="    ",
            break_long_words=False,
            break_on_hyphens=False,
        )
    if info["plugins"]:
        lines += ["", "local plugins (listed, not imported): " + ", ".join(info["plugins"])]
    return lines
