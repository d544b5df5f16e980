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

:func:`timeline` says where a 200-file coins batch's seconds go on a given
``LocalCluster(2)``, its workers' first batch and the next: timestamps from the
client (each file done, and where it ran) and from the workers (each task's
start and end, from Dask's task stream: a task carries up to sixteen files,
:mod:`graphvision.execution.dask_files`), and the CPU seconds of the client's
process (with the cluster's scheduler) and of the workers.

Run: ``python bench/bench_dask.py [timeline]`` (``make bench`` runs :func:`main`).
"""

from __future__ import annotations

import itertools
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


def _cpu() -> float:
    return time.process_time()


def timeline(files: int = 200) -> list[str]:
    """A coins batch on a running ``LocalCluster(2)``, twice (the workers' first batch, then
    the next): when the client and the workers did what, and the CPU seconds each spent."""
    import json
    import os
    import tempfile

    import bench_batch
    import distributed

    bench_batch.FILES = files
    graph = gv.load_pipeline(bench_batch.PIPELINE)
    rows = ["| batch | seconds | client files | warm-up tasks | first file task | tasks | "
            "task median ms | worker gaps ms | client+scheduler CPU s | workers CPU s |",
            "| --- | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]  # fmt: skip
    with (
        tempfile.TemporaryDirectory() as scratch,
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        paths = bench_batch._write_images(Path(scratch) / "in")
        for name in ("first", "next"):
            workers_cpu, client_cpu, began = client.run(_cpu), _cpu(), time.time()
            with distributed.get_task_stream(client) as stream:
                batch = gv.run_batch(
                    graph, [str(p) for p in paths], input="image",
                    output_dir=Path(scratch) / name, outputs=["count"],
                    executor=gv.DaskExecutor(client), cache=None,
                )  # fmt: skip
            seconds = time.time() - began
            spent = client.run(_cpu)
            workers = sum(spent[w] - workers_cpu[w] for w in spent)
            where = [json.loads((i.output_dir / "record.json").read_text())["executor"]
                     for i in batch.items]  # fmt: skip
            tasks = _tasks(stream.data, began)
            warm = ", ".join(f"{a:.2f}–{b:.2f}" for a, b, op, _ in tasks if op == "warm_worker")
            done = [(a, b, w) for a, b, op, w in tasks if op == "on_worker"]
            lengths = sorted(b - a for a, b, _ in done)
            gaps = sorted(_gaps(done))
            rows.append(
                f"| {name} | {seconds:.2f} | {sum('in the client' in w for w in where)} | "
                f"{warm} | {done[0][0]:.2f} | {len(done)} | "
                f"{lengths[len(lengths) // 2] * 1e3:.0f} | "
                f"{gaps[len(gaps) // 2] * 1e3:.1f} | {_cpu() - client_cpu:.2f} | {workers:.2f} |"
            )
    return [*rows, f"(load 1 min {os.getloadavg()[0]:.1f})"]


def _gaps(done: list[tuple[float, float, str]]) -> list[float]:
    """Seconds each worker waited between one file task's end and its next one's start."""
    found = []
    for worker in {w for *_, w in done}:
        mine = [t for t in done if t[2] == worker]
        found += [later[0] - earlier[1] for earlier, later in itertools.pairwise(mine)]
    return found


def _tasks(data: list[dict], began: float) -> list[tuple[float, float, str, str]]:
    """(start, end, function, worker) of each task Dask's task stream saw, from ``began``."""
    found = []
    for task in data:
        for part in task["startstops"]:
            if part["action"] == "compute":
                op = task["key"].rpartition("-")[0].split("-")[0]
                found.append((part["start"] - began, part["stop"] - began, op, task["worker"]))
    return sorted(found)


if __name__ == "__main__":
    import sys

    PARTS = {"main": main, "timeline": timeline}
    for part in sys.argv[1:] or ["main"]:
        print("\n".join([*PARTS[part](), ""]), flush=True)
