"""``graphvision report``: write a run folder's pages again from its record and files."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from graphvision.cli.common import registry_for
from graphvision.cli.exits import EXIT_OK


def cmd_report(args: argparse.Namespace) -> int:
    from graphvision.views.report import rewrite_report

    registry = registry_for(args) if args.plugins else None  # else: the pipeline's own
    page = rewrite_report(Path(args.directory), registry)
    print(f"wrote {page} and {page.with_name('report.md')}", file=sys.stderr)
    return EXIT_OK
