"""Segmentation side by side: thresholds, morphology, labelling, region descriptors.

* Otsu's threshold on camera, coins and page: graphvision, ``skimage.filters.
  threshold_otsu`` and ``cv2.threshold(..., THRESH_OTSU)`` on the uint8 image
  (OpenCV returns a gray level; shown divided by 255).
* Times, best of 5, on float32/bool images of 512² and 2048² (camera, tiled):
  local threshold (Sauvola, 25×25), binary erosion with a 7×7 disk and a 7×7
  square and region descriptors. Ratios are the other library's time over
  graphvision's (above 1: graphvision is faster).
* Labelling, 4- and 8-connected, on camera's Otsu mask and two noisy 2048²
  masks (uniform noise at p = 0.5, Gaussian noise smoothed with σ = 2 and
  thresholded at 0), against ``scipy.ndimage.label``, ``skimage.measure.label``
  and ``cv2.connectedComponents``.

Run: ``python bench/bench_segmentation.py``.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.ndimage as ndi
import skimage.data
import skimage.filters
import skimage.measure
import skimage.morphology
from timing import best

from graphvision_plugins import morphology, regions, threshold


def otsu_rows(cv2) -> list[str]:
    rows = [
        "| image | graphvision | skimage.filters.threshold_otsu | cv2.threshold OTSU / 255 |",
        "| --- | ---: | ---: | ---: |",
    ]
    for name in ("camera", "coins", "page"):
        raw = getattr(skimage.data, name)()
        image = (raw / 255.0).astype(np.float32)
        ours = threshold.otsu(image).threshold
        theirs = float(skimage.filters.threshold_otsu(image))
        cv = (
            cv2.threshold(raw, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)[0] / 255
            if cv2
            else None
        )
        rows.append(
            f"| {name} | {ours:.5f} | {theirs:.5f} | {'n/a' if cv is None else f'{cv:.5f}'} |"
        )
    rows.append("")
    rows.append(
        "One bin of 256 over [min, max] is about 0.004 wide; OpenCV thresholds at an "
        "integer level (pixels > T are foreground), so it may sit half a level apart."
    )
    return rows


def timing_rows(cv2) -> list[str]:
    base = (skimage.data.camera() / 255.0).astype(np.float32)
    disk = morphology.footprint(shape="disk", size=7)
    square = morphology.footprint(shape="square", size=7)
    rows = [
        "| operation | size | graphvision ms | reference | ref ms | ref / graphvision |",
        "| --- | --- | ---: | --- | ---: | ---: |",
    ]
    for side in (512, 2048):
        image = np.tile(base, (side // 512, side // 512))
        mask = image > threshold.otsu(image).threshold
        labels = regions.label(mask)
        mask_u8 = mask.astype(np.uint8)
        cases = [
            (
                "Sauvola 25×25",
                lambda i=image: threshold.local(i, window=25, k=0.2, method="sauvola"),
                {
                    "skimage.filters.threshold_sauvola": lambda i=image: (
                        i < skimage.filters.threshold_sauvola(i, 25, k=0.2, r=0.5)
                    ),
                    "cv2.adaptiveThreshold (mean, uint8)": cv2
                    and (
                        lambda i=image: cv2.adaptiveThreshold(
                            (i * 255).astype(np.uint8),
                            255,
                            cv2.ADAPTIVE_THRESH_MEAN_C,
                            cv2.THRESH_BINARY,
                            25,
                            0,
                        )
                    ),
                },
            ),
            (
                "erosion, 7×7 disk",
                lambda m=mask: morphology.erode(m, disk),
                {
                    "skimage.morphology.binary_erosion": lambda m=mask: (
                        skimage.morphology.binary_erosion(m, disk)
                    ),
                    "scipy.ndimage.binary_erosion": lambda m=mask: ndi.binary_erosion(
                        m, disk, border_value=1
                    ),
                    "cv2.erode": cv2 and (lambda m=mask_u8: cv2.erode(m, disk.astype(np.uint8))),
                },
            ),
            (
                "erosion, 7×7 square",
                lambda m=mask: morphology.erode(m, square),
                {
                    "skimage.morphology.binary_erosion": lambda m=mask: (
                        skimage.morphology.binary_erosion(m, square)
                    ),
                    "scipy.ndimage.binary_erosion": lambda m=mask: ndi.binary_erosion(
                        m, square, border_value=1
                    ),
                    "cv2.erode": cv2 and (lambda m=mask_u8: cv2.erode(m, square.astype(np.uint8))),
                },
            ),
            (
                "region descriptors",
                lambda lab=labels, i=image: regions.describe(lab, i),
                {
                    "skimage.measure.regionprops_table": lambda lab=labels, i=image: (
                        skimage.measure.regionprops_table(
                            lab,
                            i,
                            properties=(
                                "label",
                                "area",
                                "perimeter",
                                "centroid",
                                "bbox",
                                "orientation",
                                "axis_major_length",
                                "axis_minor_length",
                                "eccentricity",
                                "extent",
                                "intensity_mean",
                            ),
                        )
                    ),
                    "cv2.connectedComponentsWithStats (area, bbox, centroid only)": cv2
                    and (lambda m=mask_u8: cv2.connectedComponentsWithStats(m, connectivity=8)),
                },
            ),
        ]
        for name, ours, references in cases:
            own = best(ours)
            for label, call in references.items():
                if not call:
                    continue
                theirs = best(call)
                rows.append(
                    f"| {name} | {side}² | {own * 1e3:.1f} | `{label}` | "
                    f"{theirs * 1e3:.1f} | {theirs / own:.2f} |"
                )
    return rows


def labelling_masks() -> dict[str, np.ndarray]:
    """Masks to label: camera's Otsu mask (few large regions) and two noisy ones (seed 0)."""
    base = (skimage.data.camera() / 255.0).astype(np.float32)
    rng = np.random.default_rng(0)
    masks = {}
    for side in (512, 2048):
        image = np.tile(base, (side // 512, side // 512))
        masks[f"camera > Otsu, {side}²"] = image > threshold.otsu(image).threshold
    masks["random, p = 0.5, 2048²"] = rng.random((2048, 2048)) < 0.5
    masks["noise smoothed (σ = 2) > 0, 2048²"] = (
        ndi.gaussian_filter(rng.standard_normal((2048, 2048)), 2.0) > 0
    )
    return masks


def labelling_rows(cv2) -> list[str]:
    """4- and 8-connected labelling against scipy, scikit-image and OpenCV (same partition)."""
    rows = [
        "| mask | connectivity | regions | graphvision ms | scipy.ndimage.label | "
        "skimage.measure.label | cv2.connectedComponents |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for name, mask in labelling_masks().items():
        mask_u8 = mask.view(np.uint8)
        for connectivity in (4, 8):
            structure = np.ones((3, 3)) if connectivity == 8 else None
            ours = regions.label(mask, connectivity=connectivity)
            reference, count = ndi.label(mask, structure=structure)
            if not np.array_equal(ours, reference):
                raise RuntimeError(f"labels differ from scipy.ndimage.label on {name}")
            own = best(lambda m=mask, c=connectivity: regions.label(m, connectivity=c))
            calls = [
                lambda m=mask, st=structure: ndi.label(m, structure=st),
                lambda m=mask, c=connectivity: skimage.measure.label(m, connectivity=c // 4),
                cv2
                and (lambda m=mask_u8, c=connectivity: cv2.connectedComponents(m, connectivity=c)),
            ]
            cells = []
            for call in calls:
                theirs = best(call) if call else None
                cells.append(
                    "n/a" if theirs is None else f"{theirs * 1e3:.1f} ({theirs / own:.2f}×)"
                )
            rows.append(
                f"| {name} | {connectivity} | {count} | {own * 1e3:.1f} | "
                + " | ".join(cells)
                + " |"
            )
    rows.append("")
    rows.append(
        "In brackets: the library's time over graphvision's (above 1: graphvision is faster). "
        "Labels are checked equal to scipy's (raster order) before timing."
    )
    return rows


def main() -> list[str]:
    warnings.filterwarnings("ignore", category=FutureWarning)  # skimage's binary_erosion
    try:
        import cv2

        cv2.setNumThreads(1)
    except ImportError:
        cv2 = None
    return [
        "### Otsu thresholds",
        "",
        *otsu_rows(cv2),
        "",
        "### Times",
        "",
        *timing_rows(cv2),
        "",
        "### Labelling",
        "",
        *labelling_rows(cv2),
    ]


if __name__ == "__main__":
    print("\n".join(main()))
