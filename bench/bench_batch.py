"""A batch of 200 images through the coins pipeline on each executor, against a plain loop.

The images are scikit-image's coins with seeded flips, gamma and noise,
written as PNG files. ``graphvision.run_batch`` (output ``count``; each file
also gets its folder with ``count.json``, ``record.json`` and the reports)
runs them with the ``sync`` executor (the reference: one file after another
in this thread), the thread executor, the process pool and a Dask
``LocalCluster`` of 2 worker processes (three ways: :func:`dask_runs`), each writing
the same folders; the
ratio is sync's time over the executor's (issue 26: processes at least 1.7×,
threads 1.3×, Dask 1.6× on 2 cores). Each executor's run is paired with a sync
batch timed just before it (:func:`_paired_row`): this VM's file system makes files
more slowly for minutes after many were deleted, which moved a ratio taken against
one sync batch by a third. A Python loop calling the same node
functions on each file, writing nothing (the plain loop), shows what the engine adds. No
cache, so every file is computed. The machine's load (1-minute average)
is printed beside each row.

Two rows give the ceiling two cores allow on this work, each against the plain loop
in one process timed just before it (alternated, several runs: min–max), not
against sync: "plain loop, split over 2 processes (the machine's ceiling)" runs
each half of the files through the plain loop in one of two processes forked
before the clock (nothing to import, compile or send but the paths and the
counts); two cores gave about 1.75× on it, not 2×. "plain loop on the same
cluster, raw Dask" runs the plain loop on the running ``LocalCluster(2)`` of the
Dask rows through ``dask.distributed`` alone (:func:`raw_dask`: ``client.map`` of
a few files a task, read on the workers, counts gathered), the scheduler in the
client's process as a ``LocalCluster``'s is: the most a graphvision batch on
Dask could reach here.

:func:`scaling` runs the batch on processes over 50, 200 and 1,000 files:
time per file and the client's peak traced memory (``tracemalloc``) should
stay flat.

:func:`startup` times a processes batch's start-up (run it alone, in a fresh
process: ``python bench/bench_batch.py startup``): when its first file is done
(on the first worker when they are forked from the client, the default; in the client
from the fork server), how many files the client ran itself while the workers started
(``batch_lanes``: none when forked), when the first further file is done on a worker,
with the workers forked from the client and from the fork server, and the fork
server's steps one by one. :func:`main` also runs the first 50 files alone on
sync and processes.

Run: ``python bench/bench_batch.py [startup] [main] [client_bytes] [scaling]`` (all
four without an argument; ``make bench`` runs every benchmark).
"""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import imageio.v3 as iio
import numpy as np

import graphvision as gv
from graphvision.nodes.marks import unchecked
from graphvision_plugins import colour, morphology, regions, threshold
from graphvision_plugins.io import read_array, read_sample

PIPELINE = Path(__file__).parents[1] / "pipelines" / "coins.yaml"
FILES = 200


def _write_images(folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    coins = read_sample("coins")
    paths = []
    for k in range(FILES):
        image = coins[:, ::-1] if k % 2 else coins
        image = np.clip(image ** rng.uniform(0.8, 1.25) + rng.normal(0, 0.01, image.shape), 0, 1)
        paths.append(folder / f"coins_{k:03d}.png")
        iio.imwrite(paths[-1], np.round(image * 255).astype(np.uint8))
    return paths


def _loop(paths: list[Path]) -> list[int]:
    """The floor: the pipeline's nodes called in a loop, unchecked, nothing written."""
    disk = unchecked(morphology.footprint)(shape="disk", size=5)
    counts = []
    for path in paths:
        image = read_array(str(path)).astype(np.float32) / 255.0
        gray = unchecked(colour.to_gray)(image)
        binary = unchecked(threshold.local)(gray, window=51, k=0.0, foreground="bright")
        closed = unchecked(morphology.close)(binary, disk)
        filled = unchecked(morphology.fill_holes)(closed)
        opened = unchecked(morphology.open)(filled, disk)
        labels = unchecked(regions.label)(opened, connectivity=8)
        table = unchecked(regions.describe)(labels, gray)
        kept = unchecked(regions.filter_regions)(
            labels, table, ranges={"area": (400, None), "circularity": (0.7, None)}
        )
        counts.append(int(kept.count))
    return counts


def _batch(graph: gv.Graph, paths: list[Path], out: Path, executor: object) -> tuple[float, int]:
    """Seconds of one ``run_batch`` (all the default pages written), files counting 24 coins."""
    began = time.perf_counter()
    batch = gv.run_batch(
        graph,
        [str(p) for p in paths],
        input="image",
        output_dir=out,
        outputs=["count"],
        executor=executor,  # type: ignore[arg-type]
        workers=2,
        cache=None,
    )
    seconds = time.perf_counter() - began
    return seconds, sum(item.scalars.get("count") == 24 for item in batch.items)


def _warm(graph: gv.Graph, paths: list[Path], out: Path) -> None:
    """The process's modules imported and kernels loaded before any row is timed (one file
    through the node functions, then a one-file batch), so that no row pays them alone."""
    _loop(paths[:1])
    _batch(graph, paths[:1], out, "sync")


def _load() -> str:
    return f"{os.getloadavg()[0]:.1f}"


def main() -> list[str]:
    graph = gv.load_pipeline(PIPELINE)
    rows = [
        f"| {FILES} coins images | seconds | images/s | sync / this | counts of 24 | load 1 min |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        paths = _write_images(folder / "in")
        _warm(graph, paths, folder / "warm")
        began = time.perf_counter()
        counts = _loop(paths)
        floor = time.perf_counter() - began
        sync, good = _batch(graph, paths, folder / "sync", "sync")
        rows.append(
            f"| plain loop of node functions (writes nothing) | {floor:.1f} | "
            f"{FILES / floor:.1f} | {sync / floor:.2f}× | {sum(c == 24 for c in counts)} | "
            f"{_load()} |"
        )
        rows.append(_split_row(paths))
        rows.append(
            f"| graphvision batch, sync | {sync:.1f} | {FILES / sync:.1f} | 1.00× | {good} | "
            f"{_load()} |"
        )
        for name, executor in (("threads (2)", "threads"), ("processes (2)", "processes")):
            rows.append(_paired_row(graph, paths, folder / name[:5], name, executor))
        rows += _in_memory_rows(graph, paths)
        engine = _engine_rows(floor, sync)
        fewer = _fewer(graph, paths[:50], folder)
        rows += _dask_rows(graph, paths, folder)  # last: its client's threads stay
    return [*rows, *fewer, "", *engine]


CEILING_RUNS = 3


def _split_row(paths: list[Path]) -> str:
    """The machine's ceiling: the plain loop over each half of the files in two processes
    forked before the clock (from this warmed process: nothing to import or compile), against
    the same loop over all the files in this process, alternated :data:`CEILING_RUNS` times."""
    import multiprocessing

    halves = [paths[: len(paths) // 2], paths[len(paths) // 2 :]]
    runs = []
    with multiprocessing.get_context("fork").Pool(2) as pool:
        pool.map(_loop, [paths[:1]] * 2, chunksize=1)  # the pool's first round trip
        for _ in range(CEILING_RUNS):
            one = _timed(_loop, paths)
            split = _timed(lambda: [c for half in pool.map(_loop, halves, 1) for c in half])
            runs.append((one, split, _load()))
    return _ceiling_row("plain loop, split over 2 processes (the machine's ceiling)", runs)


def _timed(run: Callable[..., list[int]], *args: object) -> tuple[float, int]:
    """Seconds of ``run(*args)`` and how many of the counts it returns are 24."""
    began = time.perf_counter()
    counts = run(*args)
    return time.perf_counter() - began, sum(c == 24 for c in counts)


def _ceiling_row(name: str, runs: list[tuple[tuple[float, int], tuple[float, int], str]]) -> str:
    """A ceiling row: seconds of each run of ``name`` (the second of each pair) as min–max,
    and its ratio to the plain loop in one process timed just before it (the first), as
    min–max over the pairs; the load at each."""
    times = sorted(split for _, (split, _), _ in runs)
    ratios = sorted(one / split for (one, _), (split, _), _ in runs)
    good = min(g for _, (_, g), _ in runs)
    loads = ", ".join(load for *_, load in runs)
    return (
        f"| {name} ({len(runs)} runs) | {times[0]:.2f}–{times[-1]:.2f} | "
        f"{FILES / times[-1]:.1f}–{FILES / times[0]:.1f} | "
        f"{ratios[0]:.2f}–{ratios[-1]:.2f}× the loop in one process | {good} | {loads} |"
    )


def _engine_rows(floor: float, sync: float) -> list[str]:
    """Per file: the nodes' compute (the plain loop's time) and the engine's cost beside
    it (the sync batch's time less the loop's: planning, checks, record, outputs, reports;
    ``profile_batch.py`` splits it)."""
    return [
        f"| {FILES} coins images, sync, per file | ms | load 1 min |",
        "| --- | ---: | ---: |",
        f"| compute per file, ms (the plain loop) | {floor / FILES * 1e3:.1f} | {_load()} |",
        f"| engine cost per file, ms (sync batch less the loop) | "
        f"{(sync - floor) / FILES * 1e3:.1f} | {_load()} |",
    ]


PAIRED_RUNS = 3


def _paired_row(graph: gv.Graph, paths: list[Path], folder: Path, name: str, executor: str) -> str:
    """The batch on ``executor``, each of :data:`PAIRED_RUNS` runs right after a sync batch
    of the same files, its ratio to that one: on this VM, making files slows down for
    minutes after many were deleted (ext4's inode allocator), so a sync batch timed once at
    the start stood for a file system in another state (ratios from 1.25 to 1.74× for one
    build); seconds and ratios as min–max, with the load at each run."""
    runs = []
    for run in range(PAIRED_RUNS):
        sync, _ = _batch(graph, paths, folder / f"sync{run}", "sync")
        seconds, good = _batch(graph, paths, folder / f"run{run}", executor)
        runs.append((seconds, good, sync / seconds, _load()))
    return _range_row(f"graphvision batch, {name}, each after a sync batch", runs)


def _in_memory_rows(graph: gv.Graph, paths: list[Path]) -> list[str]:
    """:func:`_paired_row` on threads and processes with every folder written in memory
    (``/dev/shm``, where the machine has it): the engine's scaling without the disk's state,
    which moved the rows above from run to run."""
    if not os.path.isdir("/dev/shm"):
        return []
    rows = []
    with tempfile.TemporaryDirectory(dir="/dev/shm") as memory:
        for name, executor in (("threads (2)", "threads"), ("processes (2)", "processes")):
            where = Path(memory) / executor
            rows.append(_paired_row(graph, paths, where, f"{name}, folders in /dev/shm", executor))
    return rows


def _range_row(name: str, runs: list[tuple[float, int, float, str]]) -> str:
    """A row of several runs, each ``(seconds, counts of 24, sync / this, load)``."""
    times = sorted(seconds for seconds, *_ in runs)
    ratios = sorted(ratio for _, _, ratio, _ in runs)
    good = min(g for _, g, _, _ in runs)
    loads = ", ".join(load for *_, load in runs)
    return (
        f"| {name} ({len(runs)} runs) | {times[0]:.1f}–{times[-1]:.1f} | "
        f"{FILES / times[-1]:.1f}–{FILES / times[0]:.1f} | "
        f"{ratios[0]:.2f}–{ratios[-1]:.2f}× | {good} | {loads} |"
    )


def _dask_rows(graph: gv.Graph, paths: list[Path], folder: Path) -> list[str]:
    """The batch on Dask three ways and raw Dask's ceiling (see :func:`dask_runs`),
    :data:`DASK_RUNS` times each, against a sync batch timed before each run (the ceiling
    against the plain loop in one process): seconds and ratios as min–max, with the load
    at each run. Run after the others: the threads of a Dask client stay in the process
    after it closes."""
    found: dict[str, list[tuple[float, int, float, str]]] = {}
    ceiling: list[tuple[tuple[float, int], tuple[float, int], str]] = []
    for run in range(DASK_RUNS):  # each run's ratios against a sync batch just before it
        sync, _ = _batch(graph, paths, folder / f"sync{run}", "sync")
        for name, seconds, good, loop in dask_runs(graph, paths, folder / f"run{run}"):
            if loop is None:
                found.setdefault(name, []).append((seconds, good, sync / seconds, _load()))
            else:
                ceiling.append((loop, (seconds, good), _load()))
    rows = [_range_row(f"graphvision batch, Dask {name}", runs) for name, runs in found.items()]
    if ceiling:
        rows.append(
            _ceiling_row(f"plain loop on the same cluster, raw Dask ({RAW_TASKS})", ceiling)
        )
    return rows or ["(Dask not installed: pip install 'graphvision[dask]')"]


DASK_RUNS = 3
RAW_FILES_PER_TASK = 16  # as many as a graphvision task's most (dask_files.FILES_PER_TASK)
RAW_TASKS = f"client.map, {RAW_FILES_PER_TASK} files a task"


def dask_runs(
    graph: gv.Graph, paths: list[Path], folder: Path
) -> list[tuple[str, float, int, tuple[float, int] | None]]:
    """Seconds of the batch on a Dask ``LocalCluster`` of 2 single-threaded worker processes,
    and the files that counted 24 coins: ``executor="dask"`` in a fresh process, as the
    command line runs it (the executor starts the cluster, forking its workers from the
    client after the first file, and closes it: timed with it; :func:`own_cluster`); a
    running cluster given to ``DaskExecutor``, started before the clock, on its workers'
    first batch (each worker imports graphvision, the plugins, scipy and numba's compiler
    while the client runs files); and the same cluster's next batch (a long-lived cluster:
    nothing left to start). Last, the Dask ceiling on the same cluster (:func:`raw_dask`),
    with the plain loop in this process timed just before it (the fourth item; None for
    the batches)."""
    try:
        import distributed
    except ImportError:
        return []
    own = _own_cluster_run(paths, folder)
    found: list[tuple[str, float, int, tuple[float, int] | None]] = [
        ("(executor starts LocalCluster(2) itself, timed)", *own, None)
    ]
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        for name in ("running LocalCluster(2) given, workers' first batch", "same, next batch"):
            executor = gv.DaskExecutor(client)
            seconds, good = _batch(graph, paths, folder / f"dask-{len(found)}", executor)
            found.append((name, seconds, good, None))
        loop = _timed(_loop, paths)
        found.append(("raw", *raw_dask(client, paths), loop))
    return found


def raw_dask(client: Any, paths: list[Path]) -> tuple[float, int]:
    """The plain loop through raw ``dask.distributed`` on ``client``'s running cluster (the
    scheduler in this process, as a ``LocalCluster``'s): ``client.map`` of
    :data:`RAW_FILES_PER_TASK` files a task, read on the workers, and a ``gather`` of their
    counts; its seconds (each worker having run one file before the clock) and the counts
    of 24. The ceiling Dask itself gives a graphvision batch on this machine."""
    for address in client.scheduler_info()["workers"]:
        client.submit(_loop_on_worker, paths[:1], workers=[address], pure=False).result()
    chunks = [paths[k : k + RAW_FILES_PER_TASK] for k in range(0, len(paths), RAW_FILES_PER_TASK)]

    def run() -> list[int]:
        tasks = client.map(_loop_on_worker, chunks, pure=False)
        return [count for counts in client.gather(tasks) for count in counts]

    return _timed(run)


def _loop_on_worker(paths: list[Path]) -> list[int]:
    """:func:`_loop` on a Dask worker, its heap set as graphvision's tasks set it there
    (:func:`~graphvision.execution.dask_worker.keep_freed_memory`: the nanny's
    ``MALLOC_TRIM_THRESHOLD_`` makes each large array a fresh mapping)."""
    from graphvision.execution.dask_worker import keep_freed_memory

    keep_freed_memory()
    return _loop(paths)


def _own_cluster_run(paths: list[Path], folder: Path) -> tuple[float, int]:
    """:func:`own_cluster` in a fresh interpreter: its seconds and good files."""
    import subprocess
    import sys

    command = [sys.executable, __file__, "own_cluster", str(paths[0].parent), str(folder)]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    seconds, good = done.stdout.split()[-2:]
    return float(seconds), int(good)


def own_cluster(images: str, folder: str) -> list[str]:
    """``executor="dask"`` on the images in ``images`` (warmed as :func:`main` is first):
    its seconds and the files that counted 24 coins."""
    graph = gv.load_pipeline(PIPELINE)
    paths = sorted(Path(images).glob("coins_*.png"))
    _warm(graph, paths, Path(folder) / "own-warm")
    seconds, good = _batch(graph, paths, Path(folder) / "dask-own", "dask")
    return [f"{seconds:.3f} {good}"]


def _fewer(graph: gv.Graph, paths: list[Path], folder: Path) -> list[str]:
    """The first ``len(paths)`` files alone, on sync and on processes (the start-up weighs
    more in a shorter batch)."""
    sync, good = _batch(graph, paths, folder / "sync-fewer", "sync")
    seconds, good_processes = _batch(graph, paths, folder / "processes-fewer", "processes")
    files = len(paths)
    return [
        f"| {files} files, graphvision batch, sync | {sync:.1f} | {files / sync:.1f} | 1.00× | "
        f"{good} | {_load()} |",
        f"| {files} files, graphvision batch, processes (2) | {seconds:.1f} | "
        f"{files / seconds:.1f} | {sync / seconds:.2f}× | {good_processes} | {_load()} |",
    ]


def scaling(sizes: tuple[int, ...] = (50, 200, 1000)) -> list[str]:
    """The batch on processes for growing numbers of files: seconds per file should stay
    flat (time linear in files), and so should the client's peak traced memory."""
    import tracemalloc

    global FILES
    graph = gv.load_pipeline(PIPELINE)
    rows = [
        "| files (processes, 2) | seconds | ms per file | client peak traced MB | load 1 min |",
        "| ---: | ---: | ---: | ---: | ---: |",
    ]
    saved = FILES
    try:
        for files in sizes:
            FILES = files
            with tempfile.TemporaryDirectory() as scratch:
                paths = _write_images(Path(scratch) / "in")
                _warm(graph, paths, Path(scratch) / "warm")
                tracemalloc.start()
                seconds, good = _batch(graph, paths, Path(scratch) / "out", "processes")
                peak = tracemalloc.get_traced_memory()[1]
                tracemalloc.stop()
                assert good == files, f"{files - good} files did not count 24 coins"
            rows.append(
                f"| {files} | {seconds:.1f} | {seconds / files * 1e3:.1f} | {peak / 2**20:.1f} | "
                f"{_load()} |"
            )
    finally:
        FILES = saved
    return rows


def startup(files: int = 200) -> list[str]:
    """Where a processes batch's start-up goes: seconds from the batch's start until its
    first file (on the first worker when they are forked from the client, else in the
    client), the files the client ran itself while the workers started (none when forked),
    the first further file done on a worker, then per further file; once with the workers
    forked from the client as the batch starts (the default), once from the fork server
    (``GRAPHVISION_WORKER_START=forkserver``, what a client with other threads gets); and
    the fork server's steps, replayed one by one in a fresh interpreter
    (:func:`server_steps`). Meaningful for the first processes batch of a process (the
    server then starts): run it alone."""
    graph = gv.load_pipeline(PIPELINE)
    rows = [
        f"| processes (2), {files} files, first batch of the process | workers forked from "
        "the client | from the fork server | load 1 min |",
        "| --- | ---: | ---: | ---: |",
    ]
    forked = _startup_run(graph, files, "")
    served = _startup_run(graph, files, "forkserver")
    for (label, one), (_, two) in zip(forked, served, strict=True):
        rows.append(f"| {label} | {one} | {two} | {_load()} |")
    return [*rows, "", *server_steps(graph)]


def _startup_run(graph: gv.Graph, files: int, start: str) -> list[tuple[str, str]]:
    """One processes batch of ``files``, its workers started as ``start`` says (see
    :func:`startup`): its rows' labels and values."""
    import json

    global FILES
    saved, FILES = FILES, files
    os.environ["GRAPHVISION_WORKER_START"] = start
    try:
        with tempfile.TemporaryDirectory() as scratch:
            paths = _write_images(Path(scratch) / "in")
            _loop(paths[:1])  # the client's kernels loaded, as in main()
            gv.run_batch(  # the plugin index and the client's imports, as in main()
                graph, [str(paths[0])], input="image", output_dir=Path(scratch) / "w", cache=None
            )
            done: list[tuple[float, Path]] = []
            began = time.perf_counter()
            gv.run_batch(
                graph,
                [str(p) for p in paths],
                input="image",
                output_dir=Path(scratch) / "out",
                outputs=["count"],
                executor="processes",
                workers=2,
                cache=None,
                on_item=lambda *a: done.append((time.perf_counter() - began, a[2].output_dir)),
            )
            total = time.perf_counter() - began
            where = [
                json.loads((folder / "record.json").read_text())["executor"] for _, folder in done
            ]
    finally:
        FILES = saved
        os.environ.pop("GRAPHVISION_WORKER_START")
    client = [t for (t, _), w in zip(done, where, strict=True) if "in the client while" in w]
    workers = [t for (t, _), w in zip(done, where, strict=True) if w.endswith(" a task")]
    rest = (workers[-1] - workers[0]) / max(len(workers) - 1, 1)
    return [
        ("first file done (forked: on a worker; else in the client), s", f"{done[0][0]:.2f}"),
        ("files the client ran while the workers started", f"{len(client)}"),
        ("the last of them done at, s", f"{client[-1]:.2f}" if client else "-"),
        ("first further file done on a worker, s", f"{workers[0]:.2f}"),
        (f"each further file on the workers ({len(workers)} files, 2 workers), s", f"{rest:.3f}"),
        ("whole batch, s", f"{total:.2f}"),
    ]


STEPS = """
import importlib, json, os, sys, time
began = time.perf_counter()
sys.path[:] = json.loads(os.environ["BENCH_CLIENT_PATH"])  # as the server takes it
def mark(label):
    print(f"{time.perf_counter() - began:.3f} {label}", flush=True)
import graphvision.execution.file_task
mark("interpreter, numpy, graphvision (the file task)")
import numba
mark("import numba")
import graphvision.execution._numba_setup
mark("numba's compiler set up (CPU target refresh)")
from graphvision.execution.batch_preload import import_modules, load_kernels
found = import_modules(sys.argv[2:])
mark(f"the batch's {len(sys.argv) - 2} modules (plugins, scipy.ndimage, kernels, pages)")
load_kernels(found)
mark("their numba kernels loaded from numba's cache")
import graphvision as gv
from graphvision.execution.file_task import warm_graph
warm_graph(gv.load_pipeline(sys.argv[1]), (), ("image",))
mark("the batch's graph loaded and compiled (registry, parameter models, fingerprints)")
"""


def server_steps(graph: gv.Graph) -> list[str]:
    """The fork server's start for a coins batch, step by step: the same imports, numba
    set-up, kernel loads and graph compile, timed in a fresh interpreter with the client's
    ``sys.path``, as the server has it (seconds since its first line; the interpreter's own
    start before that is not counted). Without the client's path, the plugin index's key
    differed: the replay imported every plugin (0.9 s of the 2 s it measured), then
    removed the client's index for its own."""
    import json
    import subprocess
    import sys

    from graphvision.execution.batch import _checked_pipeline
    from graphvision.execution.file_task import preload_modules
    from graphvision.views.batch_page import BATCH_PAGES

    registry = _checked_pipeline(graph, None, {}, "image", ["count"], {})
    modules = preload_modules(registry, graph, tuple(BATCH_PAGES.run))
    command = [sys.executable, "-c", STEPS, str(PIPELINE), *modules]
    env = {**os.environ, "BENCH_CLIENT_PATH": json.dumps(sys.path)}  # the plugin index's key
    lines = subprocess.run(command, capture_output=True, text=True, check=True, env=env).stdout
    rows = ["| the fork server's steps (fresh interpreter) | seconds at its end | step |"]
    rows.append("| --- | ---: | ---: |")
    last = 0.0
    for line in lines.splitlines():
        at, _, label = line.partition(" ")
        rows.append(f"| {label} | {float(at):.2f} | {float(at) - last:.2f} |")
        last = float(at)
    return [*rows, f"(load 1 min {_load()})"]


def client_bytes(files: int = 200) -> list[str]:
    """A batch on a Dask LocalCluster (2 worker processes) with a disk cache the workers
    share: the bytes of the values they computed against what passed through the client."""
    try:
        import distributed
    except ImportError:
        return ["(Dask not installed: pip install 'graphvision[dask]')"]
    global FILES
    graph, saved, FILES = gv.load_pipeline(PIPELINE), FILES, files
    try:
        with (
            tempfile.TemporaryDirectory() as scratch,
            distributed.LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
            ) as cluster,
            distributed.Client(cluster) as client,
        ):
            paths = _write_images(Path(scratch) / "in")
            batch = gv.run_batch(
                graph,
                [str(p) for p in paths],
                input="image",
                output_dir=Path(scratch) / "out",
                executor=gv.DaskExecutor(client),
                cache=gv.Cache.at(Path(scratch) / "cache"),
            )
    finally:
        FILES = saved
    share = batch.client_bytes / max(batch.value_bytes, 1)
    return [
        f"| {files} files on Dask (2 workers), disk cache shared | bytes |",
        "| --- | ---: |",
        f"| values the workers computed (files 2 to {files}, encoded) | {batch.value_bytes:,} |",
        f"| through the client (job once, file and folder per task, outcomes) | "
        f"{batch.client_bytes:,} ({share:.2%}) |",
    ]


if __name__ == "__main__":
    import sys

    PARTS = {"startup": startup, "main": main, "client_bytes": client_bytes, "scaling": scaling}
    if sys.argv[1:2] == ["own_cluster"]:  # one run, for dask_runs
        print(*own_cluster(*sys.argv[2:4]))
        sys.exit(0)
    chosen = sys.argv[1:] or list(PARTS)  # e.g. ``python bench/bench_batch.py main``
    for name in chosen:
        print("\n".join([*PARTS[name](), ""]), flush=True)
