"""Cache figures: warm against cold runs of the demo pipeline, and input hashing speed.

* Cold: a new process runs ``pipelines/homography.yaml`` with an empty disk
  cache. Warm: another new process runs it again on the same cache (every
  output is read from disk, no intermediate). Both as the CLI runs them,
  process start-up included, and as the run record times the run alone.
* Hashing: :func:`graphvision._cache.content_key` (xxh3-128 over dtype,
  shape and bytes) on arrays of 1 MiB to 256 MiB.

Run: ``python bench/bench_cache.py``.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import graphvision as gv
from graphvision._cache import content_key

ROOT = Path(__file__).parent.parent
DEMO = ROOT / "pipelines" / "homography.yaml"  # what make demo runs


def cli_run(cache: Path, out: Path) -> tuple[float, float]:
    """(process wall time, run-record time) of one CLI run."""
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
    )
    wall = time.perf_counter() - began
    record = json.loads((out / "record.json").read_text())
    return wall, record["seconds"]


def warm_cold(repeats: int = 3) -> list[str]:
    rows = ["| run | process wall s | run record s |", "| --- | ---: | ---: |"]
    colds, warms = [], []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as tmp:
            cache, out = Path(tmp) / "cache", Path(tmp) / "out"
            colds.append(cli_run(cache, out))
            warms.append(cli_run(cache, out))
    cold, warm = min(colds), min(warms)
    rows.append(f"| cold (empty disk cache) | {cold[0]:.3f} | {cold[1]:.4f} |")
    rows.append(f"| warm (new process, disk cache) | {warm[0]:.3f} | {warm[1]:.4f} |")
    rows.append(f"| warm / cold | {warm[0] / cold[0]:.0%} | {warm[1] / cold[1]:.1%} |")
    return rows


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
    ]


if __name__ == "__main__":
    print("\n".join(main()))
