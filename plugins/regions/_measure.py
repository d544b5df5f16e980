"""Region descriptors as a table, and filtering regions by descriptor ranges."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import GrayImage, Int, LabelImage, Table, node

__all__ = ["describe", "filter_regions", "perimeter_weights"]

SQRT2 = float(np.sqrt(2.0))
# weight of a boundary pixel by its code (1 + 2·#4-neighbours + 10·#diagonal
# neighbours that are boundary pixels of the same region), after Benkrid & Crookes
_WEIGHTS = np.zeros(50)
_WEIGHTS[[5, 7, 15, 17, 25, 27]] = 1.0
_WEIGHTS[[21, 33]] = SQRT2
_WEIGHTS[[13, 23]] = (1.0 + SQRT2) / 2.0


def perimeter_weights(labels: np.ndarray) -> np.ndarray:
    """Per-pixel perimeter contribution of every region's boundary pixels.

    A boundary pixel has a 4-neighbour outside its region (or the image).
    Its contribution depends on how the boundary runs through it: 1 along a
    straight run, √2 on a diagonal, (1 + √2) / 2 at a turn.
    """
    padded = np.pad(labels, 1)
    centre = padded[1:-1, 1:-1]
    inside = centre > 0
    boundary = np.zeros_like(padded, dtype=bool)
    interior = inside.copy()
    for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        interior &= (
            padded[1 + dy : padded.shape[0] - 1 + dy, 1 + dx : padded.shape[1] - 1 + dx] == centre
        )
    boundary[1:-1, 1:-1] = inside & ~interior
    code = boundary[1:-1, 1:-1].astype(np.int64)
    rows, cols = labels.shape
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dy == dx == 0:
                continue
            same = boundary[1 + dy : rows + 1 + dy, 1 + dx : cols + 1 + dx] & (
                padded[1 + dy : rows + 1 + dy, 1 + dx : cols + 1 + dx] == centre
            )
            code += same * (10 if dy and dx else 2)
    code[~boundary[1:-1, 1:-1]] = 0
    return _WEIGHTS[np.minimum(code, _WEIGHTS.size - 1)]


def _bounding_boxes(labels: np.ndarray, present: np.ndarray) -> np.ndarray:
    """Inclusive boxes ``(x_min, y_min, x_max, y_max)`` (K, 4) int64 of labels ``present``."""
    import scipy.ndimage as ndi

    boxes = ndi.find_objects(labels)
    box = np.array(
        [
            [b[1].start, b[0].start, b[1].stop - 1, b[0].stop - 1]
            for b in (boxes[i - 1] for i in present)
        ],
        dtype=np.int64,
    ).reshape(-1, 4)
    return box


@node("regions.describe", version=1)
def describe(labels: LabelImage, image: GrayImage | None = None) -> Table:
    r"""A table of descriptors, one row per region (label 1..N; absent labels are skipped).

    Columns (coordinates ``x`` = column, ``y`` = row, in pixels):

    * ``label``, ``area`` (pixel count);
    * ``perimeter``: boundary length, boundary pixels weighted by how the
      contour runs through them (1, √2 or (1 + √2)/2);
    * ``compactness`` :math:`P^2 / A` (4π for a disk) and
      ``circularity`` :math:`4 \pi A / P^2` (1 for a disk);
    * ``centroid_x``, ``centroid_y``: :math:`\bar x = m_{10} / m_{00}`,
      :math:`\bar y = m_{01} / m_{00}`;
    * ``x_min``, ``y_min``, ``x_max``, ``y_max`` (inclusive bounding box),
      ``extent`` (area / box area);
    * from the central second moments :math:`\mu_{20}, \mu_{02}, \mu_{11}` (per pixel):
      ``orientation``
      :math:`\theta = \frac{1}{2} \operatorname{atan2}(2\mu_{11}, \mu_{20} - \mu_{02})`,
      the major axis's angle from +x towards +y (down), in radians;
      ``major_axis`` and ``minor_axis`` :math:`4\sqrt{\lambda_{1,2}}` (the
      axes of the ellipse with the same second moments), ``eccentricity``
      :math:`\sqrt{1 - \lambda_2 / \lambda_1}`;
    * ``mean_intensity``, when ``image`` is connected.

    All columns come from one pass of ``bincount`` over the pixels.

    Parameters
    ----------
    labels : LabelImage
        Regions 1..N, 0 the background.
    image : GrayImage, optional
        When connected, adds the ``mean_intensity`` column.

    Returns
    -------
    table : dict of column name to 1-D ndarray

    References
    ----------
    .. [1] M.-K. Hu, "Visual pattern recognition by moment invariants", IRE
       Trans. Information Theory 8(2), 1962.
    .. [2] K. Benkrid, D. Crookes, "Design and FPGA implementation of a
       perimeter estimator", Proc. Irish Machine Vision and Image Processing
       Conference, 2000.
    """
    if image is not None and image.shape != labels.shape:
        raise ValueError(
            f"image and labels must have the same shape, got {image.shape} and {labels.shape}"
        )
    size = int(labels.max()) + 1
    flat = labels.ravel()
    ys, xs = np.indices(labels.shape, dtype=np.float64)

    def total(weights=None):
        return np.bincount(flat, weights=weights, minlength=size)

    count = total()
    present = np.flatnonzero(count)
    present = present[present > 0]
    area = count[present]
    sx, sy = total(xs.ravel())[present], total(ys.ravel())[present]
    cx, cy = sx / area, sy / area
    mu20 = total((xs * xs).ravel())[present] / area - cx * cx
    mu02 = total((ys * ys).ravel())[present] / area - cy * cy
    mu11 = total((xs * ys).ravel())[present] / area - cx * cy
    half_trace, spread = (mu20 + mu02) / 2, np.sqrt(((mu20 - mu02) / 2) ** 2 + mu11**2)
    major_var, minor_var = half_trace + spread, np.maximum(half_trace - spread, 0.0)
    perimeter = total(perimeter_weights(labels).ravel())[present]

    box = _bounding_boxes(labels, present)
    box_area = (box[:, 2] - box[:, 0] + 1) * (box[:, 3] - box[:, 1] + 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        eccentricity = np.where(major_var > 0, np.sqrt(1 - minor_var / major_var), 0.0)
        circularity = np.where(perimeter > 0, 4 * np.pi * area / perimeter**2, 0.0)
        compactness = np.where(area > 0, perimeter**2 / area, 0.0)
    table = {
        "label": present.astype(np.int32),
        "area": area.astype(np.int64),
        "perimeter": perimeter,
        "compactness": compactness,
        "circularity": circularity,
        "centroid_x": cx,
        "centroid_y": cy,
        "x_min": box[:, 0],
        "y_min": box[:, 1],
        "x_max": box[:, 2],
        "y_max": box[:, 3],
        "extent": area / box_area,
        "orientation": 0.5 * np.arctan2(2 * mu11, mu20 - mu02),
        "major_axis": 4 * np.sqrt(major_var),
        "minor_axis": 4 * np.sqrt(minor_var),
        "eccentricity": eccentricity,
    }
    if image is not None:
        table["mean_intensity"] = total(image.ravel().astype(np.float64))[present] / area
    return table


class Kept(NamedTuple):
    labels: LabelImage
    table: Table
    count: Int  # type: ignore[assignment]  # the port is named count in pipelines; hides tuple.count


Range = Annotated[list[float | None], Field(min_length=2, max_length=2)]


@node("regions.filter", version=1)
def filter_regions(
    labels: LabelImage,
    table: Table,
    *,
    ranges: dict[str, Range] = {"area": [1.0, None]},  # noqa: B006 - pydantic copies defaults
) -> Kept:
    """Keep the regions whose descriptors lie in the given ranges, renumbered 1..N.

    ``ranges`` maps a column of ``table`` to ``[low, high]`` (inclusive;
    ``null``/None leaves that side open), e.g. ``{area: [400, null],
    circularity: [0.8, null]}``. Kept regions are renumbered in their old
    order; the returned table has the new labels.

    Parameters
    ----------
    labels : LabelImage
        Regions 1..N.
    table : Table
        Their descriptors (``regions.describe``), one row per label.
    ranges : dict
        Column name → ``[low, high]``, inclusive, ``null`` for an open side.

    Returns
    -------
    labels : (H, W) int32 ndarray
    table : the kept rows
    count : int, the number of regions kept
    """
    if "label" not in table:
        raise ValueError("table has no 'label' column; connect the output of regions.describe")
    keep = np.ones(len(table["label"]), dtype=bool)
    for column, (low, high) in ranges.items():
        if column not in table:
            raise ValueError(
                f"unknown descriptor '{column}' in ranges; columns: {', '.join(table)}"
            )
        values = table[column]
        if low is not None:
            keep &= values >= low
        if high is not None:
            keep &= values <= high
    lookup = np.zeros(int(labels.max()) + 1, dtype=np.int32)
    kept_labels = table["label"][keep]
    lookup[kept_labels] = np.arange(1, kept_labels.size + 1, dtype=np.int32)
    rows = {name: column[keep] for name, column in table.items()}
    rows["label"] = np.arange(1, kept_labels.size + 1, dtype=np.int32)
    return Kept(lookup[labels], rows, int(kept_labels.size))
