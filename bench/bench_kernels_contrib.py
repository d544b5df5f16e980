"""Own kernels whose OpenCV counterparts left the main wheel, against opencv-contrib (issue 26).

OpenCV 5 moved the cascade classifier, the HOG descriptor and selective search (``ximgproc``)
into opencv-contrib, which cannot share an environment with opencv-python-headless. Install
it into a folder of its own and put that folder first on ``PYTHONPATH`` for this bench only::

    pip install --target /tmp/cv-contrib opencv-contrib-python-headless
    PYTHONPATH=/tmp/cv-contrib python bench/bench_kernels_contrib.py

``make bench`` runs it in a child process with that ``PYTHONPATH`` when
``GRAPHVISION_OPENCV_CONTRIB`` names the folder; without it, the section says so.

Both sides single-threaded (``cv2.setNumThreads(1)``, numba and BLAS one thread), the best
of at least 3 calls of each, the two called in turn after a warm-up (``bench/timing.py``),
by the process's CPU time (the ratio by wall time beside it), the machine's 1-minute load
beside each row. The calls compared, on the same pixels
(float32 in [0, 1] for graphvision, uint8 for OpenCV):

* LBP cascade on the astronaut (512², gray): ``recognition.lbp_detect`` with scikit-image's
  copy of ``lbpcascade_frontalface.xml`` against ``cv2.CascadeClassifier`` on the same file
  (its ``featuhreParams`` tag corrected), scale factor 1.1, 3 neighbours. OpenCV scans every
  second reduced pixel while the scale is at most 2 and every one above; graphvision's
  ``step`` 0 is that rule (the same work: the row to compare), step 1 every position (the
  node's default, about 2.6 times the windows) and step 2 every second one at every scale
  (fewer than OpenCV's). The faces each found are in the row.
* HOG of the camera (512²), 9 orientations, 8×8 cells, 3×3-cell blocks one cell apart:
  ``recognition.hog_features`` against ``cv2.HOGDescriptor((512, 512), (24, 24), (8, 8),
  (8, 8), 9).compute``.
* Selective search on the astronaut at 256²: ``detection.selective_search`` with the
  strategies of OpenCV's fast mode (HSV and Lab; k = 150 and 300; colour+texture+size+fill
  and texture+size+fill) against ``ximgproc``'s ``switchToSelectiveSearchFast(150, 150,
  0.8)``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import skimage.data
import skimage.transform
from bench_kernels_vs_opencv import _single_threaded
from timing import best_in_turn

Row = tuple[str, str, Callable[[], object], Callable[[], object]]
CONTRIB = "GRAPHVISION_OPENCV_CONTRIB"
"""Environment variable: a folder holding opencv-contrib-python-headless (``pip --target``)."""
_CHILD = "GRAPHVISION_CONTRIB_CHILD"  # set in the child run with that folder first on its path


def _in_child(folder: str) -> list[str]:
    """This bench's rows, run by a Python whose path starts with ``folder``."""
    paths = [folder, os.environ.get("PYTHONPATH", "")]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in paths if p), _CHILD: "1"}
    done = subprocess.run(
        [sys.executable, __file__], env=env, capture_output=True, text=True, check=False
    )
    return done.stdout.splitlines() or [f"the contrib bench failed: {done.stderr[-400:]}"]


RULE = {0: " (OpenCV's scan)"}


def _cascade_rows(cv2, folder: Path) -> list[Row]:
    from graphvision_plugins import recognition

    text = Path(skimage.data.lbp_frontal_face_cascade_filename()).read_text()
    corrected = folder / "lbpcascade_frontalface.xml"
    corrected.write_text(text.replace("featuhreParams", "featureParams"))
    theirs = cv2.CascadeClassifier(str(corrected))
    ours = recognition.lbp_cascade(name="skimage_frontal_face")
    gray = (skimage.data.astronaut().mean(axis=2) / 255).astype(np.float32)
    gray_u8 = np.round(gray * 255).astype(np.uint8)

    def opencv() -> object:
        return theirs.detectMultiScale(gray_u8, 1.1, 3)

    found = len(opencv())
    rows = []
    for step in (0, 1, 2):

        def graphvision(step: int = step) -> object:
            return recognition.lbp_detect(gray, ours, scale_factor=1.1, step=step, min_neighbours=3)

        kept = len(graphvision().xyxy)
        rows.append(
            (
                f"LBP cascade, step {step}{RULE.get(step, '')} ({kept} faces; OpenCV {found})",
                "`CascadeClassifier.detectMultiScale(u8, 1.1, 3)`",
                graphvision,
                opencv,
            )
        )
    return rows


def _hog_rows(cv2) -> list[Row]:
    from graphvision_plugins.recognition._hog import hog_features

    camera = (skimage.data.camera() / 255).astype(np.float32)
    camera_u8 = skimage.data.camera()
    descriptor = cv2.HOGDescriptor((512, 512), (24, 24), (8, 8), (8, 8), 9)
    return [
        (
            "HOG, 8×8 cells, 3×3 blocks (512²)",
            "`HOGDescriptor.compute(u8)`",
            lambda: hog_features(camera[None], 9, (8, 8), (3, 3)),
            lambda: descriptor.compute(camera_u8),
        )
    ]


def _selective_rows(cv2) -> list[Row]:
    from graphvision_plugins import detection

    image = skimage.transform.resize(skimage.data.astronaut(), (256, 256), anti_aliasing=True)
    rgb = image.astype(np.float32)
    bgr_u8 = np.round(image[:, :, ::-1] * 255).astype(np.uint8)

    def opencv() -> object:
        search = cv2.ximgproc.segmentation.createSelectiveSearchSegmentation()
        search.setBaseImage(bgr_u8)
        search.switchToSelectiveSearchFast(150, 150, 0.8)
        return search.process()

    return [
        (
            "selective search, fast mode (256²)",
            "`ximgproc` `switchToSelectiveSearchFast(150, 150, 0.8)`",
            lambda: detection.selective_search(rgb, scales=[150.0, 300.0]),
            opencv,
        )
    ]


def _row(kernel: str, call: str, ours: Callable[[], object], theirs) -> str:
    timed = best_in_turn(ours, theirs, 3)
    load = os.getloadavg()[0]
    return (
        f"| {kernel} | {timed.ours_cpu * 1e3:.1f} | {call} | {timed.theirs_cpu * 1e3:.1f} "
        f"| {timed.ours_cpu / timed.theirs_cpu:.2f} | {timed.ours_wall / timed.theirs_wall:.2f} "
        f"| {load:.1f} |"
    )


def main() -> list[str]:
    try:
        import cv2
    except ImportError:
        return ["OpenCV is not installed: the contrib kernel ratios are skipped"]
    header = [
        "| kernel | graphvision ms (CPU) | OpenCV call | OpenCV ms (CPU) "
        "| graphvision / OpenCV | by wall time | load (1 min) |",
        "| --- | ---: | --- | ---: | ---: | ---: | ---: |",
    ]
    if not (hasattr(cv2, "CascadeClassifier") and hasattr(cv2, "ximgproc")):
        folder = os.environ.get(CONTRIB)
        if folder and os.environ.get(_CHILD):  # the child's path did not give it either
            return [f"{folder} holds no opencv-contrib `cv2` (`make bench` installs it there)"]
        if folder:
            return _in_child(folder)
        return [
            f"OpenCV {cv2.__version__} here has no CascadeClassifier or ximgproc (OpenCV 5 "
            "moved them to opencv-contrib): run with PYTHONPATH to opencv-contrib-python-"
            "headless installed with `pip install --target` (see this module's docstring)"
        ]
    _single_threaded(cv2)
    rows = list(header)
    with tempfile.TemporaryDirectory() as folder:
        for kernel, call, ours, theirs in (
            _cascade_rows(cv2, Path(folder)) + _hog_rows(cv2) + _selective_rows(cv2)
        ):
            rows.append(_row(kernel, call, ours, theirs))
    rows.append("")
    rows.append(f"OpenCV {cv2.__version__} (contrib), single-threaded on both sides.")
    return rows


if __name__ == "__main__":
    print("\n".join(main()))
