"""numba kernel of the region descriptors' sums (imported on first use: numba loads slowly).

One raster pass over the label image gathers, per label, what ``np.bincount``
gathered in eight passes and ``scipy.ndimage.find_objects`` in a ninth: the
pixel count, the sums of x, y, x², y², xy, of the perimeter weights and of the
intensities, and the bounding box. Each sum adds its float64 terms in pixel
order, one term at a time, as ``bincount`` does, so the sums are the same to
the bit (a term that is 0 is skipped, a background pixel's, or the perimeter
weight of a pixel off the boundary: adding +0.0 to a sum that started at +0.0
leaves it unchanged).

The perimeter weights follow Benkrid & Crookes: a boundary pixel (one with a
4-neighbour outside its region or the image) has the code 1 + 2·(its
4-neighbours) + 10·(its diagonal neighbours) that are boundary pixels of the
same region, and weighs ``WEIGHTS[code]``. Whether a pixel is on the boundary
is kept for three rows at a time (the row above, this one and the one below).
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["SUMS", "WEIGHTS", "region_sums"]

SQRT2 = float(np.sqrt(2.0))
# weight of a boundary pixel by its code (1 + 2·#4-neighbours + 10·#diagonal
# neighbours that are boundary pixels of the same region), after Benkrid & Crookes;
# a boundary pixel has at most three 4-neighbours in its region: codes stop at 47
WEIGHTS = np.zeros(50)
WEIGHTS[[5, 7, 15, 17, 25, 27]] = 1.0
WEIGHTS[[21, 33]] = SQRT2
WEIGHTS[[13, 23]] = (1.0 + SQRT2) / 2.0

# the columns of region_sums's float64 sums, in order
SUMS = ("x", "y", "xx", "yy", "xy", "perimeter", "intensity")


@njit(cache=True, nogil=True)
def _boundary_flag(labels, y, x, up, down, edge_row):  # pragma: no cover
    """Whether pixel (y, x) is a boundary pixel, at any place in the image (rows ``up``,
    ``down``: y - 1, y + 1 clamped to the image; ``edge_row``: y is the first or last)."""
    cols = labels.shape[1]
    lab = labels[y, x]
    left, right = labels[y, max(x - 1, 0)], labels[y, min(x + 1, cols - 1)]
    outside = edge_row | (x == 0) | (x == cols - 1)
    differs = (left != lab) | (right != lab) | (labels[up, x] != lab) | (labels[down, x] != lab)
    return (lab != 0) & (outside | differs)


@njit(cache=True, nogil=True)
def _boundary_row(labels, y, edge):  # pragma: no cover
    """``edge[1 + x]`` ← 1 where pixel (y, x) is a boundary pixel, else 0. Inside the
    image, bitwise operators rather than ``or``: no branch for the flags of a noisy row."""
    rows, cols = labels.shape
    up, down = max(y - 1, 0), min(y + 1, rows - 1)
    edge_row = y == 0 or y == rows - 1
    edge[1] = _boundary_flag(labels, y, 0, up, down, edge_row)
    if edge_row:
        for x in range(1, cols):
            edge[1 + x] = labels[y, x] != 0
    else:
        for x in range(1, cols - 1):
            lab = labels[y, x]
            differs = (labels[y, x - 1] != lab) | (labels[y, x + 1] != lab)
            differs |= (labels[up, x] != lab) | (labels[down, x] != lab)
            edge[1 + x] = (lab != 0) & differs
        edge[cols] = _boundary_flag(labels, y, cols - 1, up, down, edge_row)


@njit(cache=True, nogil=True)
def _perimeter_weight(labels, y, x, above, here, below):  # pragma: no cover
    """The weight of boundary pixel (y, x); ``above``, ``here``, ``below``: the boundary
    flags of rows y - 1, y, y + 1 (0 outside the image), column x at index x + 1. A
    neighbour outside the image has the flag 0: the label read in its place (the
    indices clamped to the image) adds nothing."""
    rows, cols = labels.shape
    lab = labels[y, x]
    up, down = max(y - 1, 0), min(y + 1, rows - 1)
    left, right = max(x - 1, 0), min(x + 1, cols - 1)
    code = 1 + 2 * ((here[x] != 0) & (labels[y, left] == lab))
    code += 2 * ((here[x + 2] != 0) & (labels[y, right] == lab))
    code += 10 * ((above[x] != 0) & (labels[up, left] == lab))
    code += 2 * ((above[x + 1] != 0) & (labels[up, x] == lab))
    code += 10 * ((above[x + 2] != 0) & (labels[up, right] == lab))
    code += 10 * ((below[x] != 0) & (labels[down, left] == lab))
    code += 2 * ((below[x + 1] != 0) & (labels[down, x] == lab))
    code += 10 * ((below[x + 2] != 0) & (labels[down, right] == lab))
    return WEIGHTS[code]


@njit(cache=True, nogil=True)
def _add_run(labels, image, y, start, end, edges, sums, count, box):  # pragma: no cover
    """Add the run ``labels[y, start:end]`` (one label) to its label's sums, pixel by pixel."""
    lab = labels[y, start]
    above, here, below = edges[y % 3], edges[(y + 1) % 3], edges[(y + 2) % 3]
    fy = float(y)
    sx, sy, sxx, syy, sxy = sums[0, lab], sums[1, lab], sums[2, lab], sums[3, lab], sums[4, lab]
    perimeter, intensity = sums[5, lab], sums[6, lab]
    for x in range(start, end):
        fx = float(x)
        sx += fx
        sy += fy
        sxx += fx * fx
        syy += fy * fy
        sxy += fx * fy
        if here[x + 1]:
            perimeter += _perimeter_weight(labels, y, x, above, here, below)
        if image is not None:
            intensity += float(image[y, x])
    sums[0, lab], sums[1, lab], sums[2, lab], sums[3, lab], sums[4, lab] = sx, sy, sxx, syy, sxy
    sums[5, lab], sums[6, lab] = perimeter, intensity
    if count[lab] == 0:
        box[lab, 0], box[lab, 1], box[lab, 2] = start, y, end - 1
    box[lab, 0] = min(box[lab, 0], start)
    box[lab, 2] = max(box[lab, 2], end - 1)
    box[lab, 3] = y
    count[lab] += end - start


@njit(cache=True, nogil=True)
def region_sums(labels, image, size):  # pragma: no cover
    """Per label 0..size-1 of ``labels`` (C-contiguous, values < size): the pixel count
    (int64), the float64 sums named by ``SUMS`` (7, size) (the intensities of ``image``
    when it is not None, else 0), the inclusive box ``(x_min, y_min, x_max, y_max)``
    (size, 4) int64. Label 0 (the background) is left at zero."""
    rows, cols = labels.shape
    count = np.zeros(size, np.int64)
    sums = np.zeros((7, size), np.float64)
    box = np.zeros((size, 4), np.int64)
    # the boundary flags of row r at edges[(r + 1) % 3], padded by a 0 on each side
    edges = np.zeros((3, cols + 2), np.uint8)
    if rows > 0:
        _boundary_row(labels, 0, edges[1])
    for y in range(rows):
        below = edges[(y + 2) % 3]
        if y + 1 < rows:
            _boundary_row(labels, y + 1, below)
        else:
            below[:] = 0
        start = 0
        while start < cols:
            lab = labels[y, start]
            end = start + 1
            while end < cols and labels[y, end] == lab:
                end += 1
            if lab != 0:
                _add_run(labels, image, y, start, end, edges, sums, count, box)
            start = end
    return count, sums, box
