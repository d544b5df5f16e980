"""Edges and Hough side by side with scikit-image and OpenCV, in one run.

* Canny on camera (512²): graphvision (σ = √1.5), ``skimage.feature.canny``
  (σ = 1; its Sobel adds variance 0.5) and ``cv2.Canny`` on the uint8 image
  blurred by ``cv2.GaussianBlur(σ = 1)`` with ``L2gradient=True``, each with
  the hysteresis thresholds at the 0.8 and 0.9 quantiles of its own gradient
  magnitude. F1 at 1-px tolerance against scikit-image and against OpenCV.
* Hough lines on ``sample:checkerboard`` and the board rotated by 20°
  (``skimage.transform.rotate``), from the same Canny edges: the count and
  the worst ρ error over the 14 interior lines. ``skimage.transform.hough_line``
  + ``hough_line_peaks`` (threshold 0.5 × max) and ``cv2.HoughLines(T=100)``.
* Hough circles on coins, radii 15–35: coins found (a circle within 5 px of a
  coin region of ``pipelines/coins.yaml``), false positives and the mean
  radius error against the regions' equivalent radius.
  ``skimage.transform.hough_circle`` + ``hough_circle_peaks`` (threshold
  0.35 × max, centres 15 px apart) on the same edges; ``cv2.HoughCircles``
  (HOUGH_GRADIENT, dp 1, minDist 30, param1 100, param2 25).

Times are the best of 5; ratios are the other library's time over
graphvision's (above 1: graphvision is faster). Run: ``python bench/bench_edges.py``.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import scipy.ndimage as ndi
import skimage.data
import skimage.feature
import skimage.transform
from timing import best

import graphvision as gv
from graphvision_plugins import edges, hough

PIPELINES = Path(__file__).parent.parent / "pipelines"
sys.path.insert(0, str(Path(__file__).parent.parent))


def f1_score(found: np.ndarray, truth: np.ndarray) -> float:
    near = np.ones((3, 3), dtype=bool)
    precision = (found & ndi.binary_dilation(truth, near)).sum() / max(found.sum(), 1)
    recall = (truth & ndi.binary_dilation(found, near)).sum() / max(truth.sum(), 1)
    return float(2 * precision * recall / max(precision + recall, 1e-12))


def _cv2():
    try:
        import cv2
    except ImportError:
        return None
    return cv2


def canny_rows(cv2) -> list[str]:
    raw = skimage.data.camera()
    image = (raw / 255).astype(np.float32)
    sigma = math.sqrt(1.5)
    ours = edges.canny(image, sigma=sigma, low=0.8, high=0.9, thresholds="quantile")
    reference = skimage.feature.canny(
        image, sigma=1.0, low_threshold=0.8, high_threshold=0.9, use_quantiles=True
    )
    t_ours = best(lambda: edges.canny(image, sigma=sigma, low=0.8, high=0.9, thresholds="quantile"))
    t_sk = best(
        lambda: skimage.feature.canny(
            image, sigma=1.0, low_threshold=0.8, high_threshold=0.9, use_quantiles=True
        )
    )
    rows = [
        "| Canny on camera | ms | ratio | edge pixels | F1 vs skimage (1 px) |",
        "| --- | ---: | ---: | ---: | ---: |",
        f"| graphvision | {t_ours * 1e3:.2f} | 1 | {ours.edges.sum()} "
        f"| {f1_score(ours.edges, reference):.3f} |",
        f"| skimage.feature.canny | {t_sk * 1e3:.2f} | {t_sk / t_ours:.2f} "
        f"| {reference.sum()} | 1 |",
    ]
    if cv2 is not None:
        blurred = cv2.GaussianBlur(raw, (0, 0), 1.0)
        # matched thresholds: the same quantiles (0.8, 0.9) of cv2's own Sobel magnitude
        sobel = np.hypot(cv2.Sobel(blurred, cv2.CV_32F, 1, 0), cv2.Sobel(blurred, cv2.CV_32F, 0, 1))
        lo, hi = (float(q) for q in np.quantile(sobel, [0.8, 0.9]))

        def run_cv():
            return cv2.Canny(cv2.GaussianBlur(raw, (0, 0), 1.0), lo, hi, L2gradient=True)

        found = cv2.Canny(blurred, lo, hi, L2gradient=True) > 0
        t_cv = best(run_cv)
        rows.append(
            f"| cv2.Canny | {t_cv * 1e3:.2f} | {t_cv / t_ours:.2f} | {found.sum()} "
            f"| {f1_score(found, reference):.3f} |"
        )
        rows.append(f"\nF1 graphvision vs cv2.Canny: {f1_score(ours.edges, found):.3f}")
    return rows


def board_truth(angle: float) -> np.ndarray:
    from tests.plugins.hough.test_hough import board_truth as truth

    return truth(angle)


def rho_error(lines: np.ndarray, truth: np.ndarray) -> float:
    """Worst ρ error over the true lines (nearest found line), inf if fewer are found."""
    if len(lines) < len(truth):
        return math.inf
    cost = np.abs(lines[:, None, 0] - truth[None, :, 0]) + 100 * np.abs(
        lines[:, None, 1] - truth[None, :, 1]
    )
    nearest = cost.argmin(axis=0)
    return float(np.abs(lines[nearest, 0] - truth[:, 0]).max())


def lines_rows(cv2) -> list[str]:
    rows = [
        "| Hough lines | board | ms | ratio | lines (truth 14) | worst ρ error px |",
        "| --- | --- | ---: | ---: | ---: | ---: |",
    ]
    board = (skimage.data.checkerboard() / 255).astype(np.float32)
    for angle in (0.0, 20.0):
        image = skimage.transform.rotate(board, angle, order=1).astype(np.float32)
        found = edges.canny(image, sigma=1.0).edges
        truth = board_truth(angle)
        ours = hough.hough_lines(found, image)
        t_ours = best(lambda image=image, found=found: hough.hough_lines(found, image))
        rows.append(
            f"| graphvision | {angle:g}° | {t_ours * 1e3:.2f} | 1 | {ours.count} "
            f"| {rho_error(ours.lines, truth):.2f} |"
        )

        def run_sk(found=found):
            h, theta, dist = skimage.transform.hough_line(found)
            return skimage.transform.hough_line_peaks(h, theta, dist, threshold=0.5 * h.max())

        _, theta, dist = run_sk()
        # skimage: θ in [-π/2, π/2); bring to [0, π) with ρ negated
        flip = theta < 0
        sk_lines = np.column_stack(
            [np.where(flip, -dist, dist), np.where(flip, theta + math.pi, theta), theta]
        )
        t_sk = best(run_sk)
        rows.append(
            f"| skimage hough_line | {angle:g}° | {t_sk * 1e3:.2f} | {t_sk / t_ours:.2f} "
            f"| {len(sk_lines)} | {rho_error(sk_lines, truth):.2f} |"
        )
        if cv2 is not None:
            mask = found.astype(np.uint8) * 255

            def run_cv(mask=mask):
                return cv2.HoughLines(mask, 1, math.pi / 180, 100)

            result = run_cv()
            cv_lines = np.zeros((0, 3)) if result is None else result[:, 0, :]
            cv_lines = np.column_stack([cv_lines[:, :2], np.zeros(len(cv_lines))])
            t_cv = best(run_cv)
            rows.append(
                f"| cv2.HoughLines T=100 | {angle:g}° | {t_cv * 1e3:.2f} | {t_cv / t_ours:.2f} "
                f"| {len(cv_lines)} | {rho_error(cv_lines, truth):.2f} |"
            )
    return rows


def score_circles(circles: np.ndarray, centroids: np.ndarray, radius: np.ndarray) -> str:
    if len(circles) == 0:
        return "0 | 0 | n/a"
    gaps = np.linalg.norm(circles[:, None, :2] - centroids[None], axis=2)
    nearest = gaps.argmin(axis=1)
    hit = gaps.min(axis=1) < 5
    coins = len(set(nearest[hit].tolist()))
    false = int((~hit).sum()) + int(hit.sum()) - coins
    error = np.abs(circles[hit, 2] - radius[nearest[hit]]).mean()
    return f"{coins} | {false} | {error:.2f}"


def circles_rows(cv2) -> list[str]:
    regions = gv.run(gv.load_pipeline(PIPELINES / "coins.yaml")).outputs["regions"]
    centroids = np.column_stack([regions["centroid_x"], regions["centroid_y"]])
    radius = np.sqrt(regions["area"] / math.pi)
    raw = skimage.data.coins()
    image = (raw / 255).astype(np.float32)
    found = edges.canny(image, sigma=1.5, low=0.04, high=0.08).edges
    params = {"min_radius": 15, "max_radius": 35, "sigma": 1.5, "threshold": 0.17}
    ours = hough.hough_circles(found, image, **params)
    t_ours = best(lambda: hough.hough_circles(found, image, **params))
    rows = [
        "| Hough circles on coins | ms | ratio | coins (of 24) | false | mean radius error px |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
        f"| graphvision | {t_ours * 1e3:.1f} | 1 "
        f"| {score_circles(ours.circles, centroids, radius)} |",
    ]
    radii = np.arange(15, 36)

    def run_sk():
        h = skimage.transform.hough_circle(found, radii)
        return skimage.transform.hough_circle_peaks(
            h, radii, min_xdistance=15, min_ydistance=15, threshold=0.35 * h.max()
        )

    _, cx, cy, r = run_sk()
    t_sk = best(run_sk, repeats=2)
    sk = np.column_stack([cx, cy, r, np.zeros(len(r))]).astype(np.float64)
    rows.append(
        f"| skimage hough_circle | {t_sk * 1e3:.1f} | {t_sk / t_ours:.2f} "
        f"| {score_circles(sk, centroids, radius)} |"
    )
    if cv2 is not None:

        def run_cv():
            return cv2.HoughCircles(
                raw, cv2.HOUGH_GRADIENT, 1, 30, param1=100, param2=25, minRadius=15, maxRadius=35
            )

        result = run_cv()
        cv = np.zeros((0, 4)) if result is None else result[0]
        cv = np.column_stack([cv[:, :3], np.zeros(len(cv))]).astype(np.float64)
        t_cv = best(run_cv)
        rows.append(
            f"| cv2.HoughCircles | {t_cv * 1e3:.1f} | {t_cv / t_ours:.2f} "
            f"| {score_circles(cv, centroids, radius)} |"
        )
    return rows


def main() -> list[str]:
    cv2 = _cv2()
    rows = [*canny_rows(cv2), "", *lines_rows(cv2), "", *circles_rows(cv2)]
    if cv2 is None:
        rows.append("\nOpenCV is not installed (pip install -e '.[bench]'): its rows are missing.")
    return rows


if __name__ == "__main__":
    print("\n".join(main()))
