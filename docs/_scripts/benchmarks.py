"""The benchmarks page: bench/results/latest.md, as the last ``make bench`` wrote it."""

from __future__ import annotations

import re

import mkdocs_gen_files
import runs

LATEST = runs.ROOT / "bench" / "results" / "latest.md"


def generate() -> None:
    text = LATEST.read_text(encoding="utf-8")
    title, _, body = text.partition("\n")
    when = re.sub(r"^#\s*graphvision benchmarks\s*[—-]?\s*", "", title).strip()
    lines = [
        "# Benchmarks",
        "",
        "`make bench` runs every module of `bench/` and writes `bench/results/latest.md`;",
        "this page is that file as it stands in the repository"
        + (f" (run of {when})." if when else "."),
        "Every row compares libraries in the same run on the same machine; ratios hold",
        "across machines better than absolute times do. One module alone:",
        "`python bench/bench_filters.py` (and so on); some sections only, rewritten in",
        "`latest.md` with the rest kept: `python bench/run_all.py \"issue 26\" studio`.",
        "Each section says when it ran and the machine's load average then.",
        "The rows against OpenCV's cascade classifier, HOG and `ximgproc` need",
        "opencv-contrib, which `make bench` installs in `.venv/opencv-contrib` (its `cv2`",
        "alone) and names in `GRAPHVISION_OPENCV_CONTRIB`; set that variable to re-run",
        "those sections by themselves.",
        "",
        body.strip(),
        "",
    ]
    with mkdocs_gen_files.open("benchmarks.md", "w") as out:
        out.write("\n".join(lines))
