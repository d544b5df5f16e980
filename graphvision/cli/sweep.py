"""``graphvision sweep``: every combination of ``--grid`` values, sharing the cache."""

from __future__ import annotations

import argparse
import math
import re
import sys
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from graphvision.cli.common import (
    UsageError,
    disk_cache,
    executor_for,
    load_run_arguments,
    named_pairs,
    output_folder,
    read_each,
    yaml_value,
)
from graphvision.cli.exits import EXIT_FAILED, EXIT_OK
from graphvision.errors import did_you_mean

if TYPE_CHECKING:
    from pathlib import Path

    from graphvision.compiler.compile import CompiledGraph
    from graphvision.graph.model import Graph
    from graphvision.nodes.registry import Registry


def cmd_sweep(args: argparse.Namespace) -> int:
    from graphvision.execution.folder_lock import only_writer
    from graphvision.views.sweep_page import check_sweep_folder

    grid, malformed = read_each(named_pairs(args.grid, "--grid"), _listed)
    if not grid and not malformed:
        raise UsageError("sweep needs at least one --grid NODE.PARAM=V1,V2,...")
    graph, registry, overrides, inputs = load_run_arguments(args, (grid, malformed))
    both = sorted(set(grid) & set(overrides))
    if both:
        raise UsageError(f"{both[0]} is both swept (--grid) and set (--set); give one of them")
    out_dir = output_folder(args.output_dir)  # checked; made when the results are written
    assert out_dir is not None  # the option is required
    combinations = math.prod(len(values) for values in grid.values())
    check_sweep_folder(out_dir, [args.plot] if args.plot else [], combinations)  # first
    with only_writer(out_dir, f"sweep of {graph.name}"):  # (removes the folders it made, if empty)
        return _sweep(args, graph, registry, overrides, inputs, grid, out_dir)


def _sweep(
    args: argparse.Namespace,
    graph: Graph,
    registry: Registry,
    overrides: dict[str, Any],
    inputs: dict[str, Any],
    grid: dict[str, Any],
    out_dir: Path,
) -> int:
    """The sweep, once its arguments are checked: run, then write the folder."""
    from graphvision.compiler.compile import compile_graph
    from graphvision.execution.sweep import SweepInterrupted, sweep
    from graphvision.views.progress import FileProgress
    from graphvision.views.sweep_page import write_sweep

    if overrides:
        graph = graph.with_overrides(overrides)
    if args.plot:
        _check_plot(args, compile_graph(graph, registry, provided=set(inputs)))
    executor = executor_for(args)
    shown: list[FileProgress] = []
    report = _progress(grid, shown, time.monotonic())

    try:
        result = sweep(
            graph,
            grid,
            registry,
            inputs=inputs,
            cache=disk_cache(args),
            executor=executor,
            workers=args.workers,
            keep_going=args.keep_going,
            outputs=args.output,
            on_row=None if args.progress is False else report,
        )
    except SweepInterrupted as stopped:  # what is done is written, then the exit is 130 (143)
        if stopped.done:
            write_sweep(stopped.result, out_dir, graph.name, [])
            print(
                f"sweep interrupted; combinations done so far are in {out_dir / 'sweep.csv'}",
                file=sys.stderr,
            )
        raise stopped.__cause__ or stopped from None
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


def _check_plot(args: argparse.Namespace, compiled: CompiledGraph) -> None:
    """``-o`` names outputs and ``--plot`` one of their scalars, or a UsageError says not."""
    from graphvision.execution.sweep import scalar_outputs_of

    unknown = [name for name in args.output or () if name not in compiled.outputs]
    if unknown:
        raise UsageError(f"-o {unknown[0]}: no such output; outputs: {', '.join(compiled.outputs)}")
    scalars = scalar_outputs_of(compiled, args.output or list(compiled.outputs))
    if args.plot not in scalars:
        listing = ", ".join(scalars) or "none"
        raise UsageError(
            f"--plot {args.plot}: not a scalar output of the sweep"
            f"{did_you_mean(args.plot, scalars)}; scalar outputs: {listing}"
        )


def _progress(
    grid: dict[str, Any], shown: list[Any], began: float
) -> Callable[[int, int, dict[str, Any]], None]:
    """A sweep's ``on_row``: a bar on a terminal, else a line per combination (kept in
    ``shown``, to be closed by the caller)."""
    from graphvision.views.progress import FileProgress

    def report(number: int, total: int, row: dict[str, Any]) -> None:
        if not shown:
            shown.append(FileProgress(total, "combinations", began=began))
        combination = ", ".join(f"{key}={row[key]}" for key in grid)
        shown[0].finished(combination, row["status"] == "ok", row["seconds"])

    return report


def _listed(key: str, values: str) -> Any:
    """``--grid key=V1,V2,...``'s values read as YAML; an empty one (``3,,5``, a comma at
    either end) is named, not left to the YAML reader's words."""
    where = f"--grid {key}={values}"
    if re.search(r"(^|,)\s*(,|$)", values):
        raise UsageError(f"{where}: an empty value (give V1,V2,...)")
    return yaml_value(f"[{values}]", where)
