"""Filters side by side: graphvision, scipy.ndimage, scikit-image and OpenCV, one run.

Same float32 gray images (``skimage.data.camera`` at 512², tiled to 2048²),
same filter settings (graphvision's Sobel is scipy's and OpenCV's divided by
8, the same work); the best of 5 runs each. Ratios are the other
library's time over graphvision's (above 1: graphvision is faster). Each
library's call is written in the table's ``call`` column.

Run: ``python bench/bench_filters.py`` (OpenCV from the ``bench`` extra).
"""

from __future__ import annotations

import numpy as np
import scipy.ndimage as ndi
import skimage.data
import skimage.filters
from timing import best

from graphvision_plugins import edges, filters


def cases(image: np.ndarray, cv2):
    kernel = np.random.default_rng(0).random((5, 5))
    kernel /= kernel.sum()
    sigma = 2.0
    radius = int(np.ceil(3 * sigma))
    image_u8 = np.round(image * 255).astype(np.uint8)
    yield (
        "gaussian σ=2",
        lambda: filters.gaussian(image, sigma=sigma),
        {
            "scipy.ndimage.gaussian_filter(truncate=3)": lambda: ndi.gaussian_filter(
                image, sigma, mode="reflect", truncate=3.0
            ),
            "skimage.filters.gaussian(truncate=3)": lambda: skimage.filters.gaussian(
                image, sigma=sigma, mode="reflect", truncate=3.0
            ),
            "cv2.GaussianBlur(ksize=13)": cv2
            and (
                lambda: cv2.GaussianBlur(
                    image, (2 * radius + 1, 2 * radius + 1), sigma, borderType=cv2.BORDER_REFLECT
                )
            ),
        },
    )
    yield (
        "Sobel ∂/∂x (÷8)",
        lambda: edges.derivative(image, axis="x", kind="sobel"),
        {
            "scipy.ndimage.sobel(axis=1)": lambda: ndi.sobel(image, axis=1, mode="reflect"),
            "cv2.Sobel(CV_32F, 1, 0)": cv2
            and (
                lambda: cv2.Sobel(image, cv2.CV_32F, 1, 0, ksize=3, borderType=cv2.BORDER_REFLECT)
            ),
        },
    )
    yield (
        "box 5×5",
        lambda: filters.box(image, size=5),
        {
            "scipy.ndimage.uniform_filter": lambda: ndi.uniform_filter(image, 5, mode="reflect"),
            "cv2.blur": cv2 and (lambda: cv2.blur(image, (5, 5), borderType=cv2.BORDER_REFLECT)),
        },
    )
    yield (
        "correlate 5×5",
        lambda: filters.correlate(image, kernel),
        {
            "scipy.ndimage.correlate": lambda: ndi.correlate(
                image, kernel.astype(np.float32), mode="reflect"
            ),
            "cv2.filter2D": cv2
            and (
                lambda: cv2.filter2D(
                    image, -1, kernel.astype(np.float32), borderType=cv2.BORDER_REFLECT
                )
            ),
        },
    )
    for size in (3, 5, 7):
        opencv = "cv2.medianBlur " + ("(float32)" if size <= 5 else "(uint8: float32 stops at 5)")
        yield (
            f"median {size}×{size}",
            lambda s=size: filters.median(image, size=s),
            {
                "scipy.ndimage.median_filter": lambda s=size: ndi.median_filter(
                    image, s, mode="reflect"
                ),
                "skimage.filters.median (uint8)": lambda s=size: skimage.filters.median(
                    image_u8, np.ones((s, s), bool)
                ),
                opencv: cv2 and (lambda s=size: cv2.medianBlur(image if s <= 5 else image_u8, s)),
            },
        )


def main() -> list[str]:
    try:
        import cv2

        cv2.setNumThreads(1)
    except ImportError:
        cv2 = None
    base = (skimage.data.camera() / 255.0).astype(np.float32)
    rows = [
        "| filter | size | graphvision ms | reference | call | ref ms | ref / graphvision |",
        "| --- | --- | ---: | --- | --- | ---: | ---: |",
    ]
    for side in (512, 2048):
        image = np.tile(base, (side // 512, side // 512))
        for name, ours, references in cases(image, cv2):
            own = best(ours)
            for label, call in references.items():
                if call is None:
                    continue
                library = label.split(".")[0]
                theirs = best(call)
                rows.append(
                    f"| {name} | {side}² | {own * 1e3:.1f} | {library} | `{label}` | "
                    f"{theirs * 1e3:.1f} | {theirs / own:.2f} |"
                )
    if cv2 is None:
        rows.append("\nOpenCV not installed: `pip install -e .[bench]` adds it.")
    return rows


if __name__ == "__main__":
    print("\n".join(main()))
