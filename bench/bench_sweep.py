"""A 3×3 sweep of the homography pipeline against nine independent runs.

The sweep varies the matcher's ratio and RANSAC's threshold; SIFT of both
images is upstream of both and is computed once for all nine combinations.
Nine independent runs (each with a cold memory cache) are the reference.
Aim (issue 15): the sweep below 40 % of the nine runs' wall time.

Run: ``python bench/bench_sweep.py`` (``make bench`` runs every benchmark).
"""

from __future__ import annotations

import itertools
import time
from pathlib import Path

import graphvision as gv

PIPELINE = Path(__file__).parent.parent / "pipelines" / "homography.yaml"
GRID = {"params.ratio": [0.6, 0.7, 0.8], "fit.threshold": [1.0, 2.0, 3.0]}


def main() -> list[str]:
    graph = gv.load_pipeline(PIPELINE)
    registry = gv.discover(graph.plugins)
    gv.run(graph, registry, cache=None)  # warm-up: imports and compiled kernels
    began = time.perf_counter()
    result = gv.sweep(graph, GRID, registry)
    swept = time.perf_counter() - began
    began = time.perf_counter()
    for values in itertools.product(*GRID.values()):
        overrides = dict(zip(GRID, values, strict=True))
        gv.run(graph, registry, overrides=overrides, cache=gv.Cache(gv.MemoryStore()))
    separate = time.perf_counter() - began
    computed = sum(row["computed"] for row in result.rows)
    return [
        "| what | wall time s | nodes computed |",
        "| --- | ---: | ---: |",
        f"| 3×3 sweep (`gv.sweep`) | {swept:.2f} | {computed} |",
        f"| 9 independent runs | {separate:.2f} | {9 * result.rows[0]['computed']} |",
        f"| sweep / independent | {swept / separate:.0%} | |",
    ]


if __name__ == "__main__":
    print("\n".join(main()))
