"""What every command shares: exit statuses, values given on the command line, and
the set-up of a run (plugins, cache, executor, the pipeline with its --set and --input)."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from graphvision.cli.overrides import refused_overrides
from graphvision.cli.usage import UsageError
from graphvision.cli.utf8_paths import (
    plugin_paths,
    refuse_cache_dir_not_utf8,
    refuse_not_utf8,
    refuse_paths_not_utf8,
)

if TYPE_CHECKING:
    from graphvision.cache.store import Cache
    from graphvision.graph.model import Graph
    from graphvision.nodes.registry import Registry

EXECUTORS = ("threads", "sync", "processes", "dask")
MAX_WORKERS = 256  # workers of one machine's pool or local cluster (each is a thread or a process)
CACHE_DIR_HELP = "$GRAPHVISION_CACHE_DIR, else $XDG_CACHE_HOME/graphvision or ~/.cache/graphvision"


class Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]  # raises, as the base does
        raise UsageError(f"{self.prog}: {message}")


# -- values given on the command line ---------------------------------------------------


def named_pairs(items: Sequence[str], flag: str) -> dict[str, str]:
    pairs: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise UsageError(f"{flag} expects NAME=VALUE, got '{item}'")
        if name in pairs:
            raise UsageError(f"{flag} {name} is given twice ({pairs[name]!r} and {value!r})")
        pairs[name] = value
    return pairs


def yaml_value(text: str, where: str) -> Any:
    """A command-line value read as YAML (``2``, ``true``, ``[1, 2]``), or a UsageError."""
    from graphvision.errors import PipelineError
    from graphvision.graph.yaml_reader import parse_value

    try:
        return parse_value(text)
    except PipelineError as error:
        reasons = "; ".join(problem.message for problem in error.problems)
        shown = where if len(where) <= 80 else f"{where[:60]}..."
        raise UsageError(f"{shown}: {reasons}") from None


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: '{text}'") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    if value > MAX_WORKERS:
        raise argparse.ArgumentTypeError(f"at most {MAX_WORKERS}, got {value}")
    return value


def pixel_count(text: str) -> int:
    """``--max-pixels``: a whole number of at least 1 (``1e9`` and ``1_000_000`` accepted)."""
    from graphvision.values.budget import pixel_count as parsed

    try:
        return parsed(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def byte_size(text: str) -> int:
    units = {"k": 2**10, "m": 2**20, "g": 2**30, "t": 2**40}
    text = text.strip().lower().removesuffix("ib").removesuffix("b")
    try:
        size = int(float(text[:-1]) * units[text[-1]]) if text and text[-1] in units else int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a size: '{text}' (e.g. 500M, 2G)") from None
    if size <= 0:
        raise argparse.ArgumentTypeError(f"a size must be positive, got '{text}' (e.g. 500M, 2G)")
    return size


def path_text(text: str) -> str:
    """A file or folder named on the command line: an empty name (``--cache-dir ''``, a
    variable that was not set) is refused, never read as this folder or as the default."""
    if not text.strip():
        raise argparse.ArgumentTypeError("is empty: give a path (use . for this folder)")
    return text


def positive_seconds(text: str) -> float:
    try:
        seconds = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds: '{text}'") from None
    if not seconds > 0 or seconds == float("inf"):
        raise argparse.ArgumentTypeError(f"seconds must be positive, got '{text}'")
    return seconds


def read_each(
    pairs: dict[str, str], read: Callable[[str, str], Any]
) -> tuple[dict[str, Any], list[str]]:
    """Each value of ``pairs`` read by ``read(key, text)``: the values read, and the message
    of each that could not be (a :class:`UsageError`'s), to be named with the others."""
    values, problems = {}, []
    for key, text in pairs.items():
        try:
            values[key] = read(key, text)
        except UsageError as error:
            problems.append(str(error))
    return values, problems


def raise_refused(problems: list[str], refused: int, unknown: int) -> None:
    """Refuse the overrides of :func:`refused_overrides`, all of them in one message: a
    headline counting the overrides, and the problems when they are more (one value refused
    by two nodes, or a --grid's two values), then one line per problem."""
    if len(problems) == 1:
        raise UsageError(problems[0])
    if problems:
        listed = "".join(f"\n  - {problem}" for problem in problems)
        lines = f" ({len(problems)} problems)" if len(problems) != refused else ""
        if refused == 1:
            raise UsageError(f"1 override is refused{lines}:{listed}")
        what = "name nothing in the pipeline" if unknown == refused else "are refused"
        raise UsageError(f"{refused} overrides {what}{lines}:{listed}")


def output_folder(text: str | None) -> Path | None:
    """The output folder, checked now (a file, a folder that cannot be made, or a name that
    is not UTF-8 is refused before anything runs) and made when the first file is written
    into it: a command that fails or is stopped first leaves no folder behind."""
    from graphvision.errors import OutputFolderError
    from graphvision.execution.folders import missing_folders, remove_empty_folders
    from graphvision.execution.utf8_names import refuse_folder_not_utf8

    if text is None:
        return None
    folder = Path(text)
    try:  # its files name it in UTF-8 (record.json, batch.csv, the pages)
        refuse_folder_not_utf8(folder, "--output-dir")
    except OutputFolderError as error:
        raise UsageError(str(error)) from None
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"--output-dir {folder}: is a file, not a folder")
    made = missing_folders(folder)
    try:  # made and removed at once: it can be made
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UsageError(f"--output-dir {folder}: cannot be made ({error.strerror})") from None
    finally:
        remove_empty_folders(made)
    return folder


@contextlib.contextmanager
def folders_kept_only_if_used(*folders: Path | None) -> Iterator[None]:
    """On a failure or an interruption, remove the folders among ``folders`` and their
    parents that the command made and left empty (deepest first)."""
    from graphvision.execution.folders import missing_folders, remove_empty_folders

    made = missing_folders(*[folder for folder in folders if folder is not None])
    try:
        yield
    except BaseException:
        remove_empty_folders(made)
        raise


# -- shared set-up ---------------------------------------------------------------------


def registry_for(
    args: argparse.Namespace, graph: Graph | None = None, *, run_its_plugins: bool = True
) -> Registry:
    """The plugins: ``--plugins``, and with a pipeline only the installed families it uses
    (when the plugin index says which those are), else all of them; and the pipeline's
    own ``plugins:`` when it is to run or be validated (announced), never when it is only
    drawn or described."""
    from graphvision.execution.batch_signals import signals_deferred

    for path in args.plugins:
        if not Path(path).exists():
            raise UsageError(f"--plugins {path}: no such file or folder")
    named = [("--plugins", path) for path in args.plugins]
    if graph is not None and run_its_plugins:
        named += [(f"{graph.source or graph.name}: plugin", path) for path in graph.plugins]
    why = "a plugin is loaded and recorded by its path in UTF-8"
    for what, path in named:  # (it would fail to load: a warning, then its nodes unknown)
        for given, read in plugin_paths(Path(path)):
            refuse_not_utf8(what, str(given), why)
            refuse_not_utf8(f"{what} {given} leads to", str(read), why)
    with signals_deferred(insisted=True):  # a Ctrl-C in a plugin's own lines: not lost either
        registry = _discovered(args, graph, run_its_plugins)
    for plugin in registry.failed_plugins():
        print(f"warning: plugin '{plugin.name}' failed to load: {plugin.error}", file=sys.stderr)
    return registry


def _discovered(args: argparse.Namespace, graph: Graph | None, run_its_plugins: bool) -> Registry:
    """The registry of :func:`registry_for`, its plugins imported. (Imported from a plugin
    file by the loader, not by an import statement, a plugin's own lines are not deferred
    by :func:`~graphvision.execution.batch_signals.defer_signals_in_imports`: a Ctrl-C
    raised in its class's ``__set_name__`` made it a plugin that failed to load.)"""
    from graphvision.nodes.plugins import Needs, discover, discover_for

    if graph is None:
        return discover(args.plugins)
    if not run_its_plugins:
        return discover(args.plugins, needs=Needs.of(graph))
    if graph.plugins:  # (each from the working folder, when it is in it)
        here = Path.cwd()
        shown = [os.path.relpath(p, here) if Path(p).is_relative_to(here) else p
                 for p in graph.plugins]  # fmt: skip
        print(f"loading local plugins: {', '.join(shown)}", file=sys.stderr)
    return discover_for(graph, args.plugins)


def disk_cache(args: argparse.Namespace) -> Cache | None:
    from graphvision.cache.store import Cache
    from graphvision.locations import default_cache_dir

    if args.no_cache:
        return None
    folder = default_cache_dir() if args.cache_dir is None else args.cache_dir
    return Cache.at(folder, args.cache_max_bytes)


def executor_for(args: argparse.Namespace) -> Any:
    """The executor name, or a Dask executor (started here, so that it can be shut down)."""
    if args.executor != "dask":
        if args.scheduler:
            raise UsageError("--scheduler goes with --executor dask")
        return args.executor
    from graphvision.execution.dask import DaskExecutor

    return DaskExecutor(address=args.scheduler, workers=args.workers or 2)


def load_run_arguments(
    args: argparse.Namespace, grid: tuple[dict[str, Any], list[str]] | None = None
) -> tuple[Graph, Registry, dict[str, Any], dict[str, Any]]:
    """The pipeline, its registry, the checked overrides (``--set``) and inputs (``--input``);
    a sweep's ``grid`` (its values read, and the messages of those that could not be) is
    checked with the overrides, every refused one of both named in one message."""
    from graphvision.execution.arguments import environment_limits
    from graphvision.graph.pipeline_file import load_pipeline
    from graphvision.values.budget import ENVIRONMENT_VARIABLE

    if args.max_pixels is not None:  # in the environment: worker processes read it too
        os.environ[ENVIRONMENT_VARIABLE] = str(args.max_pixels)
    node_limit_options(args)
    environment_limits()  # a malformed variable refused once, before the pipeline is read
    order = backend_order(args)  # an empty entry is refused before the file is read
    inputs = dict(named_pairs(args.input, "--input"))
    refuse_paths_not_utf8(args.pipeline, inputs)
    if not getattr(args, "no_cache", False):
        refuse_cache_dir_not_utf8(args.cache_dir)
    graph = load_pipeline(args.pipeline, allow_outside_plugins=args.allow_outside_plugins)
    graph = graph.with_backends(order)  # --backend: the run's order
    registry = registry_for(args, graph)
    check_backend_option(order, registry)
    overrides, malformed = read_each(
        named_pairs(args.set, "--set"), lambda key, text: yaml_value(text, f"--set {key}={text}")
    )
    swept_keys = grid[0] if grid is not None else {}
    problems, refused, unknown = refused_overrides(
        graph, registry, overrides, "--set", malformed=malformed, also_overridden=swept_keys
    )
    if grid is not None:
        swept = refused_overrides(graph, registry, grid[0], "--grid", True, grid[1], overrides)
        problems, refused, unknown = problems + swept[0], refused + swept[1], unknown + swept[2]
    raise_refused(problems, refused, unknown)
    return graph, registry, overrides, inputs


def backend_order(args: argparse.Namespace) -> list[str] | None:
    """``--backend``'s names in order (None without the option); an empty entry
    (``--backend ''``, ``--backend opencv,``) is a usage error naming it."""
    from graphvision.graph.model import parse_backends

    text = getattr(args, "backend", None)
    if text is None:
        return None
    try:
        return parse_backends(text)
    except ValueError as error:
        raise UsageError(f"--backend: {error}") from None


def check_backend_option(order: list[str] | None, registry: Registry) -> None:
    """``--backend``'s names, each once and provided by an installed plugin (a usage
    error, attributed to the option, not to the pipeline file whose ``backends:`` it
    replaces)."""
    from graphvision.compiler.backends import BackendChooser

    if order is None:
        return
    problems = BackendChooser(registry, order).order_problems()
    if problems:
        raise UsageError(f"--backend {','.join(order)}: " + "; ".join(problems))


def node_limit_options(args: argparse.Namespace) -> None:
    """``--node-timeout``, ``--node-memory`` and ``--max-memory`` for every run the command
    makes (through the environment, as ``--max-pixels``), refused where they cannot be kept."""
    from graphvision.execution.limits import MEMORY_VARIABLE, TIMEOUT_VARIABLE
    from graphvision.execution.peak_memory import MEMORY_VARIABLE as RUN_MEMORY_VARIABLE

    if args.node_memory is not None and args.executor != "processes":
        raise UsageError(
            "--node-memory needs --executor processes (nodes in one process share its memory)"
        )
    if args.executor == "dask" and args.node_timeout is not None:
        raise UsageError("--node-timeout applies on sync, threads and processes, not dask")
    for variable, value in (
        (TIMEOUT_VARIABLE, args.node_timeout),
        (MEMORY_VARIABLE, args.node_memory),
        (RUN_MEMORY_VARIABLE, args.max_memory),
    ):
        if value is not None:
            os.environ[variable] = str(value)


def note_unread_plugins(graph: Graph, passed: Sequence[str | Path] = ()) -> list[str]:
    """Say which local plugins a pipeline names that reading it does not import: those
    not also given with ``--plugins`` (``passed``; the same file, however it is spelled).
    Returns them."""
    given = {Path(path).resolve() for path in passed}
    unread = [plugin for plugin in graph.plugins if Path(plugin).resolve() not in given]
    if unread:
        print(
            f"note: {graph.source} names local plugins {', '.join(unread)}; they are "
            "not imported to draw it (its code runs only with `run` or `validate`): "
            "pass --plugins PATH to load and check their ops",
            file=sys.stderr,
        )
    return unread
