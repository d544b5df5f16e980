"""numba kernels of Förstner's sub-pixel corner iteration for all corners of a board
(imported on first use), without the ``corners × window`` temporaries of the array form.

The gradient is ``np.gradient``'s and each sample :func:`._corner_kernels.bilinear`'s; a
window inside the image sums its rows in vectorised (reassociated) loops, so a refined
corner differs from the sample-by-sample iteration by rounding (about 1e-12 px; the test
bound is 1e-9 px), a window crossing the border sums sample by sample, in order.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit
from ._corner_kernels import _dx, _dy

__all__ = ["forstner"]


@njit(cache=True, nogil=True)
def _axis_samples(q, half, length, first, second, weight, inside):  # pragma: no cover
    """For the ``2 half + 1`` positions ``q + o`` (o = −half … half) along one axis of
    ``length`` pixels, what :func:`bilinear` derives from each: the lower and upper pixel
    (``first``, ``second``), the weight of the upper one and whether it lies inside
    ``[0, length - 1]``, computed as :func:`bilinear` computes them."""
    for c in range(2 * half + 1):
        p = q + float(c - half)
        inside[c] = 0.0 <= p <= length - 1
        lower = min(int(np.floor(p)), length - 1) if inside[c] else 0
        first[c] = lower
        second[c] = min(lower + 1, length - 1)
        weight[c] = p - lower


@njit(cache=True, nogil=True)
def _forstner_sums(smooth, qx, qy, half, weight, columns, rows):  # pragma: no cover
    """Förstner's normal equations ``(axx, axy, ayy, bx, by)`` of one corner at
    ``(qx, qy)``: the window's samples in row-major order, each as :func:`bilinear` gives
    it at ``q + offset`` from :func:`gradient` of ``smooth`` (its values computed where
    read; ``columns`` and ``rows`` hold :func:`_axis_samples` of each axis)."""
    x0, x1, wxs, xin = columns
    y0, y1, wys, yin = rows
    side = 2 * half + 1
    axx = axy = ayy = bx = by = 0.0
    for r in range(side):
        py = qy + float(r - half)
        wy, top, bottom = wys[r], y0[r], y1[r]
        for c in range(side):
            w = weight[r * side + c]
            if w == 0.0:
                continue
            px = qx + float(c - half)
            sx = sy = 0.0
            if yin[r] and xin[c]:
                wx, left, right = wxs[c], x0[c], x1[c]
                upper = (1.0 - wx) * _dx(smooth, top, left) + wx * _dx(smooth, top, right)
                lower = (1.0 - wx) * _dx(smooth, bottom, left) + wx * _dx(smooth, bottom, right)
                sx = (1.0 - wy) * upper + wy * lower
                upper = (1.0 - wx) * _dy(smooth, top, left) + wx * _dy(smooth, top, right)
                lower = (1.0 - wx) * _dy(smooth, bottom, left) + wx * _dy(smooth, bottom, right)
                sy = (1.0 - wy) * upper + wy * lower
            axx += w * sx * sx
            axy += w * sx * sy
            ayy += w * sy * sy
            bx += w * (sx * sx * px + sx * sy * py)
            by += w * (sx * sy * px + sy * sy * py)
    return axx, axy, ayy, bx, by


@njit(cache=True, nogil=True, fastmath=True)
def _forstner_sums_inside(smooth, qx, qy, half, weight, across, down):  # pragma: no cover
    """:func:`_forstner_sums` of a window whose samples, their right and lower pixels and
    those pixels' neighbours all lie inside the image: every sample has the same weights
    (``q`` minus its floor) and every gradient is a central difference. The gradient is
    first interpolated along x once per pixel row of the window (its ``2 half + 2`` rows
    into ``across`` (d/dx) and ``down`` (d/dy)), then each sample interpolates those rows
    along y; every loop is vectorised over consecutive pixels (sums reassociated: the
    result differs from the sample-by-sample sums by rounding)."""
    fx, fy = np.floor(qx), np.floor(qy)
    wx, wy = qx - fx, qy - fy
    left, top = int(fx) - half, int(fy) - half
    side = 2 * half + 1
    for r in range(side + 1):  # pixel row top + r, its pixels left + c and left + c + 1
        row = smooth[top + r, left - 1 :]  # pixel left + c is element c + 1
        above, below = smooth[top + r - 1, left:], smooth[top + r + 1, left:]
        gx, gy = across[r], down[r]
        for c in range(side):
            x0 = (row[c + 2] - row[c]) / 2.0
            x1 = (row[c + 3] - row[c + 1]) / 2.0
            y0 = (below[c] - above[c]) / 2.0
            y1 = (below[c + 1] - above[c + 1]) / 2.0
            gx[c] = (1.0 - wx) * x0 + wx * x1
            gy[c] = (1.0 - wx) * y0 + wx * y1
    axx = axy = ayy = bx = by = 0.0
    for r in range(side):
        py = qy + float(r - half)
        x_upper, x_lower, y_upper, y_lower = across[r], across[r + 1], down[r], down[r + 1]
        w_row = weight[r * side : (r + 1) * side]
        for c in range(side):
            w = w_row[c]
            px = qx + float(c - half)
            sx = (1.0 - wy) * x_upper[c] + wy * x_lower[c]
            sy = (1.0 - wy) * y_upper[c] + wy * y_lower[c]
            axx += w * sx * sx
            axy += w * sx * sy
            ayy += w * sy * sy
            bx += w * (sx * sx * px + sx * sy * py)
            by += w * (sx * sy * px + sy * sy * py)
    return axx, axy, ayy, bx, by


@njit(cache=True, nogil=True)
def forstner(smooth, corners, half, weight, which, iterations):  # pragma: no cover
    """Förstner's iteration for every corner at once (see ``refine_corners``): the window's
    offsets are the ``(2 half + 1)²`` integer ones, row-major (x fastest), corner ``i``'s
    weights ``weight[which[i]]``; stops when no corner moves by 1e-4 px or more. The
    samples' pixels and weights are found once per row and column of a window, not once
    per sample; the arithmetic is :func:`bilinear`'s."""
    height, width = smooth.shape
    side = 2 * half + 1
    columns = (
        np.empty(side, np.int64),
        np.empty(side, np.int64),
        np.empty(side),
        np.empty(side, np.bool_),
    )
    rows = (
        np.empty(side, np.int64),
        np.empty(side, np.int64),
        np.empty(side),
        np.empty(side, np.bool_),
    )
    across = np.empty((side + 1, side))
    down = np.empty((side + 1, side))
    q = corners.copy()
    new = corners.copy()
    for _ in range(iterations):
        shift = 0.0
        for i in range(q.shape[0]):
            left, top = np.floor(q[i, 0]) - half, np.floor(q[i, 1]) - half
            if left >= 1 and top >= 1 and left + side + 1 < width and top + side + 1 < height:
                axx, axy, ayy, bx, by = _forstner_sums_inside(
                    smooth, q[i, 0], q[i, 1], half, weight[which[i]], across, down
                )
            else:
                _axis_samples(q[i, 0], half, width, *columns)
                _axis_samples(q[i, 1], half, height, *rows)
                axx, axy, ayy, bx, by = _forstner_sums(
                    smooth, q[i, 0], q[i, 1], half, weight[which[i]], columns, rows
                )
            det = axx * ayy - axy * axy
            new[i, 0], new[i, 1] = q[i, 0], q[i, 1]
            if det > 1e-12:
                new[i, 0] = (ayy * bx - axy * by) / det
                new[i, 1] = (axx * by - axy * bx) / det
            shift = max(shift, abs(new[i, 0] - q[i, 0]), abs(new[i, 1] - q[i, 1]))
        q[:] = new
        if shift < 1e-4:
            break
    return q
