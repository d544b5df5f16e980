"""Run every benchmark and write ``bench/results/latest.md`` (``make bench``)."""

from __future__ import annotations

import platform
import sys
import time
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


def main() -> None:
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
        ("Batch of 200 files against sync (issue 26)", bench_batch.main),
        ("Batch on processes: 50, 200, 1,000 files (issue 26)", bench_batch.scaling),
        ("Batch on Dask: bytes through the client (issue 26)", bench_batch.client_bytes),
        ("Where a batch file's time goes (issue 26)", profile_batch.main),
        ("Dask executor overhead (issue 15)", bench_dask.main),
        (
            "Held-out geometry: structured light, GHT, templates, lines (issue 24)",
            bench_held_out_geometry.main,
        ),
        ("Backends: the reference and OpenCV (issue 25)", bench_backends.main),
    ]
    lines = [
        f"# graphvision benchmarks — {time.strftime('%Y-%m-%d %H:%M')}",
        "",
        f"Python {platform.python_version()}, {platform.machine()}, "
        f"{__import__('os').cpu_count()} cores",
        "",
    ]
    for title, func in sections:
        print(f"== {title}", flush=True)
        rows = func()
        print("\n".join(rows), flush=True)
        lines += [f"## {title}", "", *rows, ""]
    out = HERE / "results" / "latest.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text("\n".join(lines))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
