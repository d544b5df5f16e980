"""``graphvision validate``: check pipelines without running them.

A pipeline is checked against the ops ``run`` would find: its own ``plugins:`` are
imported as ``run`` imports them (only from inside its folder unless
``--allow-outside-plugins``, announced), so a pipeline ``run`` accepts is never refused
for an op of its plugins, and a plugin that fails to load is named with its file and line.
The inputs' defaults are loaded as ``run`` loads them: a mistyped ``sample:camra`` or a
missing file is refused at its line. ``-i NAME=VALUE`` stands in for an input's default
(one that has none, a placeholder, or one to try), read and loaded as ``run`` reads and
loads it: a value that does not load, or a name the pipeline does not declare, is refused.
"""

from __future__ import annotations

import argparse
import sys

from graphvision.cli.common import named_pairs, registry_for
from graphvision.cli.exits import EXIT_OK, EXIT_USAGE
from graphvision.cli.utf8_paths import refuse_paths_not_utf8


def cmd_validate(args: argparse.Namespace) -> int:
    from graphvision.compiler.compile import compile_graph
    from graphvision.errors import PipelineError
    from graphvision.execution.inputs import default_problems
    from graphvision.graph.pipeline_file import load_pipeline

    status = EXIT_OK
    inputs = named_pairs(args.input, "--input")
    for path in args.pipelines:
        refuse_paths_not_utf8(path, inputs)  # as `run` refuses them (its messages are UTF-8)
        try:
            graph = load_pipeline(path, allow_outside_plugins=args.allow_outside_plugins)
            registry = registry_for(args, graph)  # as `run` makes it: the same plugins
            compiled = compile_graph(graph, registry)
            problems = default_problems(graph, compiled.input_types, registry, inputs)
            if problems:  # each default, or value given instead, loaded as `run` loads it
                raise PipelineError(problems, path)
            print(f"{path}: ok")
        except PipelineError as error:
            print(error, file=sys.stderr)
            status = EXIT_USAGE
    return status
