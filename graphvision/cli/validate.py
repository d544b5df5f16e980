"""``graphvision validate``: check pipelines without running (or importing) anything."""

from __future__ import annotations

import argparse
import sys

from graphvision.cli.common import EXIT_OK, EXIT_USAGE, note_unread_plugins, registry_for


def cmd_validate(args: argparse.Namespace) -> int:
    from graphvision.compiler.compile import compile_graph
    from graphvision.errors import PipelineError
    from graphvision.graph.pipeline_file import load_pipeline

    status = EXIT_OK
    for path in args.pipelines:
        try:
            graph = load_pipeline(path, allow_outside_plugins=args.allow_outside_plugins)
            unread = note_unread_plugins(graph, args.plugins)
            registry = registry_for(args, graph, run_its_plugins=False)
            registry.unread_plugins = unread
            compile_graph(graph, registry)
            print(f"{path}: ok")
        except PipelineError as error:
            print(error, file=sys.stderr)
            status = EXIT_USAGE
    return status
