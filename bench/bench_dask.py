"""The Dask executor's cost per task against raw ``dask.distributed`` on the same graph.

A chain of trivial nodes (``x + 1``) on a 2-worker ``LocalCluster``: raw Dask
submits each task with its predecessor's future; graphvision runs the same
chain as a pipeline with :class:`~graphvision.DaskExecutor` on the same
client (each node a task, values in array encoding, results validated and
kept by the client). Raw Dask is also timed with the client taking each
result before it submits the next task, which is what an engine that
validates and caches every value on the client does. Independent tasks: raw
Dask submits them all and gathers; graphvision runs a fan-out pipeline of the
same tasks. Aim (issue 15): within
1.2× of raw Dask per task.

Run: ``python bench/bench_dask.py`` (``make bench`` runs every benchmark).
"""

from __future__ import annotations

import time
from pathlib import Path

from bench_scheduler import chain_graph, fan_graph, inc

import graphvision as gv

HERE = Path(__file__).parent
NODES = 200


def main() -> list[str]:
    try:
        import distributed
    except ImportError:
        return ["(Dask not installed: pip install 'graphvision[dask]')"]
    registry = gv.discover([HERE / "trivial_nodes.py"])
    compiled = gv.compile_graph(chain_graph(NODES), registry)
    fanned = gv.compile_graph(fan_graph(NODES), registry)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        executor = gv.DaskExecutor(client)

        def raw() -> None:
            future = client.submit(inc, 0.0, pure=False)
            for _ in range(NODES - 1):
                future = client.submit(inc, future, pure=False)
            assert future.result() == float(NODES)

        def raw_waiting() -> None:  # the client takes each result before the next task
            value = 0.0
            for _ in range(NODES):
                value = client.submit(inc, value, pure=False).result()
            assert value == float(NODES)

        def ours() -> None:
            result = gv.run(compiled, registry, executor=executor, cache=None)
            assert next(iter(result.outputs.values())) == float(NODES)

        def raw_independent() -> None:
            futures = [client.submit(inc, 0.0, pure=False) for _ in range(NODES)]
            assert sum(client.gather(futures)) == float(NODES)

        def ours_independent() -> None:
            result = gv.run(fanned, registry, executor=executor, cache=None)
            assert sum(result.outputs.values()) == float(NODES)

        timings = {}
        cases = (
            ("raw", raw),
            ("raw, waiting", raw_waiting),
            ("graphvision", ours),
            ("raw, independent", raw_independent),
            ("graphvision, independent", ours_independent),
        )
        for name, func in cases:
            func()
            runs = []
            for _ in range(3):
                began = time.perf_counter()
                func()
                runs.append(time.perf_counter() - began)
            timings[name] = min(runs) / NODES
    return [
        "| chain of trivial tasks, LocalCluster(2 workers) | ms per task |",
        "| --- | ---: |",
        f"| raw `dask.distributed` (`client.submit` chain) | {timings['raw'] * 1e3:.2f} |",
        f"| raw, the client taking each result before submitting the next | "
        f"{timings['raw, waiting'] * 1e3:.2f} |",
        f"| graphvision `DaskExecutor` | {timings['graphvision'] * 1e3:.2f} |",
        f"| graphvision / raw | {timings['graphvision'] / timings['raw']:.2f}× |",
        f"| graphvision / raw, waiting | {timings['graphvision'] / timings['raw, waiting']:.2f}× |",
        "",
        f"| {NODES} independent trivial tasks, same cluster | ms per task |",
        "| --- | ---: |",
        f"| raw `dask.distributed` (submit all, gather) | "
        f"{timings['raw, independent'] * 1e3:.2f} |",
        f"| graphvision `DaskExecutor` (a fan-out pipeline) | "
        f"{timings['graphvision, independent'] * 1e3:.2f} |",
        f"| graphvision / raw | "
        f"{timings['graphvision, independent'] / timings['raw, independent']:.2f}× |",
    ]


if __name__ == "__main__":
    print("\n".join(main()))
