"""Scheduler overhead per node: graphvision against dask.delayed, in one run.

A 10,000-node chain and a 1,000-node fan-out of trivial nodes (``x + 1``), no
cache. The figure is wall time per node of the run itself; graph building and
validation are reported apart. Dask runs the same functions with
``dask.delayed`` and its threaded scheduler.

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


def main() -> list[str]:
    import dask

    registry = gv.discover([HERE / "trivial_nodes.py"])
    rows = [
        "| shape | nodes | graphvision threads µs/node | graphvision sync µs/node | "
        "dask threads µs/node | dask / graphvision (threads) | build+validate µs/node |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for name, builder, dask_builder, n in [
        ("chain", chain_graph, dask_chain, 10_000),
        ("fan-out", fan_graph, dask_fan, 1_000),
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
        rows.append(
            f"| {name} | {n} | {threads * 1e6:.1f} | {sync * 1e6:.1f} | "
            f"{dask_time * 1e6:.1f} | {dask_time / threads:.1f}× | {build * 1e6:.1f} |"
        )
    return rows


if __name__ == "__main__":
    print("\n".join(main()))
