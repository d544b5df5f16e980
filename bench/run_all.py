"""Run every benchmark and write ``bench/results/latest.md`` (``make bench``).

``python bench/run_all.py "issue 25" studio`` runs only the sections whose title holds one
of the phrases (case aside) and rewrites those sections of ``latest.md``, keeping the rest;
every section says when it ran and the machine's load then.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))

import bench_backends  # noqa: E402
import bench_batch  # noqa: E402
import bench_cache  # noqa: E402
import bench_camera  # noqa: E402
import bench_colour_template  # noqa: E402
import bench_dask  # noqa: E402
import bench_detection  # noqa: E402
import bench_edges  # noqa: E402
import bench_faces  # noqa: E402
import bench_faster_rcnn  # noqa: E402
import bench_filters  # noqa: E402
import bench_find_object  # noqa: E402
import bench_held_out_geometry  # noqa: E402
import bench_held_out_robust  # noqa: E402
import bench_homography  # noqa: E402
import bench_kernels_contrib  # noqa: E402
import bench_kernels_vs_opencv  # noqa: E402
import bench_recognition  # noqa: E402
import bench_scheduler  # noqa: E402
import bench_segmentation  # noqa: E402
import bench_semantic_segmentation  # noqa: E402
import bench_stereo  # noqa: E402
import bench_studio  # noqa: E402
import bench_sweep  # noqa: E402
import profile_batch  # noqa: E402


def main(only: list[str]) -> None:
    """Run every section, or those whose title contains one of ``only`` (lower case),
    which then replace their own sections of ``latest.md`` and keep the others."""
    sections = [
        ("Scheduler overhead (engine issue)", bench_scheduler.main),
        ("Cache (engine issue)", bench_cache.main),
        ("Filters (engine issue)", bench_filters.main),
        ("Segmentation (segmentation issue)", bench_segmentation.main),
        ("Homography pipeline (features issue)", bench_homography.main),
        ("Recognition (recognition issue)", bench_recognition.main),
        ("Cameras and image formation (camera issue)", bench_camera.main),
        ("Edges and Hough (issue 10)", bench_edges.main),
        ("Colour, templates, FFT, pyramids (issue 10)", bench_colour_template.main),
        ("Two views and stereo (issue 12)", bench_stereo.main),
        ("Modern detection: CNN, proposals, R-CNN (issue 14)", bench_detection.main),
        ("Faster R-CNN and Mask R-CNN (issue 28)", bench_faster_rcnn.main),
        ("Finding every instance of an object (issue 28)", bench_find_object.main),
        ("Faces in photographs: LBP cascade (issue 28)", bench_faces.main),
        (
            "Held-out scenes: corners, Canny, DLT, proposals, significance (issue 24)",
            bench_held_out_robust.main,
        ),
        ("Own kernels against OpenCV, single-threaded (issue 26)", bench_kernels_vs_opencv.main),
        (
            "Own kernels against opencv-contrib, single-threaded (issue 26)",
            bench_kernels_contrib.main,
        ),
        (
            "Semantic segmentation: U-Net and per-pixel classifiers (issue 28)",
            bench_semantic_segmentation.main,
        ),
        ("Sweep sharing (issue 15)", bench_sweep.main),
        ("Studio: a change until the picture repaints (issue 27)", bench_studio.main),
        ("Batch on processes: start-up to the first file (issue 26)", fresh(bench_batch.startup)),
        ("Batch of 200 files against sync (issue 26)", fresh(bench_batch.main)),
        ("Batch on processes: 50, 200, 1,000 files (issue 26)", fresh(bench_batch.scaling)),
        ("Batch on Dask: bytes through the client (issue 26)", fresh(bench_batch.client_bytes)),
        ("Where a batch file's time goes (issue 26)", fresh(profile_batch.main)),
        ("Dask executor overhead (issue 15)", bench_dask.main),
        (
            "Held-out geometry: structured light, GHT, templates, lines (issue 24)",
            bench_held_out_geometry.main,
        ),
        ("Backends: the reference and OpenCV (issue 25)", bench_backends.main),
    ]
    chosen = [(t, f) for t, f in sections if not only or any(w in t.lower() for w in only)]
    if not chosen:
        titles = "\n  ".join(title for title, _ in sections)
        raise SystemExit(f"no section matches {' '.join(only)!r}; sections:\n  {titles}")
    out = HERE / "results" / "latest.md"
    kept = _sections_of(out) if only else {}
    for title, func in chosen:
        print(f"== {title}", flush=True)
        began = time.strftime("%Y-%m-%d %H:%M")
        rows = func()
        print("\n".join(rows), flush=True)
        load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
        kept[title] = [f"_Run {began}, load average {load}._", "", *rows]
    lines = [
        f"# graphvision benchmarks — {time.strftime('%Y-%m-%d %H:%M')}",
        "",
        f"Python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} cores",
        "",
    ]
    for title, _ in sections:  # the registry's order; a section never run is left out
        if title in kept:
            lines += [f"## {title}", "", *kept[title], ""]
    out.parent.mkdir(exist_ok=True)
    out.write_text("\n".join(lines))
    print(f"wrote {out}")


def fresh(func: Callable[[], list[str]]) -> Callable[[], list[str]]:
    """``func`` run in a new interpreter, as ``graphvision batch`` runs: a process in which
    earlier sections left threads (Dask's, a thread pool's) does not fork its workers from
    itself (``graphvision.execution.worker_start.fork_context``) and would time the fork
    server's start instead."""

    def run() -> list[str]:
        code = (
            f"import json, sys; sys.path.insert(0, {str(HERE)!r}); "
            f"import {func.__module__} as section; rows = section.{func.__name__}(); "
            "print('@@rows@@' + json.dumps(rows))"
        )
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        if done.returncode != 0 or "@@rows@@" not in done.stdout:
            raise SystemExit(f"{func.__module__}.{func.__name__} failed:\n{done.stderr}")
        rows: list[str] = json.loads(done.stdout.rsplit("@@rows@@", 1)[1])
        return rows

    return run


def _sections_of(path: Path) -> dict[str, list[str]]:
    """The sections of an earlier ``latest.md`` by title, kept when only some are run."""
    if not path.exists():
        return {}
    sections: dict[str, list[str]] = {}
    title = None
    for line in path.read_text().splitlines():
        if line.startswith("## "):
            title = line[3:]
            sections[title] = []
        elif title is not None:
            sections[title].append(line)
    return {title: _trimmed(rows) for title, rows in sections.items()}


def _trimmed(rows: list[str]) -> list[str]:
    while rows and not rows[-1].strip():
        rows = rows[:-1]
    while rows and not rows[0].strip():
        rows = rows[1:]
    return rows


if __name__ == "__main__":
    main([word.lower() for word in sys.argv[1:]])
