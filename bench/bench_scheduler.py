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

Run: ``python bench/bench_scheduler.py`` (``make bench`` runs every benchmark).
"""

from __future__ import annotations

import time
from pathlib import Path

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


if __name__ == "__main__":
    print("\n".join(main()))
