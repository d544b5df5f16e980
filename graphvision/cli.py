"""The ``graphvision`` command line: argument parsing and printing, nothing else.

::

    graphvision run PIPELINE [-i NAME=VALUE]... [-s NODE.PARAM=VALUE]... [-o NAME]...
                             [-d DIR] [--batch NAME=GLOB] [--executor KIND] [--workers N]
                             [--scheduler ADDRESS] [--no-cache | --cache-dir DIR]
                             [--keep-going] [--record] [--[no-]progress]
    graphvision sweep PIPELINE --grid NODE.PARAM=V1,V2,... [--grid ...] -d DIR [--plot OUTPUT]
    graphvision validate PIPELINE...
    graphvision nodes [--json]
    graphvision describe OP [--json]
    graphvision schema
    graphvision graph PIPELINE [--format dot|mermaid|svg]
    graphvision cache info|prune|clear [--cache-dir DIR] [--max-bytes SIZE]

``--plugins PATH`` and ``--debug`` go anywhere on the line. Exit status: 0
success, 1 a run failed (or the environment: a full disk, a closed pipe), 2
an invalid pipeline or usage, 130 interrupted (Ctrl-C), 143 terminated
(SIGTERM). Every mistake is one message, never a traceback (``--debug`` adds
it). Every sub-command calls the Python
API; heavy modules are imported by the command that needs them, so ``--help``
is quick.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ._errors import GraphvisionError, UnknownNameError, did_you_mean
from ._warnings import show_warning

if TYPE_CHECKING:
    from ._cache import Cache
    from ._graph import Graph
    from ._registry import Registry

__all__ = ["entry", "main"]

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 130, 143
EXECUTORS = ("threads", "sync", "processes", "dask")
MAX_WORKERS = 256  # workers of one machine's pool or local cluster (each is a thread or a process)
CACHE_DIR_HELP = "$GRAPHVISION_CACHE_DIR, else $XDG_CACHE_HOME/graphvision or ~/.cache/graphvision"


class UsageError(GraphvisionError):
    """A command-line mistake (exit status 2)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]  # raises, as the base does
        raise UsageError(f"{self.prog}: {message}")


# -- values given on the command line ---------------------------------------------------


def _pairs(items: Sequence[str], flag: str) -> dict[str, str]:
    pairs: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise UsageError(f"{flag} expects NAME=VALUE, got '{item}'")
        if name in pairs:
            raise UsageError(f"{flag} {name} is given twice ({pairs[name]!r} and {value!r})")
        pairs[name] = value
    return pairs


def _yaml_value(text: str, where: str) -> Any:
    """A command-line value read as YAML (``2``, ``true``, ``[1, 2]``), or a UsageError."""
    from ._errors import PipelineError
    from ._pipeline_file import parse_value

    try:
        return parse_value(text)
    except PipelineError as error:
        reasons = "; ".join(problem.message for problem in error.problems)
        raise UsageError(f"{where}: {reasons}") from None


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: '{text}'") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    if value > MAX_WORKERS:
        raise argparse.ArgumentTypeError(f"at most {MAX_WORKERS}, got {value}")
    return value


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


def _check_overrides(
    graph: Graph, registry: Registry, overrides: dict[str, Any], flag: str
) -> None:
    """Refuse, naming the command line, an override of a node or parameter that does not exist."""
    for key, value in overrides.items():
        target, _, param = key.partition(".")
        shown = f"{flag} {key}={value!r}"
        if not param:
            raise UsageError(f"{shown}: expected NODE.PARAM or params.NAME")
        if target == "params":
            if param not in graph.params:
                hint = did_you_mean(param, graph.params)
                raise UsageError(f"{shown}: the pipeline has no param '{param}'{hint}")
            continue
        if target not in graph.nodes:
            hint = did_you_mean(target, graph.nodes)
            raise UsageError(f"{shown}: the pipeline has no node '{target}'{hint}")
        spec = registry.nodes.get(graph.nodes[target].op)
        if spec is not None and param not in spec.param_fields:
            names = list(spec.param_fields)
            hint = did_you_mean(param, names)
            listing = ", ".join(names) or "none"
            raise UsageError(
                f"{shown}: {spec.id} has no parameter '{param}'{hint}; parameters: {listing}"
            )


def _output_dir(text: str | None) -> Path | None:
    """The output folder, made now: a file or a folder that cannot be made is refused first."""
    if text is None:
        return None
    if not text.strip():
        raise UsageError("--output-dir is empty: give a folder (use . for this one)")
    folder = Path(text)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"--output-dir {folder}: is a file, not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UsageError(f"--output-dir {folder}: cannot be made ({error.strerror})") from None
    return folder


# -- shared set-up ---------------------------------------------------------------------


def _registry(
    args: argparse.Namespace, graph: Graph | None = None, *, run_its_plugins: bool = True
) -> Registry:
    """The plugins: ``--plugins``, and with a pipeline only the installed families it uses
    (when the plugin index says which those are), else all of them; and the pipeline's
    own ``plugins:`` when it is to run (announced), never when it is only read."""
    from ._plugins import Needs, discover, discover_for

    for path in args.plugins:
        if not Path(path).exists():
            raise UsageError(f"--plugins {path}: no such file or folder")
    if graph is None:
        registry = discover(args.plugins)
    elif run_its_plugins:
        if graph.plugins:
            print(f"loading local plugins: {', '.join(graph.plugins)}", file=sys.stderr)
        registry = discover_for(graph, args.plugins)
    else:
        registry = discover(args.plugins, needs=Needs.of(graph))
    for plugin in registry.failed_plugins():
        print(f"warning: plugin '{plugin.name}' failed to load: {plugin.error}", file=sys.stderr)
    return registry


def _cache(args: argparse.Namespace) -> Cache | None:
    from ._cache import Cache, default_cache_dir

    if args.no_cache:
        return None
    return Cache.at(args.cache_dir or default_cache_dir(), args.cache_max_bytes)


def _executor(args: argparse.Namespace) -> Any:
    """The executor name, or a Dask executor (started here, so that it can be shut down)."""
    if args.executor != "dask":
        if args.scheduler:
            raise UsageError("--scheduler goes with --executor dask")
        return args.executor
    from ._dask import DaskExecutor

    return DaskExecutor(address=args.scheduler, workers=args.workers or 2)


def _load(args: argparse.Namespace) -> tuple[Graph, Registry, dict[str, Any], dict[str, Any]]:
    """The pipeline, its registry, the checked overrides (``--set``) and inputs (``--input``)."""
    from ._pipeline_file import load_pipeline

    graph = load_pipeline(args.pipeline, allow_outside_plugins=args.allow_outside_plugins)
    registry = _registry(args, graph)
    overrides = {
        key: _yaml_value(value, f"--set {key}={value}")
        for key, value in _pairs(args.set, "--set").items()
    }
    _check_overrides(graph, registry, overrides, "--set")
    return graph, registry, overrides, dict(_pairs(args.input, "--input"))


# -- commands ---------------------------------------------------------------------------


def cmd_run(args: argparse.Namespace) -> int:
    from ._errors import RunError
    from ._progress import RunProgress
    from ._report import check_output_folder, write_run
    from ._run import run

    graph, registry, overrides, inputs = _load(args)
    made = args.output_dir is not None and not Path(args.output_dir).exists()
    out_dir = _output_dir(args.output_dir)
    progress = args.progress or (args.progress is None and sys.stderr.isatty())
    if args.batch:
        return _batch(graph, registry, inputs, overrides, args, progress)
    if out_dir is not None:  # refuse before running, not after
        check_output_folder(out_dir, args.output or graph.outputs)
    executor = _executor(args)
    status = EXIT_OK
    try:
        result = run(
            graph,
            registry,
            inputs=inputs,
            outputs=args.output or None,
            overrides=overrides,
            executor=executor,
            workers=args.workers,
            cache=_cache(args),
            keep_going=args.keep_going,
            hooks=[RunProgress()] if progress else [],
            keep_intermediates=args.keep_intermediates,
        )
    except RunError as error:
        print(f"error: run failed\n{error}", file=sys.stderr)
        if args.debug:
            for failure in error.failures.values():
                traceback.print_exception(failure.__cause__ or failure, file=sys.stderr)
        status, result = EXIT_FAILED, error.result  # type: ignore[attr-defined]
    except BaseException:  # interrupted: a folder made for this run goes again, still empty
        if made and out_dir is not None:
            with contextlib.suppress(OSError):
                out_dir.rmdir()
        raise
    finally:
        if not isinstance(executor, str):
            executor.shutdown()
    if out_dir is not None:
        files = write_run(result, out_dir)
        print(
            f"wrote {len(files)} output(s), record.json, {out_dir / 'report.md'} "
            f"and {out_dir / 'report.html'}",
            file=sys.stderr,
        )
    else:
        for name, summary in result.record.outputs.items():
            print(f"{name}: {summary}")
    if args.record:
        print(result.record.table())
    return status


def _batch(
    graph: Graph,
    registry: Registry,
    inputs: dict[str, Any],
    overrides: dict[str, Any],
    args: argparse.Namespace,
    progress: bool,
) -> int:
    """``--batch NAME=GLOB``: :func:`~graphvision.run_batch`, a line (or a bar) per file."""
    from ._batch import BatchItem, run_batch
    from ._errors import InputError
    from ._progress import FileProgress

    if len(args.batch) > 1:
        raise UsageError("--batch maps one input; give it once")
    name, pattern = next(iter(_pairs(args.batch, "--batch").items()))
    if not args.output_dir:
        raise UsageError("--batch needs --output-dir (one folder per input file)")
    shown: list[FileProgress] = []
    began = time.monotonic()

    def report(number: int, total: int, item: BatchItem) -> None:
        if not shown:  # the total is known once the glob is expanded
            shown.append(FileProgress(total, bar=None if progress else False, began=began))
        if item.error:
            print(f"error: {item.file}: {item.error}", file=sys.stderr)
        shown[0].finished(f"{item.file} -> {item.output_dir}", not item.error, item.seconds)

    executor = _executor(args)
    try:
        batch = run_batch(
            graph,
            pattern,
            input=name,
            output_dir=args.output_dir,
            registry=registry,
            inputs=inputs,
            outputs=args.output or None,
            overrides=overrides,
            executor=executor,
            workers=args.workers,
            cache=_cache(args),
            keep_going=args.keep_going,
            on_item=report,
        )
    except InputError as error:
        raise UsageError(f"--batch {name}={pattern}: {error}") from None
    except KeyboardInterrupt:
        summary = Path(args.output_dir) / "batch.csv"
        if summary.is_file():
            print(f"batch interrupted; files done so far are listed in {summary}", file=sys.stderr)
        raise
    finally:
        for bar in shown:
            bar.close()
        if not isinstance(executor, str):
            executor.shutdown()
    total = len(batch.items)
    print(
        f"{total - batch.failed} of {total} succeeded; summary in {batch.summary}", file=sys.stderr
    )
    return EXIT_FAILED if batch.failed else EXIT_OK


def cmd_sweep(args: argparse.Namespace) -> int:
    from ._compile import compile_graph
    from ._progress import FileProgress
    from ._sweep import SweepInterrupted, check_sweep_folder, scalar_outputs_of, sweep, write_sweep

    graph, registry, overrides, inputs = _load(args)
    grid = {
        key: _yaml_value(f"[{values}]", f"--grid {key}={values}")
        for key, values in _pairs(args.grid, "--grid").items()
    }
    if not grid:
        raise UsageError("sweep needs at least one --grid NODE.PARAM=V1,V2,...")
    _check_overrides(graph, registry, grid, "--grid")
    both = sorted(set(grid) & set(overrides))
    if both:
        raise UsageError(f"{both[0]} is both swept (--grid) and set (--set); give one of them")
    out_dir = _output_dir(args.output_dir)
    assert out_dir is not None  # the option is required
    check_sweep_folder(out_dir)  # before anything runs
    if overrides:
        graph = graph.with_overrides(overrides)
    if args.plot:
        compiled = compile_graph(graph, registry, provided=set(inputs))
        unknown = [name for name in args.output or () if name not in compiled.outputs]
        if unknown:
            raise UsageError(
                f"-o {unknown[0]}: no such output; outputs: {', '.join(compiled.outputs)}"
            )
        scalars = scalar_outputs_of(compiled, args.output or list(compiled.outputs))
        if args.plot not in scalars:
            listing = ", ".join(scalars) or "none"
            raise UsageError(
                f"--plot {args.plot}: not a scalar output of the sweep"
                f"{did_you_mean(args.plot, scalars)}; scalar outputs: {listing}"
            )
    executor = _executor(args)
    shown: list[FileProgress] = []
    began = time.monotonic()

    def report(number: int, total: int, row: dict[str, Any]) -> None:
        if not shown:  # a bar on a terminal, else a line per combination
            shown.append(FileProgress(total, "combinations", began=began))
        combination = ", ".join(f"{key}={row[key]}" for key in grid)
        shown[0].finished(combination, row["status"] == "ok", row["seconds"])

    try:
        result = sweep(
            graph,
            grid,
            registry,
            inputs=inputs,
            cache=_cache(args),
            executor=executor,
            workers=args.workers,
            keep_going=args.keep_going,
            outputs=args.output,
            on_row=None if args.progress is False else report,
        )
    except SweepInterrupted as stopped:  # what is done is written, then the exit is 130
        write_sweep(stopped.result, out_dir, graph.name, [])
        print(
            f"sweep interrupted; combinations done so far are in {out_dir / 'sweep.csv'}",
            file=sys.stderr,
        )
        raise
    finally:
        for bar in shown:
            bar.close()
        if not isinstance(executor, str):
            executor.shutdown()
    written = write_sweep(result, out_dir, graph.name, [args.plot] if args.plot else [])
    failed = sum(row["status"] != "ok" for row in result.rows)
    print(
        f"{len(result.rows) - failed} of {len(result.rows)} combinations succeeded; wrote "
        + ", ".join(str(p) for p in written),
        file=sys.stderr,
    )
    return EXIT_FAILED if failed else EXIT_OK


def cmd_validate(args: argparse.Namespace) -> int:
    from ._compile import compile_graph
    from ._errors import PipelineError
    from ._pipeline_file import load_pipeline

    status = EXIT_OK
    for path in args.pipelines:
        try:
            graph = load_pipeline(path, allow_outside_plugins=args.allow_outside_plugins)
            _note_unread_plugins(graph)
            compile_graph(graph, _registry(args, graph, run_its_plugins=False))
            print(f"{path}: ok")
        except PipelineError as error:
            print(error, file=sys.stderr)
            status = EXIT_USAGE
    return status


def _note_unread_plugins(graph: Graph) -> None:
    """Say which local plugins a pipeline names that reading it does not import."""
    if graph.plugins:
        print(
            f"note: {graph.source} names local plugins {', '.join(graph.plugins)}; they are "
            "not imported to check or draw it (nothing in a pipeline runs until `run`): "
            "pass --plugins PATH to load and check their ops",
            file=sys.stderr,
        )


def plain_text(text: str) -> str:
    """reStructuredText roles and literals as plain text (``:math:`x``` -> ``x``)."""
    import re

    text = re.sub(r":[a-z]+:`~?([^`]+)`", lambda m: m.group(1).rsplit(".", 1)[-1], text)
    return text.replace("``", "")


def _listed_nodes(args: argparse.Namespace) -> tuple[dict[str, str], Callable[[str], Any]]:
    """Each node's one-line summary by id, and a function giving a node's description.

    From the plugin index when it matches the installed plugins and no local
    plugin is asked for (no plugin is imported then), else by discovering them.
    """
    if not args.plugins:
        from ._plugin_index import environment_key, installed_entry_points, read_index

        indexed = read_index(environment_key(installed_entry_points()))
        if indexed is not None:
            summaries = {op: str(entry["summary"]) for op, entry in indexed.items()}
            return summaries, lambda op: indexed[op]["description"]
    registry = _registry(args)
    summaries = {op: spec.summary for op, spec in registry.nodes.items()}
    return summaries, lambda op: registry.nodes[op].describe()


def cmd_nodes(args: argparse.Namespace) -> int:
    import json

    summaries, describe = _listed_nodes(args)
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
            print(f"  {op.ljust(width)}  {plain_text(summaries[op])}")
    return EXIT_OK


def cmd_describe(args: argparse.Namespace) -> int:
    import json

    summaries, describe = _listed_nodes(args)
    if args.op not in summaries:
        raise UnknownNameError(f"unknown op '{args.op}'{did_you_mean(args.op, summaries)}")
    info = describe(args.op)
    if args.json:
        print(json.dumps(info, indent=2))
        return EXIT_OK
    where = f"version {info['version']}, plugin {info['plugin']}, {info['function']}"
    print(f"{info['id']} ({where})\n")
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
    print(f"\n{plain_text(info['doc'])}")
    return EXIT_OK


def cmd_schema(args: argparse.Namespace) -> int:
    import json

    from ._pipeline_file import pipeline_json_schema

    print(json.dumps(pipeline_json_schema(), indent=2))
    return EXIT_OK


def cmd_graph(args: argparse.Namespace) -> int:
    from ._compile import compile_graph
    from ._pipeline_file import load_pipeline
    from ._render import render

    graph = load_pipeline(args.pipeline, allow_outside_plugins=args.allow_outside_plugins)
    _note_unread_plugins(graph)
    compile_graph(graph, _registry(args, graph, run_its_plugins=False))
    print(render(graph, args.format))
    return EXIT_OK


def cmd_report(args: argparse.Namespace) -> int:
    from ._report import rewrite_report

    registry = _registry(args) if args.plugins else None  # else: the pipeline's own
    page = rewrite_report(Path(args.directory), registry)
    print(f"wrote {page} and {page.with_name('report.md')}", file=sys.stderr)
    return EXIT_OK


def cmd_cache(args: argparse.Namespace) -> int:
    from ._cache import DiskStore, default_cache_dir

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


# -- the parser -------------------------------------------------------------------------


def _global_options(parser: argparse.ArgumentParser, top: bool) -> None:
    """``--plugins`` and ``--debug``, accepted before and after the sub-command.

    The sub-commands' copies default to SUPPRESS, so that a value given before
    the sub-command is not reset by the sub-command's default.
    """
    parser.add_argument(
        "--plugins",
        action="append",
        default=[] if top else argparse.SUPPRESS,
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


def _cache_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--cache-dir", metavar="DIR", help=f"disk cache folder ({CACHE_DIR_HELP})")
    parser.add_argument(
        "--cache-max-bytes",
        type=_byte_size,
        default=4 * 2**30,
        metavar="SIZE",
        help="disk cache bound, e.g. 500M, 4G (default 4G)",
    )


def _run_options(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``run`` and ``sweep``."""
    parser.add_argument("pipeline", help="the pipeline file (YAML)")
    parser.add_argument(
        "--input",
        "-i",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="graph input: a path, sample:NAME, or a literal",
    )
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
        type=_positive_int,
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
    _cache_options(parser)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="graphvision", description="Run classical computer-vision pipelines.")
    parser.add_argument("--version", action="version", version=f"graphvision {_version()}")
    _global_options(parser, top=True)
    commands = parser.add_subparsers(dest="command", parser_class=_Parser, metavar="COMMAND")

    def command(name: str, help: str) -> argparse.ArgumentParser:
        sub = commands.add_parser(name, help=help, description=help)
        _global_options(sub, top=False)
        return sub

    p = command("run", "run a pipeline (once, or once per file with --batch)")
    _run_options(p)
    p.add_argument(
        "--output",
        "-o",
        action="append",
        metavar="NAME",
        help="produce only this output (repeatable); only what it needs runs",
    )
    p.add_argument(
        "--output-dir", "-d", metavar="DIR", help="write outputs, record, report.md, report.html"
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

    p = command("sweep", "run every combination of parameter values; sweep.csv, plots, page")
    _run_options(p)
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
    p.add_argument("--output-dir", "-d", metavar="DIR", required=True, help="where to write")
    p.add_argument("--plot", metavar="OUTPUT", help="plot this scalar output against each param")
    p.set_defaults(func=cmd_sweep)

    p = command("validate", "check pipelines without running them")
    p.add_argument("pipelines", nargs="+", metavar="PIPELINE", help="pipeline files")
    p.set_defaults(func=cmd_validate)

    p = command("nodes", "list the nodes by family")
    p.add_argument("--json", action="store_true", help="every node's description as JSON")
    p.set_defaults(func=cmd_nodes)

    p = command("describe", "show a node's ports, parameters and documentation")
    p.add_argument("op", help="the node id, family.name")
    p.add_argument("--json", action="store_true", help="the description as JSON")
    p.set_defaults(func=cmd_describe)

    p = command("schema", "print the JSON Schema of pipeline files")
    p.set_defaults(func=cmd_schema)

    p = command("graph", "draw a pipeline as SVG, DOT or Mermaid")
    p.add_argument("pipeline", help="the pipeline file (YAML)")
    p.add_argument(
        "--format", choices=("svg", "dot", "mermaid"), default="dot", help="the drawing's format"
    )
    p.set_defaults(func=cmd_graph)

    p = command("report", "write a run folder's report.md and report.html again from its files")
    p.add_argument("directory", help="the run's output folder (-d of graphvision run)")
    p.set_defaults(func=cmd_report)

    p = command("cache", "inspect, prune or empty the disk cache")
    p.add_argument("action", choices=("info", "prune", "clear"), help="what to do")
    _cache_options(p)
    p.add_argument(
        "--max-bytes",
        type=_byte_size,
        default=None,
        metavar="SIZE",
        help="with prune: size to prune down to",
    )
    p.set_defaults(func=cmd_cache)
    return parser


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("graphvision")
    except PackageNotFoundError:  # pragma: no cover - run from a source tree
        return "unknown"


# -- main -------------------------------------------------------------------------------


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line on ``argv``; return the exit status (never raises for a mistake).

    The one place errors become messages: a graphvision error is a usage
    problem (2), a failed run or a problem of the environment (a full disk,
    no permission, a closed pipe) a failure (1), Ctrl-C 130, SIGTERM 143.
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    warnings.showwarning = show_warning
    began = time.perf_counter()
    try:
        parser = build_parser()
        if not argv:
            parser.print_usage(sys.stderr)
            print(
                "commands: " + ", ".join(_commands(parser)) + "; --help for more", file=sys.stderr
            )
            return EXIT_USAGE
        try:
            args = parser.parse_args(argv)
        except SystemExit as done:  # --help, --version
            return int(done.code or 0)
        if args.command is None:
            raise UsageError("give a command: " + ", ".join(_commands(parser)))
        return int(args.func(args))
    except KeyboardInterrupt as stop:
        what = "terminated" if isinstance(stop, Terminated) else "interrupted"
        print(f"{what} after {time.perf_counter() - began:.1f} s", file=sys.stderr)
        return EXIT_TERMINATED if isinstance(stop, Terminated) else EXIT_INTERRUPTED
    except BrokenPipeError:  # `graphvision nodes | head -1`: the reader has what it wanted
        _silence_stdout()
        return EXIT_OK
    except Exception as error:
        if debug:
            traceback.print_exc()
        return _report_error(error)


def _report_error(error: Exception) -> int:
    from ._errors import RunError

    if isinstance(error, RunError):
        print(f"error: {error}", file=sys.stderr)
        return EXIT_FAILED
    if isinstance(error, GraphvisionError):
        print(f"error: {error}", file=sys.stderr)
        return EXIT_USAGE
    if isinstance(error, OSError):  # the environment: disk full, permissions, a vanished file
        where = f": {error.filename}" if error.filename else ""
        print(f"error: {error.strerror or error}{where}", file=sys.stderr)
        return EXIT_FAILED
    print(
        f"error: internal error ({type(error).__name__}: {error}); please report it, "
        "with the output of --debug",
        file=sys.stderr,
    )
    return EXIT_FAILED


def _commands(parser: argparse.ArgumentParser) -> list[str]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return list(action.choices)
    return []


def _silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush does not fail again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def entry() -> None:
    """The ``graphvision`` console script: :func:`main`, then exit at once with its status.

    On Ctrl-C the process exits without waiting for worker threads to finish
    the node they run (cache entries and outputs are written atomically, so
    nothing is left half-written; worker processes see their parent go and exit).
    """
    signal.signal(signal.SIGTERM, _terminate)
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    if status in (EXIT_INTERRUPTED, EXIT_TERMINATED):
        _release_process_resources()
        os._exit(status)
    sys.exit(status)


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, ``timeout``, ``docker stop``, a batch scheduler): stopped as Ctrl-C
    stops a run, so a batch or sweep still writes what it has done."""


def _terminate(signum: int, frame: Any) -> None:
    raise Terminated


def _release_process_resources() -> None:
    """Unlink the semaphores of a process pool before an immediate exit.

    ``os._exit`` skips the finalizers that release them, and multiprocessing's
    resource tracker then prints a warning about leaked semaphores. Running
    the finalizers of priority >= 0 (close queues, unlink semaphores) does not
    wait for the workers, which exit on their own when their parent is gone.
    """
    util = sys.modules.get("multiprocessing.util")
    if util is not None:
        util._run_finalizers(0)  # private, unchanged since Python 3.4


if __name__ == "__main__":
    entry()
