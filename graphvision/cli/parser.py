"""The argument parser: global options, shared run options, one sub-parser per command."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from graphvision.cli.cache import cmd_cache
from graphvision.cli.common import (
    CACHE_DIR_HELP,
    EXECUTORS,
    Parser,
    byte_size,
    path_text,
    pixel_count,
    positive_int,
    positive_seconds,
)
from graphvision.cli.graph import cmd_graph
from graphvision.cli.nodes import cmd_describe, cmd_nodes
from graphvision.cli.report import cmd_report
from graphvision.cli.run import cmd_run
from graphvision.cli.schema import cmd_schema
from graphvision.cli.studio import cmd_studio, studio_options
from graphvision.cli.sweep import cmd_sweep
from graphvision.cli.validate import cmd_validate


def global_options(parser: argparse.ArgumentParser, top: bool) -> None:
    """``--plugins`` and ``--debug``, accepted before and after the sub-command.

    The sub-commands' copies default to SUPPRESS, so that a value given before
    the sub-command is not reset by the sub-command's default.
    """
    parser.add_argument(
        "--plugins",
        action="append",
        default=[] if top else argparse.SUPPRESS,
        type=path_text,
        metavar="PATH",
        help="load a local plugin file or folder (repeatable)",
    )
    parser.add_argument(
        "--allow-outside-plugins",
        action="store_true",
        default=False if top else argparse.SUPPRESS,
        help="let a pipeline's plugins: name files outside its folder (they run its code)",
    )
    parser.add_argument(
        "--debug",
        action="store_true",
        default=False if top else argparse.SUPPRESS,
        help="show Python tracebacks",
    )


def cache_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--cache-dir", type=path_text, metavar="DIR", help=f"disk cache folder ({CACHE_DIR_HELP})"
    )
    parser.add_argument(
        "--cache-max-bytes",
        type=byte_size,
        default=4 * 2**30,
        metavar="SIZE",
        help="disk cache bound, e.g. 500M, 4G (default 4G)",
    )


def limit_options(parser: argparse.ArgumentParser) -> None:
    """``--max-memory``, ``--node-timeout``, ``--node-memory`` (shared by ``run`` and ``sweep``)."""
    parser.add_argument(
        "--max-memory",
        type=byte_size,
        metavar="SIZE",
        help="memory a run may take, e.g. 8G (default: what is available); a run whose peak, "
        "estimated from its inputs before it starts, exceeds it is refused",
    )
    parser.add_argument(
        "--node-timeout",
        type=positive_seconds,
        metavar="SECONDS",
        help="a node running longer fails alone (a node's own timeout: may be lower)",
    )
    parser.add_argument(
        "--node-memory",
        type=byte_size,
        metavar="SIZE",
        help="with --executor processes: memory a node may allocate in its worker, e.g. 2G; "
        "a node over it fails alone",
    )


def backend_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--backend",
        metavar="NAMES",
        help="backend lookup order, e.g. opencv,numpy: each node runs the first implementation "
        "of its op found (default: the pipeline's backends:, else numpy, the reference)",
    )


def input_option(parser: argparse.ArgumentParser) -> None:
    """``--input NAME=VALUE`` (``-i``): of ``run``, ``sweep``, ``studio`` and ``validate``,
    read by :func:`~graphvision.cli.common.named_pairs`."""
    parser.add_argument(
        "--input",
        "-i",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="graph input: a path, sample:NAME, or a literal",
    )


def run_options(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``run`` and ``sweep``."""
    parser.add_argument("pipeline", type=path_text, help="the pipeline file (YAML)")
    parser.add_argument(
        "--max-pixels",
        type=pixel_count,
        metavar="N",
        help="pixel budget of every image and array read (default 100000000; files that "
        "declare more are refused before they are decoded)",
    )
    limit_options(parser)
    input_option(parser)
    parser.add_argument(
        "--set",
        "-s",
        action="append",
        default=[],
        metavar="NODE.PARAM=VALUE",
        help="override a node parameter (params.NAME for a pipeline param); VALUE is YAML",
    )
    parser.add_argument(
        "--executor",
        choices=EXECUTORS,
        default="threads",
        help="where nodes run: threads (default), sync, processes, or dask",
    )
    parser.add_argument(
        "--workers",
        type=positive_int,
        default=None,
        metavar="N",
        help="threads or processes (default: the number of cores); dask: local workers (2)",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="with --executor dask: an existing scheduler, tcp://HOST:PORT "
        "(default $GRAPHVISION_DASK_SCHEDULER, else a local cluster)",
    )
    backend_option(parser)
    parser.add_argument("--no-cache", action="store_true", help="neither read nor write the cache")
    parser.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="show progress (default: when stderr is a terminal; batches and sweeps print a "
        "line per file or combination elsewhere)",
    )
    parser.add_argument(
        "--keep-going",
        action="store_true",
        help="after a node fails, finish every branch that does not depend on it",
    )
    cache_options(parser)


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="graphvision", description="Run classical computer-vision pipelines.")
    parser.add_argument("--version", action="version", version=f"graphvision {version()}")
    global_options(parser, top=True)
    commands = parser.add_subparsers(dest="command", parser_class=Parser, metavar="COMMAND")

    def command(name: str, help: str) -> argparse.ArgumentParser:
        sub = commands.add_parser(name, help=help, description=help)
        global_options(sub, top=False)
        return sub

    for add in (_run, _sweep, _studio, _validate, _registry_commands, _graph_and_report, _cache):
        add(command)
    return parser


Command = Callable[[str, str], argparse.ArgumentParser]


def _run(command: Command) -> None:
    p = command("run", "run a pipeline (once, or once per file with --batch)")
    run_options(p)
    p.add_argument(
        "--output",
        "-o",
        action="append",
        metavar="NAME",
        help="produce only this output (repeatable); only what it needs runs",
    )
    p.add_argument(
        "--output-dir",
        "-d",
        type=path_text,
        metavar="DIR",
        help="write outputs, record, report.md, report.html",
    )
    p.add_argument(
        "--batch",
        action="append",
        default=[],
        metavar="NAME=GLOB",
        help="run once per file matching GLOB (given to input NAME; ** recurses); needs -d",
    )
    p.add_argument("--record", action="store_true", help="print the run record")
    p.add_argument(
        "--keep-intermediates",
        action="store_true",
        help="with -d: keep every intermediate value and show its picture in report.html",
    )
    p.set_defaults(func=cmd_run)


def _sweep(command: Command) -> None:
    p = command("sweep", "run every combination of parameter values; sweep.csv, plots, page")
    run_options(p)
    p.add_argument(
        "--grid",
        action="append",
        default=[],
        metavar="NODE.PARAM=V1,V2,...",
        help="values to try for one parameter (repeatable; every combination runs)",
    )
    p.add_argument(
        "--output",
        "-o",
        action="append",
        metavar="NAME",
        help="produce only this output in each run (repeatable); only what it needs runs",
    )
    p.add_argument(
        "--output-dir", "-d", type=path_text, metavar="DIR", required=True, help="where to write"
    )
    p.add_argument("--plot", metavar="OUTPUT", help="plot this scalar output against each param")
    p.set_defaults(func=cmd_sweep)


def _studio(command: Command) -> None:
    p = command("studio", "tune a pipeline live in the browser (needs graphvision[studio])")
    run_options(p)
    studio_options(p)
    # its own worker processes by default: a superseded node's worker is ended, not waited for
    p.set_defaults(func=cmd_studio, executor="processes")


def _validate(command: Command) -> None:
    p = command("validate", "check pipelines without running them")
    p.add_argument(
        "pipelines", nargs="+", type=path_text, metavar="PIPELINE", help="pipeline files"
    )
    input_option(p)  # loaded as `run` loads it, in place of the input's default
    p.set_defaults(func=cmd_validate)


def _graph_and_report(command: Command) -> None:
    """``graph`` and ``report``: a pipeline drawn, a run folder's pages written again."""
    p = command("graph", "print a pipeline's drawing: Graphviz DOT, SVG or Mermaid")
    p.add_argument("pipeline", type=path_text, help="the pipeline file (YAML)")
    p.add_argument(
        "--format",
        choices=("dot", "svg", "mermaid"),
        default="dot",
        help="the drawing's format (default: dot, for Graphviz: graphvision graph P | dot -Tpng)",
    )
    p.set_defaults(func=cmd_graph)

    p = command("report", "write a run folder's report.md and report.html again from its files")
    p.add_argument(
        "directory", type=path_text, help="the run's output folder (-d of graphvision run)"
    )
    p.set_defaults(func=cmd_report)


def _registry_commands(command: Command) -> None:
    """``nodes``, ``describe`` and ``schema``: what the registry and the file format hold."""
    p = command("nodes", "list the nodes by family")
    p.add_argument("--json", action="store_true", help="every node's description as JSON")
    p.set_defaults(func=cmd_nodes)

    p = command(
        "describe",
        "show a node's ports, parameters and documentation, or a pipeline's inputs, "
        "parameters, outputs and families",
    )
    p.add_argument("op", help="the node id, family.name; or a pipeline file (.yaml)")
    p.add_argument("--json", action="store_true", help="the description as JSON")
    p.set_defaults(func=cmd_describe)

    p = command("schema", "print the JSON Schema of pipeline files")
    p.set_defaults(func=cmd_schema)


def _cache(command: Command) -> None:
    p = command("cache", "inspect, prune or empty the disk cache")
    p.add_argument("action", choices=("info", "prune", "clear"), help="what to do")
    cache_options(p)
    p.add_argument(
        "--max-bytes",
        type=byte_size,
        default=None,
        metavar="SIZE",
        help="with prune: size to prune down to",
    )
    p.set_defaults(func=cmd_cache)


def version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("graphvision")
    except PackageNotFoundError:  # pragma: no cover - run from a source tree
        return "unknown"
