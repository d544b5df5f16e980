"""``graphvision graph``: draw a pipeline (SVG, DOT or Mermaid)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from graphvision.cli.common import EXIT_OK, note_unread_plugins, registry_for

if TYPE_CHECKING:
    pass


def cmd_graph(args: argparse.Namespace) -> int:
    from graphvision.compiler.compile import compile_graph
    from graphvision.graph.pipeline_file import load_pipeline
    from graphvision.graph.render import render

    graph = load_pipeline(args.pipeline, allow_outside_plugins=args.allow_outside_plugins)
    note_unread_plugins(graph, args.plugins)
    compile_graph(graph, registry_for(args, graph, run_its_plugins=False))
    print(render(graph, args.format))
    return EXIT_OK
