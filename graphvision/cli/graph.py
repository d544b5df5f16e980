"""``graphvision graph``: draw a pipeline (SVG, DOT or Mermaid)."""

from __future__ import annotations

import argparse

from graphvision.cli.common import note_unread_plugins, registry_for
from graphvision.cli.exits import EXIT_OK


def cmd_graph(args: argparse.Namespace) -> int:
    from graphvision.compiler.compile import compile_graph
    from graphvision.graph.pipeline_file import load_pipeline
    from graphvision.graph.render import render

    graph = load_pipeline(args.pipeline, allow_outside_plugins=args.allow_outside_plugins)
    unread = note_unread_plugins(graph, args.plugins)
    registry = registry_for(args, graph, run_its_plugins=False)
    registry.unread_plugins = unread
    compile_graph(graph, registry)
    print(render(graph, args.format))
    return EXIT_OK
