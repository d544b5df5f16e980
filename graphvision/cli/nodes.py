"""``graphvision nodes`` and ``graphvision describe``: the registry, read from the plugin
index when it is current (no plugin is imported then)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from graphvision.cli.common import registry_for
from graphvision.cli.exits import EXIT_OK
from graphvision.errors import UnknownNameError, did_you_mean


def listed_nodes(
    args: argparse.Namespace,
) -> tuple[dict[str, str], Callable[[str], Any], dict[str, list[str]]]:
    """Each node's one-line summary by id, a function giving a node's description, and
    the backends other than the reference that implement each op.

    From the plugin index when it matches the installed plugins and no local
    plugin is asked for (no plugin is imported then), else by discovering them.
    """
    if not args.plugins:
        from graphvision.nodes.plugin_index import (
            environment_key,
            installed_entry_points,
            read_index,
        )

        indexed = read_index(environment_key(installed_entry_points()))
        if indexed is not None:
            summaries = {op: str(entry["summary"]) for op, entry in indexed.items()}
            others = {op: other_backends(entry["description"]) for op, entry in indexed.items()}
            return summaries, lambda op: indexed[op]["description"], others
    registry = registry_for(args)
    summaries = {op: spec.summary for op, spec in registry.nodes.items()}
    others = {op: other_backends(registry.describe(op)) for op in summaries}
    return summaries, registry.describe, others


def _mark(backend: str, info: dict[str, Any], long: bool) -> str:
    """``opencv``, ``opencv (not installed)`` or ``opencv (cannot run here)``: how a
    backend of an op's description is listed (``long``: with why it cannot run)."""
    if info.get("backends", {}).get(backend, True):
        return backend
    why = str(info.get("unavailable", {}).get(backend, ""))
    if not why or why.endswith("not found"):
        return f"{backend} (not installed)"
    return f"{backend} (cannot run here{': ' + why if long else ''})"


def other_backends(info: dict[str, Any]) -> list[str]:
    """The backends of an op's description but the reference, each that cannot run here
    marked (``graphvision nodes``)."""
    return [_mark(b, info, long=False) for b in info.get("backends", {}) if b != "numpy"]


def backends_text(info: dict[str, Any]) -> str:
    """``numpy, opencv`` with each backend that cannot run here marked, and why
    (``graphvision describe``)."""
    if not info.get("backends"):
        return "numpy"
    return ", ".join(_mark(b, info, long=True) for b in info["backends"])


def cmd_nodes(args: argparse.Namespace) -> int:
    import json

    summaries, describe, others = listed_nodes(args)
    if args.json:
        print(json.dumps({op: describe(op) for op in sorted(summaries)}, indent=2))
        return EXIT_OK
    families: dict[str, list[str]] = {}
    for op in sorted(summaries):
        families.setdefault(op.split(".", 1)[0], []).append(op)
    for family, ops in families.items():
        print(f"{family}")
        width = max(len(op) for op in ops)
        for op in ops:
            extra = f"  [+{', '.join(others[op])}]" if others.get(op) else ""
            print(f"  {op.ljust(width)}  {summaries[op]}{extra}")
    return EXIT_OK


def cmd_describe(args: argparse.Namespace) -> int:
    """``describe OP``, or ``describe PIPELINE.yaml`` (a YAML suffix or an existing file)."""
    import json

    from graphvision.cli.describe_pipeline import cmd_describe_pipeline, names_a_pipeline

    if names_a_pipeline(args.op):
        return cmd_describe_pipeline(args)
    summaries, describe, _ = listed_nodes(args)
    if args.op not in summaries:
        raise UnknownNameError(f"unknown op '{args.op}'{did_you_mean(args.op, summaries)}")
    info = describe(args.op)
    if args.json:
        print(json.dumps(info, indent=2))
        return EXIT_OK
    where = f"version {info['version']}, plugin {info['plugin']}, {info['function']}"
    print(f"{info['id']} ({where})\n")
    print(f"backends: {backends_text(info)}")
    if info.get("conformance"):  # how far another backend may be from the reference
        rule = info["conformance"]
        print(f"conformance: {rule['metric']} {rule['tolerance']}. {rule.get('note', '')}".strip())
    print("inputs:")
    for name, port in info["inputs"].items():
        print(f"  {name}: {port['type']}{' (optional)' if port['optional'] else ''}")
    print("outputs:")
    for name, kind in info["outputs"].items():
        print(f"  {name}: {kind}")
    print("parameters:")
    props = info["params"].get("properties", {})
    for name, schema in props.items():
        shown = {k: v for k, v in schema.items() if k not in ("title",)}
        print(f"  {name}: {json.dumps(shown)}")
    if not props:
        print("  none")
    print(f"\n{info['text']}")
    return EXIT_OK
