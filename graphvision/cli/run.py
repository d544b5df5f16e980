"""``graphvision run``: one run, or one per file with ``--batch``."""

from __future__ import annotations

import argparse
import sys
import time
import traceback
from pathlib import Path
from typing import TYPE_CHECKING, Any

from graphvision.cli.common import (
    UsageError,
    disk_cache,
    executor_for,
    folders_kept_only_if_used,
    load_run_arguments,
    named_pairs,
    output_folder,
)
from graphvision.cli.exits import EXIT_FAILED, EXIT_OK

if TYPE_CHECKING:
    from graphvision.execution.record import RunResult
    from graphvision.graph.model import Graph
    from graphvision.nodes.registry import Registry


def cmd_run(args: argparse.Namespace) -> int:
    from graphvision.execution.folder_lock import only_writer
    from graphvision.execution.owned import check_output_folder

    graph, registry, overrides, inputs = load_run_arguments(args)
    out_dir = output_folder(args.output_dir)  # checked; made when its first file is written
    progress = args.progress or (args.progress is None and sys.stderr.isatty())
    if args.batch:
        with folders_kept_only_if_used(out_dir):
            return run_batch_command(graph, registry, inputs, overrides, args, progress)
    if out_dir is None:
        return _run_once(graph, registry, inputs, overrides, args, progress, None)
    check_output_folder(out_dir, args.output or graph.outputs)  # refuse before running
    with only_writer(out_dir, f"run of {graph.name}"):  # (removes the folders it made, if empty)
        return _run_once(graph, registry, inputs, overrides, args, progress, out_dir)


def _run_once(
    graph: Graph,
    registry: Registry,
    inputs: dict[str, Any],
    overrides: dict[str, Any],
    args: argparse.Namespace,
    progress: bool,
    out_dir: Path | None,
) -> int:
    """One run of ``graph``, its figures printed and, with ``out_dir``, its folder written."""
    from graphvision.errors import RunError
    from graphvision.execution.run import run
    from graphvision.execution.sweep import scalar_outputs_of
    from graphvision.views.progress import RunProgress

    executor = executor_for(args)
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
            cache=disk_cache(args),
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
    finally:
        if not isinstance(executor, str):
            executor.shutdown()
    shown = list(result.record.outputs)
    if out_dir is not None:
        status = max(status, _write_folder(result, out_dir, args.debug))
        shown = scalar_outputs_of(result.compiled, shown)  # the figures; the rest is in files
    for name in shown:
        print(f"{name}: {result.record.outputs[name]}")
    if args.record:
        print(result.record.table())
    return status


def _write_folder(result: RunResult, out_dir: Path, debug: bool) -> int:
    """Write the run's folder; a writer that fails (a port type's, a report page's) fails
    the command (exit 1) with one line naming the folder and the cause."""
    from graphvision.errors import GraphvisionError
    from graphvision.execution.folders import write_run
    from graphvision.views.report import RUN_PAGES

    try:
        files = write_run(result, out_dir, RUN_PAGES)
    except (GraphvisionError, OSError):  # the folder, the disk: said as for any command
        raise
    except Exception as error:
        if debug:
            traceback.print_exc()
        print(
            f"error: the run's files could not be written to {out_dir} "
            f"({type(error).__name__}: {error})",
            file=sys.stderr,
        )
        return EXIT_FAILED
    print(
        f"wrote {len(files)} output(s), record.json, {out_dir / 'report.md'} "
        f"and {out_dir / 'report.html'}",
        file=sys.stderr,
    )
    return EXIT_OK


def run_batch_command(
    graph: Graph,
    registry: Registry,
    inputs: dict[str, Any],
    overrides: dict[str, Any],
    args: argparse.Namespace,
    progress: bool,
) -> int:
    """``--batch NAME=GLOB``: :func:`~graphvision.run_batch`, a line (or a bar) per file."""
    from graphvision.errors import InputError
    from graphvision.execution.batch_files import BatchItem
    from graphvision.views.batch_page import run_batch
    from graphvision.views.progress import FileProgress

    name, pattern = _batch_argument(args)
    shown: list[FileProgress] = []
    began = time.monotonic()

    def report(number: int, total: int, item: BatchItem) -> None:
        if not shown:  # the total is known once the glob is expanded
            shown.append(FileProgress(total, bar=None if progress else False, began=began))
        if item.error:
            print(f"error: {item.file}: {item.error}", file=sys.stderr)
        folder = f" -> {item.output_dir}" if item.output_dir and item.output_dir.is_dir() else ""
        shown[0].finished(f"{item.file}{folder}", not item.error, item.seconds)

    executor = executor_for(args)
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
            cache=disk_cache(args),
            keep_going=args.keep_going,
            on_item=report,
        )
    except InputError as error:  # before any file ran
        about_batch = f"input '{name}'" in str(error)
        raise UsageError(
            f"--batch {name}={pattern}: {error}" if about_batch else str(error)
        ) from None
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
    done = f"{len(batch.items) - batch.failed} of {len(batch.items)} succeeded"
    print(f"{done}; summary in {batch.summary}", file=sys.stderr)
    return EXIT_FAILED if batch.failed else EXIT_OK


def _batch_argument(args: argparse.Namespace) -> tuple[str, str]:
    """The input ``--batch NAME=GLOB`` names, and the pattern; a UsageError when misused."""
    if len(args.batch) > 1:
        raise UsageError("--batch maps one input; give it once")
    name, pattern = next(iter(named_pairs(args.batch, "--batch").items()))
    if not args.output_dir:
        raise UsageError("--batch needs --output-dir (one folder per input file)")
    return name, pattern
