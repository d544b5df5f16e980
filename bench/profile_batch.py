"""Where a batch file's time goes: the engine's cost per file beside the nodes' compute.

A ``sync`` batch of coins images (as ``bench_batch.py`` makes them) runs
under ``cProfile``; the cumulative time of the functions that do each part
of the engine's work, divided by the files, gives milliseconds per file:

- compute: the node functions themselves;
- planning: compiling the graph, keying the steps, the cache plan;
- hashing: content keys of the inputs, SHA-256 of the input file and of the
  files written (provenance, ``record.json``'s ``file_sha256``);
- transport: port types' encode/decode (cache entries, values to and from
  other processes);
- record: the run's provenance (versions, git state) and ``record.json``;
- report: ``report.md`` and ``report.html`` less their thumbnails;
- thumbnails: the pictures' thumbnails and their PNG bytes in ``report.html``;
- outputs: the outputs' files (PNG, ``.npy``, JSON).

The parts overlap where one calls another (the report's thumbnails are
inside the report; outputs' PNG encoding is not a thumbnail). cProfile slows
Python-heavy parts more than array kernels, so read the split, not the sum.
Times are CPU time (the profiler's clock is ``time.process_time``), which the
machine's load inflates far less than wall time.

Run: ``python bench/profile_batch.py [FILES]``.
"""

from __future__ import annotations

import cProfile
import os
import pstats
import sys
import tempfile
import time
from pathlib import Path

from bench_batch import PIPELINE, _write_images

import graphvision as gv

PARTS: dict[str, list[tuple[str, str]]] = {
    "compute": [("executors.py", "call_node"), ("state.py", "run_here")],
    "planning": [
        ("run.py", "_compiled"),
        ("state.py", "key_steps"),
        ("state.py", "plan"),
        ("state.py", "prepare"),
    ],
    "hashing": [("keys.py", "content_key"), ("provenance.py", "file_sha256")],
    "transport": [("/values/", "encode"), ("/values/", "decode")],
    "record": [("provenance.py", "describe_run"), ("record.py", "to_json")],
    "report": [("report.py", "markdown_page"), ("report.py", "html_page")],
    "thumbnails": [("pictures.py", "png_bytes"), ("pictures.py", "thumbnail")],
    "outputs": [("folders.py", "write_outputs")],
}


def _cumulative(stats: pstats.Stats, file: str, function: str) -> float:
    total = 0.0
    for (path, _, name), (_, _, _, cumulative, _) in stats.stats.items():  # type: ignore[attr-defined]
        if file in path and name == function:
            total += cumulative
    return total


def profile(files: int) -> list[str]:
    """Per-file milliseconds of each part, under cProfile, for a sync batch of ``files``."""
    import bench_batch

    bench_batch.FILES = files
    graph = gv.load_pipeline(PIPELINE)
    with tempfile.TemporaryDirectory() as scratch:
        paths = _write_images(Path(scratch) / "in")
        gv.run_batch(  # plugins loaded, kernels compiled: what follows is per file
            graph, [str(paths[0])], input="image", output_dir=Path(scratch) / "warm", cache=None
        )
        profiler = cProfile.Profile(time.process_time)  # CPU time: what load cannot inflate
        began, cpu = time.perf_counter(), time.process_time()
        profiler.enable()
        gv.run_batch(
            graph,
            [str(p) for p in paths],
            input="image",
            output_dir=Path(scratch) / "out",
            executor="sync",
            cache=None,
        )
        profiler.disable()
        wall, cpu = time.perf_counter() - began, time.process_time() - cpu
    stats = pstats.Stats(profiler)
    load = f"{os.getloadavg()[0]:.1f}"
    rows = [
        f"| part ({files} files, sync, under cProfile) | CPU ms per file | load 1 min |",
        "| --- | ---: | ---: |",
        f"| whole file (profiled; wall {wall / files * 1e3:.1f} ms) | {cpu / files * 1e3:.1f} "
        f"| {load} |",
    ]
    for part, functions in PARTS.items():
        seconds = sum(_cumulative(stats, f, name) for f, name in functions)
        rows.append(f"| {part} | {seconds / files * 1e3:.1f} | {load} |")
    return rows


def main() -> list[str]:
    return profile(50)


if __name__ == "__main__":
    print("\n".join(profile(int(sys.argv[1]) if len(sys.argv) > 1 else 50)))
