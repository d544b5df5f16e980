"""Cache figures: warm against cold runs of the demo, input hashing, command start-up.

* Cold: a new process runs ``pipelines/homography.yaml`` with an empty disk
  cache. Warm: another new process runs it again on the same cache (every
  output is read from disk, no intermediate). Both as the CLI runs them,
  process start-up included, and as the run record times the run alone.
* Hashing: :func:`graphvision.cache.store.content_key` (xxh3-128 over dtype,
  shape and bytes) on arrays of 1 MiB to 256 MiB.
* Start-up: whole-process wall time of ``graphvision --help``, ``nodes``
  (with the plugin index, and without: a new cache folder, so the plugins are
  imported and the index written) and ``validate`` of the demo.

Cold means an empty result cache; the plugin index is present in both runs
(written once before, as any earlier command does), so cold and warm differ
by the results alone. Each start-up command has a cache folder of its own.
Python's own bytecode cache is as the environment sets it
(``PYTHONDONTWRITEBYTECODE`` makes every process compile graphvision's and
the plugins' modules again); the tables say which.

Run: ``python bench/bench_cache.py``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import graphvision as gv
from graphvision.cache.keys import content_key

ROOT = Path(__file__).parent.parent
DEMO = ROOT / "pipelines" / "homography.yaml"  # what make demo runs


def _environment(cache: Path) -> dict[str, str]:
    """The environment of a CLI process whose default cache (and plugin index) is ``cache``."""
    return {**os.environ, "GRAPHVISION_CACHE_DIR": str(cache)}


def _bytecode_note() -> str:
    written = "not written" if os.environ.get("PYTHONDONTWRITEBYTECODE") else "written"
    return f"Python bytecode of graphvision and the plugins: {written} (PYTHONDONTWRITEBYTECODE)."


def cli_run(cache: Path, out: Path, home: Path) -> tuple[float, float]:
    """(process wall time, run-record time) of one CLI run on the result cache ``cache``,
    with the default cache folder (beside which the plugin index is) ``home``."""
    began = time.perf_counter()
    subprocess.run(
        [
            sys.executable,
            "-m",
            "graphvision.cli",
            "run",
            str(DEMO),
            "--cache-dir",
            str(cache),
            "--output-dir",
            str(out),
            "--no-progress",
        ],
        check=True,
        capture_output=True,
        env=_environment(home),
    )
    wall = time.perf_counter() - began
    record = json.loads((out / "record.json").read_text())
    return wall, record["seconds"]


def warm_cold(repeats: int = 3) -> list[str]:
    rows = ["| run | process wall s | run record s |", "| --- | ---: | ---: |"]
    colds, warms = [], []
    with tempfile.TemporaryDirectory() as tmp:
        home = Path(tmp) / "home"
        _command_seconds(["nodes"], home)  # writes the plugin index
        for repeat in range(repeats):
            cache, out = Path(tmp) / f"cache-{repeat}", Path(tmp) / f"out-{repeat}"
            colds.append(cli_run(cache, out, home))
            warms.append(cli_run(cache, out, home))
    cold, warm = min(colds), min(warms)
    rows.append(f"| cold (empty disk cache) | {cold[0]:.3f} | {cold[1]:.4f} |")
    rows.append(f"| warm (new process, disk cache) | {warm[0]:.3f} | {warm[1]:.4f} |")
    rows.append(f"| warm / cold | {warm[0] / cold[0]:.0%} | {warm[1] / cold[1]:.1%} |")
    return [*rows, "", _bytecode_note()]


def _command_seconds(args: list[str], cache: Path) -> float:
    began = time.perf_counter()
    command = [sys.executable, "-m", "graphvision", *args]
    subprocess.run(command, check=True, capture_output=True, env=_environment(cache))
    return time.perf_counter() - began


def startup(repeats: int = 5) -> list[str]:
    """Best whole-process wall time of the commands a user waits for before any work."""
    rows = ["| command | process wall s |", "| --- | ---: |"]
    with tempfile.TemporaryDirectory() as tmp:
        cache = Path(tmp) / "cache"
        commands = {
            "graphvision --help": ["--help"],
            "graphvision nodes (plugin index present)": ["nodes"],
            "graphvision validate pipelines/homography.yaml": ["validate", str(DEMO)],
        }
        _command_seconds(["nodes"], cache)  # writes the plugin index
        for label, args in commands.items():
            seconds = min(_command_seconds(args, cache) for _ in range(repeats))
            rows.append(f"| {label} | {seconds:.3f} |")
        fresh = min(_command_seconds(["nodes"], Path(tmp) / f"new-{i}") for i in range(repeats))
        rows.append(
            f"| graphvision nodes (no index: plugins imported, index written) | {fresh:.3f} |"
        )
    return [*rows, "", _bytecode_note()]


def hashing() -> list[str]:
    rows = ["| array | GB/s |", "| --- | ---: |"]
    rng = np.random.default_rng(0)
    for side in (512, 2048, 8192):
        array = rng.random((side, side), dtype=np.float32)
        content_key(gv.ArrayPort, array)
        best = min(_timed(lambda a=array: content_key(gv.ArrayPort, a)) for _ in range(5))
        rows.append(
            f"| float32 {side}×{side} ({array.nbytes / 2**20:.0f} MiB) | "
            f"{array.nbytes / best / 1e9:.1f} |"
        )
    return rows


def _timed(func) -> float:
    began = time.perf_counter()
    func()
    return time.perf_counter() - began


def main() -> list[str]:
    return [
        "### Warm against cold (demo pipeline)",
        "",
        *warm_cold(),
        "",
        "### Hashing graph inputs",
        "",
        *hashing(),
        "",
        "### Start-up of commands",
        "",
        *startup(),
    ]


if __name__ == "__main__":
    print("\n".join(main()))
