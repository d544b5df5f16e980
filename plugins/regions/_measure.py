"""Region descriptors as a table, and filtering regions by descriptor ranges."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import GrayImage, Int, LabelImage, Table, node

__all__ = ["describe", "filter_regions"]


@node("regions.describe", version=1)
def describe(labels: LabelImage, image: GrayImage | None = None) -> Table:
    r"""A table of descriptors, one row per region (label 1..N; absent labels are skipped).

    Columns (coordinates ``x`` = column, ``y`` = row, in pixels):

    * ``label``, ``area`` (pixel count);
    * ``perimeter``: boundary length, boundary pixels weighted by how the
      contour runs through them (1, √2 or (1 + √2)/2) [2]_: a boundary pixel
      (one with a 4-neighbour outside its region or the image) has the code
      :math:`1 + 2 n_4 + 10 n_d`, :math:`n_4` and :math:`n_d` its 4- and
      diagonal neighbours that are boundary pixels of its region; codes 5, 7,
      15, 17, 25, 27 weigh 1, codes 21, 33 weigh √2, codes 13, 23 weigh
      (1 + √2)/2, the others 0;
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

    All columns come from one raster pass over the pixels (compiled with
    numba): per region the pixel count, the sums of :math:`x, y, x^2, y^2, xy`
    (:math:`m_{10}, m_{01}, m_{20}, m_{02}, m_{11}`), of the perimeter weights
    and of the intensities, and the box. Each sum adds its float64 terms in
    pixel order, as ``np.bincount`` with weights does, so the table is the
    one the former eight ``bincount`` passes gave, to the bit.

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
    from ._measure_kernels import SUMS, region_sums  # numba loads on first use

    pixels = None if image is None else np.ascontiguousarray(image)
    values, names = _compact(np.ascontiguousarray(labels))
    count, sums, box = region_sums(values, pixels, int(values.max()) + 1)
    present = np.flatnonzero(count)
    present = present[present > 0]
    area = count[present]
    total = dict(zip(SUMS, sums[:, present], strict=True))
    cx, cy = total["x"] / area, total["y"] / area
    mu20 = total["xx"] / area - cx * cx
    mu02 = total["yy"] / area - cy * cy
    mu11 = total["xy"] / area - cx * cy
    half_trace, spread = (mu20 + mu02) / 2, np.sqrt(((mu20 - mu02) / 2) ** 2 + mu11**2)
    major_var, minor_var = half_trace + spread, np.maximum(half_trace - spread, 0.0)
    perimeter = total["perimeter"]
    box = box[present]
    box_area = (box[:, 2] - box[:, 0] + 1) * (box[:, 3] - box[:, 1] + 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        eccentricity = np.where(major_var > 0, np.sqrt(1 - minor_var / major_var), 0.0)
        circularity = np.where(perimeter > 0, 4 * np.pi * area / perimeter**2, 0.0)
        compactness = np.where(area > 0, perimeter**2 / area, 0.0)
    table = {
        "label": (present if names is None else names[present]).astype(np.int32),
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
        table["mean_intensity"] = total["intensity"] / area
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


def _compact(labels: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """``labels`` as they are, or, when their largest value exceeds their pixel count (the
    kernel's per-label sums would be longer than the image: a label of 2·10⁸ on 50×50 took
    18 GB), their ranks among the values present with 0 kept for the background, and the
    values (rank -> label). Ranks keep the order and the equality of labels, so every sum
    is the same, added in the same pixel order."""
    if labels.size == 0 or int(labels.max()) < labels.size:
        return labels, None
    names = np.unique(labels)
    if names[0] != 0:
        names = np.concatenate((np.zeros(1, names.dtype), names))
    return np.searchsorted(names, labels).reshape(labels.shape), names
