"""numba kernels of growing a checkerboard's grid row by row (imported on first use).

A homography fitted to the grid's last rows predicts the next one
(:func:`grid_homography`, normalised DLT), each prediction takes the strongest candidate
near it (:func:`next_row`), the new corners must be X-junctions, point-symmetric in the
smoothed image (:func:`x_junctions`), and :func:`grow` turns the grid so that every side
is grown in turn. The steps are ``_corners._Grower``'s, compiled as one call.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit
from ._corner_kernels import bilinear

__all__ = ["grid_homography", "grow", "next_row", "x_junctions"]


@njit(cache=True, nogil=True)
def _normalising(points):  # pragma: no cover
    """Hartley's similarity (``geometry.normalising_transform``) as ``(scale, cx, cy)``."""
    n = points.shape[0]
    cx = cy = 0.0
    for i in range(n):
        cx += points[i, 0]
        cy += points[i, 1]
    cx /= n
    cy /= n
    total = 0.0
    for i in range(n):
        total += (points[i, 0] - cx) ** 2 + (points[i, 1] - cy) ** 2
    spread = np.sqrt(total / n)
    return (np.sqrt(2.0) / spread if spread > 0 else 1.0), cx, cy


@njit(cache=True, nogil=True)
def grid_homography(src, dst):  # pragma: no cover
    """Normalised DLT by the 9×9 normal equations (see ``_corners._grid_homography``):
    ``(True, H)`` with :math:`H_{33} = 1`, or ``(False, zeros)`` when degenerate."""
    s_scale, s_cx, s_cy = _normalising(src)
    d_scale, d_cx, d_cy = _normalising(dst)
    normal = np.zeros((9, 9))
    row = np.empty(9)
    for i in range(src.shape[0]):
        ax = s_scale * src[i, 0] - s_scale * s_cx
        ay = s_scale * src[i, 1] - s_scale * s_cy
        bx = d_scale * dst[i, 0] - d_scale * d_cx
        by = d_scale * dst[i, 1] - d_scale * d_cy
        for k in range(2):
            b = bx if k == 0 else by
            row[:] = 0.0
            row[3 * k] = -ax
            row[3 * k + 1] = -ay
            row[3 * k + 2] = -1.0
            row[6], row[7], row[8] = b * ax, b * ay, b
            for p in range(9):
                for q in range(9):
                    normal[p, q] += row[p] * row[q]
    values, vectors = np.linalg.eigh(normal)
    h = np.zeros((3, 3))
    if values[1] < 1e-12 * values[-1]:
        return False, h
    t_src = np.array([[s_scale, 0, -s_scale * s_cx], [0, s_scale, -s_scale * s_cy], [0, 0, 1.0]])
    t_dst = np.array([[d_scale, 0, -d_scale * d_cx], [0, d_scale, -d_scale * d_cy], [0, 0, 1.0]])
    h = np.linalg.inv(t_dst) @ np.ascontiguousarray(vectors[:, 0]).reshape(3, 3) @ t_src
    if abs(h[2, 2]) <= 1e-15:
        return False, h
    return True, h / h[2, 2]


@njit(cache=True, nogil=True)
def _strongest_near(candidates, x, y, radius):  # pragma: no cover
    """The first (strongest) candidate within ``radius`` of ``(x, y)``, or -1."""
    for i in range(candidates.shape[0]):
        dx = candidates[i, 0] - x
        dy = candidates[i, 1] - y
        if np.sqrt(dx * dx + dy * dy) <= radius:
            return i
    return -1


@njit(cache=True, nogil=True)
def x_junctions(smooth, points, radius, cos, sin, max_asymmetry):  # pragma: no cover
    """Every point is point-symmetric at its ``radius`` (``_corners._Photo.x_junctions``)."""
    for i in range(points.shape[0]):
        high = -np.inf
        low = np.inf
        worst = 0.0
        for a in range(cos.size):
            ox = radius[i] * cos[a]
            oy = radius[i] * sin[a]
            ahead = bilinear(smooth, points[i, 0] + ox, points[i, 1] + oy)
            behind = bilinear(smooth, points[i, 0] - ox, points[i, 1] - oy)
            high = max(high, ahead, behind)
            low = min(low, ahead, behind)
            worst = max(worst, abs(ahead - behind))
        if not worst <= max_asymmetry * max(high - low, 1e-9):
            return False
    return True


@njit(cache=True, nogil=True)
def next_row(candidates, grid, smooth, tolerance, cos, sin, max_asymmetry):  # pragma: no cover
    """The row after the last of ``grid`` (``_corners._Grower._next_row``): ``(True, fit,
    indices)`` or ``(False, 0, empty)``. A homography fitted to the last 3 rows predicts it,
    each prediction takes the strongest candidate within ``tolerance`` × its distance to
    the last row; the row must be distinct, new and of X-junctions."""
    height, width = grid.shape
    first = max(height - 3, 0)
    count = (height - first) * width
    src = np.empty((count, 2))
    dst = np.empty((count, 2))
    n = 0
    for j in range(first, height):
        for i in range(width):
            src[n, 0], src[n, 1] = i, j
            dst[n, 0], dst[n, 1] = candidates[grid[j, i], 0], candidates[grid[j, i], 1]
            n += 1
    none = np.empty(0, dtype=np.int64)
    ok, h = grid_homography(src, dst)
    if not ok:
        return False, 0.0, none
    index = np.empty(width, dtype=np.int64)
    spacing = np.empty(width)
    predicted = np.empty((width, 2))
    fit = 0.0
    for i in range(width):
        w = i * h[2, 0] + height * h[2, 1] + h[2, 2]
        px = (i * h[0, 0] + height * h[0, 1] + h[0, 2]) / w
        py = (i * h[1, 0] + height * h[1, 1] + h[1, 2]) / w
        if not (np.isfinite(px) and np.isfinite(py)):
            return False, 0.0, none
        last = candidates[grid[height - 1, i]]
        spacing[i] = np.sqrt((px - last[0]) ** 2 + (py - last[1]) ** 2)
        found = _strongest_near(candidates, px, py, tolerance * spacing[i])
        if found < 0:
            return False, 0.0, none
        for k in range(i):
            if index[k] == found:
                return False, 0.0, none
        if (grid == found).any():
            return False, 0.0, none
        index[i] = found
        predicted[i, 0], predicted[i, 1] = px, py
    points = np.empty((width, 2))
    for i in range(width):
        points[i] = candidates[index[i]]
        fit += np.sqrt(np.sum((points[i] - predicted[i]) ** 2)) / spacing[i]
    if not x_junctions(smooth, points, tolerance * spacing, cos, sin, max_asymmetry):
        return False, 0.0, none
    return True, fit / width, index


@njit(cache=True, nogil=True)
def _rot90(grid, turn):  # pragma: no cover
    """``np.rot90(grid, turn)`` for ``turn`` in 0 … 3, as a new array."""
    height, width = grid.shape
    if turn % 2 == 0:
        out = np.empty((height, width), dtype=grid.dtype)
    else:
        out = np.empty((width, height), dtype=grid.dtype)
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            if turn == 0:
                out[i, j] = grid[i, j]
            elif turn == 1:
                out[i, j] = grid[j, width - 1 - i]
            elif turn == 2:
                out[i, j] = grid[height - 1 - i, width - 1 - j]
            else:
                out[i, j] = grid[height - 1 - j, i]
    return out


@njit(cache=True, nogil=True)
def grow(
    candidates, grid, smooth, columns, rows, tolerance, cos, sin, max_asymmetry
):  # pragma: no cover
    """The grid of candidate indices grown from ``grid`` (``_corners._Grower._grow``): at
    each step, of the rows after the last of the grid turned by 0, 90, 180 and 270°
    (:func:`next_row`, where the grid plus that row still fits a ``columns × rows`` board
    either way round), the one that fits best (the first of equal fits) is added, until
    none is found."""
    while True:
        best_fit = np.inf
        best_turn = -1
        best_row = np.empty(0, dtype=np.int64)
        for turn in range(4):
            turned = _rot90(grid, turn)
            longer, across = turned.shape[0] + 1, turned.shape[1]
            fits = (longer <= rows and across <= columns) or (longer <= columns and across <= rows)
            if not fits:
                continue
            ok, fit, index = next_row(
                candidates, turned, smooth, tolerance, cos, sin, max_asymmetry
            )
            if ok and (best_turn < 0 or fit < best_fit):
                best_fit, best_turn, best_row = fit, turn, index
        if best_turn < 0:
            return grid
        turned = _rot90(grid, best_turn)
        longer = np.empty((turned.shape[0] + 1, turned.shape[1]), dtype=np.int64)
        longer[:-1] = turned
        longer[-1] = best_row
        grid = _rot90(longer, (4 - best_turn) % 4)
