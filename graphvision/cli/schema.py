"""``graphvision schema``: the JSON Schema of pipeline files."""

from __future__ import annotations

import argparse

from graphvision.cli.exits import EXIT_OK


def cmd_schema(args: argparse.Namespace) -> int:
    import json

    from graphvision.graph.schema import pipeline_json_schema

    print(json.dumps(pipeline_json_schema(), indent=2))
    return EXIT_OK
