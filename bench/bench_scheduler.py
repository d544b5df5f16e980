"""Scheduler overhead per node: graphvision against Dask's schedulers, in one run.

A 10,000-node chain and a 1,000-node fan-out of trivial nodes (``x + 1``), no
cache. The figure is wall time per node of the run itself; graph building and
validation are reported apart. Dask runs the same functions twice: with
``dask.delayed`` and its threaded scheduler, and as a raw task graph (a dict
of tuples) through its plain synchronous scheduler ``dask.local.get_sync``,
the least work a Dask run can do.

Validation: a pipeline file of a chain of 1,000, 10,000 and 100,000 nodes,
parsed and compiled (what ``graphvision validate`` does), in µs per node, and
the peak memory traced meanwhile (``tracemalloc``, a separate untimed pass).

Phases (``--phases``): where a run's time goes, in CPU µs per node (``time.process_time``,
which load disturbs less than wall time), best of 7 runs: the inputs' and outputs' keys,
the nodes' records, the scheduler with the nodes themselves, ground-truth checks,
provenance, the outputs with their summaries, and the rest (arguments, BLAS limit,
executor).

Run: ``python bench/bench_scheduler.py [--phases | --graphvision]`` (``make bench`` runs every
benchmark; ``--graphvision`` gives graphvision's columns alone, with the load average).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from timing import best

import graphvision as gv

HERE = Path(__file__).parent


def inc(x: float) -> float:
    return x + 1.0


def chain_graph(n: int) -> gv.Graph:
    graph = gv.Graph("chain")
    previous = graph.input("x", "Float", default=0.0)
    for i in range(n):
        previous = graph.add(f"n{i}", "bench.inc", x=previous)
    graph.output("last", previous)
    return graph


def fan_graph(n: int) -> gv.Graph:
    graph = gv.Graph("fan")
    x = graph.input("x", "Float", default=0.0)
    for i in range(n):
        graph.output(f"o{i}", graph.add(f"n{i}", "bench.inc", x=x))
    return graph


def dask_chain(n: int):
    import dask

    value = 0.0
    for _ in range(n):
        value = dask.delayed(inc, pure=True)(value)
    return value


def dask_fan(n: int):
    import dask

    return [dask.delayed(inc, pure=True)(0.0, dask_key_name=f"n{i}") for i in range(n)]


def dask_raw_chain(n: int) -> tuple[dict, str]:
    graph: dict = {"n0": (inc, 0.0)}
    for i in range(1, n):
        graph[f"n{i}"] = (inc, f"n{i - 1}")
    return graph, f"n{n - 1}"


def dask_raw_fan(n: int) -> tuple[dict, list[str]]:
    return {f"n{i}": (inc, 0.0) for i in range(n)}, [f"n{i}" for i in range(n)]


def chain_file(n: int) -> str:
    """A pipeline file of an ``n``-node chain of ``bench.inc``."""
    lines = ["version: 1", "name: chain", "inputs:", "  x: {type: Float, default: 0.0}", "nodes:"]
    previous = "x"
    for i in range(n):
        lines.append(f"  n{i}: {{op: bench.inc, in: {{x: {previous}}}}}")
        previous = f"n{i}"
    return "\n".join([*lines, "outputs:", f"  last: {previous}", ""])


def validation_rows(registry: gv.Registry) -> list[str]:
    import tracemalloc

    from graphvision.graph.pipeline_file import parse_pipeline

    rows = [
        "| pipeline file | nodes | parse + compile µs/node | peak traced memory, bytes/node |",
        "| --- | ---: | ---: | ---: |",
    ]
    for n in (1_000, 10_000, 100_000):
        text = chain_file(n)

        def validate(text: str = text) -> None:
            gv.compile_graph(parse_pipeline(text, "chain.yaml"), registry)

        seconds = best(validate, 3 if n < 100_000 else 1)
        tracemalloc.start()
        validate()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        rows.append(f"| chain | {n} | {seconds / n * 1e6:.1f} | {peak / n:.0f} |")
    return rows


def main() -> list[str]:
    import dask
    from dask.local import get_sync

    registry = gv.discover([HERE / "trivial_nodes.py"])
    rows = [
        "| shape | nodes | graphvision threads µs/node | graphvision sync µs/node | "
        "dask threads µs/node | dask / graphvision (threads) | dask get_sync, raw graph "
        "µs/node | dask get_sync / graphvision (sync) | build+validate µs/node |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for name, builder, dask_builder, raw_builder, n in [
        ("chain", chain_graph, dask_chain, dask_raw_chain, 10_000),
        ("fan-out", fan_graph, dask_fan, dask_raw_fan, 1_000),
    ]:
        began = time.perf_counter()
        compiled = gv.compile_graph(builder(n), registry)
        build = (time.perf_counter() - began) / n
        threads = best(lambda c=compiled: gv.run(c, registry, executor="threads"), 7) / n
        sync = best(lambda c=compiled: gv.run(c, registry, executor="sync"), 7) / n
        result = gv.run(compiled, registry, executor="sync").outputs
        expected = float(n) if name == "chain" else 1.0
        assert next(iter(result.values())) == expected
        tasks = dask_builder(n)
        dask_time = best(lambda t=tasks: dask.compute(t, scheduler="threads"), 7) / n
        raw, keys = raw_builder(n)
        raw_time = best(lambda r=raw, k=keys: get_sync(r, k), 7) / n
        rows.append(
            f"| {name} | {n} | {threads * 1e6:.1f} | {sync * 1e6:.1f} | "
            f"{dask_time * 1e6:.1f} | {dask_time / threads:.1f}× | {raw_time * 1e6:.1f} | "
            f"{raw_time / sync:.1f}× | {build * 1e6:.1f} |"
        )
    return [*rows, "", *validation_rows(registry)]


def graphvision_rows(registry: gv.Registry) -> list[str]:
    """The µs per node of graphvision's runs alone, as :func:`main` measures them, with the
    load average (three of these give a min-max at one load in a few seconds)."""
    import os

    rows = [
        f"load average {os.getloadavg()[0]:.1f} (1 min)",
        "| shape | sync µs/node | threads µs/node |",
        "| --- | ---: | ---: |",
    ]
    for name, builder, n in [("chain", chain_graph, 10_000), ("fan-out", fan_graph, 1_000)]:
        compiled = gv.compile_graph(builder(n), registry)
        sync = best(lambda c=compiled: gv.run(c, registry, executor="sync"), 7) / n
        threads = best(lambda c=compiled: gv.run(c, registry, executor="threads"), 7) / n
        rows.append(f"| {name} | {sync * 1e6:.1f} | {threads * 1e6:.1f} |")
    return rows


def phase_rows(registry: gv.Registry, repeats: int = 7) -> list[str]:
    """CPU µs per node of each phase of a run (see the module docstring)."""
    from graphvision.execution import run as run_module
    from graphvision.execution.state import RunState

    spent: dict[str, float] = {}
    wrapped = [
        (RunState, "key_inputs", "keys"),
        (RunState, "key_steps", "keys"),
        (RunState, "prepare", "records"),
        (run_module, "run_tasks", "scheduler + nodes"),
        (run_module, "outputs_with_truth", "truth"),
        (run_module, "describe_run", "provenance"),
        (RunState, "result", "outputs"),
    ]
    originals = [(owner, name, getattr(owner, name)) for owner, name, _ in wrapped]

    def timed(original: Any, label: str) -> Any:
        def call(*args: Any, **kwargs: Any) -> Any:
            began = time.process_time()
            try:
                return original(*args, **kwargs)
            finally:
                spent[label] = spent.get(label, 0.0) + time.process_time() - began

        return call

    labels = ["keys", "records", "scheduler + nodes", "truth", "provenance", "outputs"]
    rows = [
        f"| shape | executor | total | {' | '.join(labels)} | rest |",
        "| --- | --- |" + " ---: |" * (len(labels) + 2),
    ]
    try:
        for owner, name, label in wrapped:
            setattr(owner, name, timed(getattr(owner, name), label))
        for shape, builder, n in [("chain", chain_graph, 10_000), ("fan-out", fan_graph, 1_000)]:
            compiled = gv.compile_graph(builder(n), registry)
            for executor in ("sync", "threads"):
                gv.run(compiled, registry, executor=executor)
                runs = []
                for _ in range(repeats):
                    spent.clear()
                    began = time.process_time()
                    gv.run(compiled, registry, executor=executor)
                    runs.append((time.process_time() - began, dict(spent)))
                total, parts = min(runs, key=lambda item: item[0])
                cells = [parts.get(label, 0.0) / n * 1e6 for label in labels]
                rest = total / n * 1e6 - sum(cells)
                rows.append(
                    f"| {shape} | {executor} | {total / n * 1e6:.1f} | "
                    + " | ".join(f"{c:.2f}" for c in cells)
                    + f" | {rest:.2f} |"
                )
    finally:
        for owner, name, original in originals:
            setattr(owner, name, original)
    return rows


if __name__ == "__main__":
    import sys

    if sys.argv[1:2] == ["--graphvision"]:  # graphvision's columns alone (no Dask, no files)
        print("\n".join(graphvision_rows(gv.discover([HERE / "trivial_nodes.py"]))))
    elif sys.argv[1:2] == ["--phases"]:
        print("\n".join(phase_rows(gv.discover([HERE / "trivial_nodes.py"]))))
    else:
        print("\n".join(main()))
