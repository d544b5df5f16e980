"""The ``graphvision`` command line.

::

    graphvision run PIPELINE [--input NAME=VALUE]... [--set NODE.PARAM=VALUE]...
                             [--output-dir DIR] [--output NAME]... [--executor KIND]
                             [--batch NAME=GLOB]
                             [--no-cache | --cache-dir DIR] [--keep-going] [--record]
    graphvision validate PIPELINE...
    graphvision nodes [--json]
    graphvision describe OP [--json]
    graphvision schema
    graphvision graph PIPELINE [--format dot|mermaid]
    graphvision cache info|prune|clear [--cache-dir DIR] [--max-bytes N]

Exit status: 0 success, 1 a run failed, 2 an invalid pipeline or usage. User
mistakes print a message, not a traceback (``--debug`` shows it).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import traceback
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml

from ._batch import BatchItem, run_batch
from ._cache import Cache, DiskStore, MemoryStore, default_cache_dir
from ._compile import compile_graph
from ._errors import GraphvisionError, InputError, PipelineError, RunError
from ._executors import EXECUTORS
from ._pipeline_file import load_pipeline, pipeline_json_schema
from ._plugins import discover
from ._registry import Registry
from ._report import check_output_folder, write_run
from ._run import RunHooks, RunResult, run

__all__ = ["main"]

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


class UsageError(GraphvisionError):
    """A command-line mistake (exit status 2)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # exit 2 with our message style, no usage dump
        raise UsageError(f"{self.prog}: {message}")


def _pairs(items: Sequence[str], flag: str) -> dict[str, str]:
    pairs = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise UsageError(f"{flag} expects NAME=VALUE, got '{item}'")
        pairs[name] = value
    return pairs


class Progress(RunHooks):
    """Prints one line per finished node to stderr."""

    def __init__(self) -> None:
        self.total, self.done = 0, 0

    def run_started(self, *, pipeline: str, steps: list[str]) -> None:
        self.total = len(steps)
        print(f"running {pipeline}: {self.total} node(s) to compute", file=sys.stderr)

    def node_finished(self, *, name: str, op: str, status: str, seconds: float) -> None:
        if status == "cached":
            return
        self.done += 1
        print(
            f"  [{self.done}/{self.total}] {name} ({op}) {status} {seconds * 1e3:.0f} ms",
            file=sys.stderr,
        )


def _registry(args: argparse.Namespace, extra: Sequence[str] = ()) -> Registry:
    registry = discover([*args.plugins, *extra])
    for plugin in registry.failed_plugins():
        print(f"warning: plugin '{plugin.name}' failed to load: {plugin.error}", file=sys.stderr)
    return registry


def _cache(args: argparse.Namespace) -> Cache | None:
    if args.no_cache:
        return None
    disk = DiskStore.open(args.cache_dir or default_cache_dir(), args.cache_max_bytes)
    return Cache(MemoryStore(), disk)


def _run_once(
    graph: Any, registry: Registry, inputs: dict[str, Any], args: argparse.Namespace, **options: Any
) -> tuple[int, RunResult]:
    """One run; a failed run still returns what it produced (exit status 1)."""
    try:
        return EXIT_OK, run(
            graph,
            registry,
            inputs=inputs,
            outputs=args.output or None,
            keep_going=args.keep_going,
            **options,
        )
    except RunError as error:
        print(f"error: run failed\n{error}", file=sys.stderr)
        if args.debug:
            for failure in error.failures.values():
                traceback.print_exception(failure.__cause__ or failure, file=sys.stderr)
        return EXIT_FAILED, error.result  # type: ignore[attr-defined]


def _write(result: RunResult, out_dir: Path) -> dict[str, list[str]]:
    return write_run(result, out_dir)


def cmd_run(args: argparse.Namespace) -> int:
    graph = load_pipeline(args.pipeline)
    registry = _registry(args, graph.plugins)
    overrides: dict[str, Any] = {k: yaml.safe_load(v) for k, v in _pairs(args.set, "--set").items()}
    inputs: dict[str, Any] = dict(_pairs(args.input, "--input"))
    out_dir = Path(args.output_dir) if args.output_dir else None
    progress = args.progress or (args.progress is None and sys.stderr.isatty())
    options = {
        "overrides": overrides,
        "workers": args.workers,
        "cache": _cache(args),
        "hooks": [Progress()] if progress and not args.batch else [],
    }
    if args.batch:
        return _batch(graph, registry, inputs, args, options)
    if out_dir is not None:  # refuse before running, not after
        check_output_folder(out_dir, args.output or graph.outputs)
    status, result = _run_once(graph, registry, inputs, args, executor=args.executor, **options)
    if out_dir is not None:
        files = _write(result, out_dir)
        print(
            f"wrote {len(files)} output(s), record.json and {out_dir / 'report.md'}",
            file=sys.stderr,
        )
    else:
        for name, summary in result.record.outputs.items():
            print(f"{name}: {summary}")
    if args.record:
        print(result.record.table())
    return status


def _batch(
    graph: Any,
    registry: Registry,
    inputs: dict[str, Any],
    args: argparse.Namespace,
    options: dict[str, Any],
) -> int:
    """``--batch NAME=GLOB``: :func:`~graphvision.run_batch` with a line per file on stderr."""
    if len(args.batch) > 1:
        raise UsageError("--batch maps one input; give it once")
    name, pattern = next(iter(_pairs(args.batch, "--batch").items()))
    if not args.output_dir:
        raise UsageError("--batch needs --output-dir (one folder per input file)")

    def report(number: int, total: int, item: BatchItem) -> None:
        if item.error:
            print(f"error: {item.file}: {item.error}", file=sys.stderr)
        print(
            f"  [{number}/{total}] {item.file}: {item.status} ({item.seconds:.2f} s) "
            f"-> {item.output_dir}",
            file=sys.stderr,
        )

    try:
        batch = run_batch(
            graph,
            pattern,
            input=name,
            output_dir=args.output_dir,
            registry=registry,
            inputs=inputs,
            outputs=args.output or None,
            executor=args.executor,
            keep_going=args.keep_going,
            on_item=report,
            **options,
        )
    except InputError as error:
        raise UsageError(f"--batch {name}={pattern}: {error}") from None
    total = len(batch.items)
    print(
        f"{total - batch.failed} of {total} succeeded; summary in {batch.summary}", file=sys.stderr
    )
    return EXIT_FAILED if batch.failed else EXIT_OK


def cmd_validate(args: argparse.Namespace) -> int:
    status = EXIT_OK
    for path in args.pipelines:
        try:
            graph = load_pipeline(path)
            compile_graph(graph, _registry(args, graph.plugins))
            print(f"{path}: ok")
        except PipelineError as error:
            print(error, file=sys.stderr)
            status = EXIT_USAGE
    return status


def cmd_nodes(args: argparse.Namespace) -> int:
    registry = _registry(args)
    if args.json:
        print(
            json.dumps(
                {op: spec.describe() for op, spec in sorted(registry.nodes.items())}, indent=2
            )
        )
        return EXIT_OK
    for family, specs in registry.families().items():
        print(f"{family}")
        width = max(len(s.id) for s in specs)
        for spec in specs:
            print(f"  {spec.id.ljust(width)}  {spec.summary}")
    return EXIT_OK


def cmd_describe(args: argparse.Namespace) -> int:
    spec = _registry(args).node(args.op)
    info = spec.describe()
    if args.json:
        print(json.dumps(info, indent=2))
        return EXIT_OK
    print(f"{spec.id} (version {spec.version}, plugin {spec.plugin}, {info['function']})\n")
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
    print(f"\n{info['doc']}")
    return EXIT_OK


def cmd_schema(args: argparse.Namespace) -> int:
    print(json.dumps(pipeline_json_schema(), indent=2))
    return EXIT_OK


def cmd_graph(args: argparse.Namespace) -> int:
    graph = load_pipeline(args.pipeline)
    compile_graph(graph, _registry(args, graph.plugins))
    lines = ["digraph pipeline {", "  rankdir=LR;"] if args.format == "dot" else ["flowchart LR"]
    for name, decl in graph.inputs.items():
        lines.append(
            f'  {name} [shape=ellipse, label="{name}\\n{decl.type}"];'
            if args.format == "dot"
            else f"  {name}([{name}: {decl.type}])"
        )
    for name, decl in graph.nodes.items():
        lines.append(
            f'  {name} [shape=box, label="{name}\\n{decl.op}"];'
            if args.format == "dot"
            else f'  {name}["{name}<br/>{decl.op}"]'
        )
        for port, ref in decl.inputs.items():
            label = f"{ref.port or ''}→{port}"
            lines.append(
                f'  {ref.node} -> {name} [label="{label}"];'
                if args.format == "dot"
                else f"  {ref.node} -->|{label}| {name}"
            )
    for name, ref in graph.outputs.items():
        lines.append(
            f'  out_{name} [shape=note, label="{name}"];\n  {ref.node} -> out_{name};'
            if args.format == "dot"
            else f"  {ref.node} --> out_{name}[/{name}/]"
        )
    if args.format == "dot":
        lines.append("}")
    print("\n".join(lines))
    return EXIT_OK


def cmd_cache(args: argparse.Namespace) -> int:
    store = DiskStore(args.cache_dir or default_cache_dir(), args.cache_max_bytes)
    if args.action == "info":
        info = store.info()
        print(
            f"directory: {info.directory}\nentries:   {info.entries}\n"
            f"size:      {info.bytes / 2**20:.1f} MiB of {info.max_bytes / 2**20:.0f} MiB"
        )
    elif args.action == "prune":
        freed = store.prune(args.max_bytes if args.max_bytes is not None else store.max_bytes)
        print(f"freed {freed / 2**20:.1f} MiB")
    else:
        print(f"removed {store.clear()} entries from {store.directory}")
    return EXIT_OK


def _byte_size(text: str) -> int:
    units = {"k": 2**10, "m": 2**20, "g": 2**30, "t": 2**40}
    text = text.strip().lower().removesuffix("ib").removesuffix("b")
    try:
        size = int(float(text[:-1]) * units[text[-1]]) if text and text[-1] in units else int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a size: '{text}' (e.g. 500M, 2G)") from None
    if size <= 0:
        raise argparse.ArgumentTypeError(f"a size must be positive, got '{text}' (e.g. 500M, 2G)")
    return size


def build_parser() -> argparse.ArgumentParser:
    common = _Parser(add_help=False)
    common.add_argument(
        "--plugins",
        action="append",
        default=[],
        metavar="PATH",
        help="load a local plugin file or folder (repeatable)",
    )
    common.add_argument("--debug", action="store_true", help="show Python tracebacks")
    cache_opts = _Parser(add_help=False)
    cache_opts.add_argument(
        "--cache-dir", metavar="DIR", help=f"disk cache folder (default {default_cache_dir()})"
    )
    cache_opts.add_argument(
        "--cache-max-bytes",
        type=_byte_size,
        default=4 * 2**30,
        metavar="SIZE",
        help="disk cache bound, e.g. 500M, 4G (default 4G)",
    )

    parser = _Parser(
        prog="graphvision", description="Run classical computer-vision pipelines.", parents=[common]
    )
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = commands.add_parser("run", parents=[common, cache_opts], help="run a pipeline")
    p.add_argument("pipeline")
    p.add_argument(
        "--input",
        "-i",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="graph input: a path, sample:NAME, or a literal",
    )
    p.add_argument(
        "--set",
        "-s",
        action="append",
        default=[],
        metavar="NODE.PARAM=VALUE",
        help="override a node parameter (params.NAME for a pipeline param)",
    )
    p.add_argument(
        "--output",
        "-o",
        action="append",
        metavar="NAME",
        help="produce only this output (repeatable); only what it needs runs",
    )
    p.add_argument("--output-dir", "-d", metavar="DIR", help="write outputs, record and report")
    p.add_argument(
        "--batch",
        action="append",
        default=[],
        metavar="NAME=GLOB",
        help="run once per file matching GLOB (given to input NAME); needs -d",
    )
    p.add_argument("--executor", choices=EXECUTORS, default="threads")
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--no-cache", action="store_true", help="neither read nor write the disk cache")
    p.add_argument(
        "--keep-going",
        action="store_true",
        help="after a node fails, finish every branch that does not depend on it",
    )
    p.add_argument("--record", action="store_true", help="print the run record")
    p.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="print progress (default: when stderr is a terminal)",
    )
    p.set_defaults(func=cmd_run)

    p = commands.add_parser("validate", parents=[common], help="check pipelines without running")
    p.add_argument("pipelines", nargs="+")
    p.set_defaults(func=cmd_validate)

    p = commands.add_parser("nodes", parents=[common], help="list nodes by family")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_nodes)

    p = commands.add_parser("describe", parents=[common], help="show a node's ports and params")
    p.add_argument("op")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_describe)

    p = commands.add_parser("schema", parents=[common], help="print the pipeline JSON Schema")
    p.set_defaults(func=cmd_schema)

    p = commands.add_parser("graph", parents=[common], help="render a pipeline as DOT or Mermaid")
    p.add_argument("pipeline")
    p.add_argument("--format", choices=("dot", "mermaid"), default="dot")
    p.set_defaults(func=cmd_graph)

    p = commands.add_parser(
        "cache", parents=[common, cache_opts], help="inspect or empty the cache"
    )
    p.add_argument("action", choices=("info", "prune", "clear"))
    p.add_argument(
        "--max-bytes",
        type=_byte_size,
        default=None,
        metavar="SIZE",
        help="with prune: size to prune down to",
    )
    p.set_defaults(func=cmd_cache)
    return parser


def _show_warning(
    message: Any,
    category: type,
    filename: str,
    lineno: int,
    file: Any = None,
    line: str | None = None,
) -> None:
    print(f"warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``graphvision`` command; returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    warnings.showwarning = _show_warning
    began = time.perf_counter()
    try:
        args = build_parser().parse_args(argv)
        status = args.func(args)
    except RunError as error:  # raised outside cmd_run's handling
        print(f"error: {error}", file=sys.stderr)
        status = EXIT_FAILED
    except GraphvisionError as error:
        if debug:
            traceback.print_exc()
        print(f"error: {error}", file=sys.stderr)
        status = EXIT_USAGE
    except KeyboardInterrupt:
        print(f"interrupted after {time.perf_counter() - began:.1f} s", file=sys.stderr)
        status = 130
    return status


if __name__ == "__main__":
    sys.exit(main())
