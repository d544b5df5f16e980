"""``graphvision validate``: check pipelines without running them.

A pipeline is checked against the ops ``run`` would find: its own ``plugins:`` are
imported as ``run`` imports them (only from inside its folder unless
``--allow-outside-plugins``, announced), so a pipeline ``run`` accepts is never refused
for an op of its plugins, and a plugin that fails to load is named with its file and line.
The inputs' defaults are loaded as ``run`` loads them: a mistyped ``sample:camra`` or a
missing file is refused at its line.
"""

from __future__ import annotations

import argparse
import sys

from graphvision.cli.common import EXIT_OK, EXIT_USAGE, refuse_paths_not_utf8, registry_for


def cmd_validate(args: argparse.Namespace) -> int:
    from graphvision.compiler.compile import compile_graph
    from graphvision.errors import PipelineError
    from graphvision.execution.inputs import default_problems
    from graphvision.graph.pipeline_file import load_pipeline

    status = EXIT_OK
    for path in args.pipelines:
        refuse_paths_not_utf8(path, {})  # as `run` refuses it (its messages name it in UTF-8)
        try:
            graph = load_pipeline(path, allow_outside_plugins=args.allow_outside_plugins)
            registry = registry_for(args, graph)  # as `run` makes it: the same plugins
            compiled = compile_graph(graph, registry)
            problems = default_problems(graph, compiled.input_types, registry)
            if problems:  # each default loaded as `run` loads it
                raise PipelineError(problems, path)
            print(f"{path}: ok")
        except PipelineError as error:
            print(error, file=sys.stderr)
            status = EXIT_USAGE
    return status
