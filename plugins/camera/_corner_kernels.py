"""numba kernels of checkerboard corners (imported on first use: numba loads slowly).

The saddle response and its peaks in one pass each, bilinear samples of an image at
sub-pixel points, and Förstner's sub-pixel iteration for all corners, without the
``corners × window`` temporaries of the array form. The arithmetic is NumPy's and
SciPy's: :func:`gradient` is ``np.gradient`` to the bit, :func:`sample` is
``scipy.ndimage.map_coordinates(order=1)`` (mode ``constant``: 0 outside the pixel
centres' range); sums run in order, so a refined corner may differ from the array form
by rounding (about 1e-12 px).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["forstner", "gradient", "saddle_peaks", "saddle_response", "sample"]


@numba.njit(cache=True, nogil=True, inline="always")
def _dy(f, y, x):  # pragma: no cover
    """``np.gradient(f, axis=0)`` at ``(y, x)``: central inside, one-sided at the border."""
    height = f.shape[0]
    if 0 < y < height - 1:
        return (f[y + 1, x] - f[y - 1, x]) / 2.0
    if y == 0:
        return f[1, x] - f[0, x]
    return f[y, x] - f[y - 1, x]


@numba.njit(cache=True, nogil=True, inline="always")
def _dx(f, y, x):  # pragma: no cover
    """``np.gradient(f, axis=1)`` at ``(y, x)``."""
    width = f.shape[1]
    if 0 < x < width - 1:
        return (f[y, x + 1] - f[y, x - 1]) / 2.0
    if x == 0:
        return f[y, 1] - f[y, 0]
    return f[y, x] - f[y, x - 1]


@numba.njit(cache=True, nogil=True)
def gradient(f):  # pragma: no cover
    """``np.gradient(f)`` of a 2-D array (both sides at least 2 long), ``(d/dy, d/dx)``."""
    height, width = f.shape
    gy = np.empty((height, width))
    gx = np.empty((height, width))
    for y in range(height):
        for x in range(width):
            gy[y, x] = _dy(f, y, x)
            gx[y, x] = _dx(f, y, x)
    return gy, gx


@numba.njit(cache=True, nogil=True)
def saddle_response(smooth):  # pragma: no cover
    r""":math:`-(I_{xx} I_{yy} - I_{xy} I_{yx})` with every derivative by ``np.gradient``
    (one pass over the first derivatives; no other full-size temporaries)."""
    iy, ix = gradient(smooth)
    height, width = smooth.shape
    out = np.empty((height, width))
    for y in range(height):
        for x in range(width):
            iyy, iyx = _dy(iy, y, x), _dx(iy, y, x)
            ixy, ixx = _dy(ix, y, x), _dx(ix, y, x)
            out[y, x] = -(ixx * iyy - ixy * iyx)
    return out


@numba.njit(cache=True, nogil=True)
def saddle_peaks(response, radius):  # pragma: no cover
    """Rows and columns (row-major order) of the pixels at least ``radius + 1`` from the
    border with a positive response equal to the maximum of their ``2 radius + 1``
    square (``response == maximum_filter(response, 2 radius + 1)``, whose window lies
    inside the image there), the maximum taken along rows, then down columns."""
    height, width = response.shape
    border = radius + 1
    across = np.empty_like(response)  # the maximum along each row's window
    for y in range(height):
        for x in range(radius, width - radius):
            best = response[y, x - radius]
            for u in range(x - radius + 1, x + radius + 1):
                best = max(best, response[y, u])
            across[y, x] = best
    rows = []
    cols = []
    for y in range(border, height - border):
        for x in range(border, width - border):
            value = response[y, x]
            if value <= 0.0 or across[y, x] > value:
                continue
            best = across[y - radius, x]
            for v in range(y - radius + 1, y + radius + 1):
                best = max(best, across[v, x])
            if best <= value:
                rows.append(y)
                cols.append(x)
    return np.array(rows, dtype=np.int64), np.array(cols, dtype=np.int64)


@numba.njit(cache=True, nogil=True, inline="always")
def _bilinear(values, x, y):  # pragma: no cover
    """``values`` at ``(x, y)`` interpolated linearly; 0 outside ``[0, W-1] × [0, H-1]``."""
    height, width = values.shape
    if not (0.0 <= x <= width - 1 and 0.0 <= y <= height - 1):
        return 0.0
    x0 = min(int(np.floor(x)), width - 1)
    y0 = min(int(np.floor(y)), height - 1)
    wx = x - x0
    wy = y - y0
    x1 = min(x0 + 1, width - 1)
    y1 = min(y0 + 1, height - 1)
    top = (1.0 - wx) * values[y0, x0] + wx * values[y0, x1]
    bottom = (1.0 - wx) * values[y1, x0] + wx * values[y1, x1]
    return (1.0 - wy) * top + wy * bottom


@numba.njit(cache=True, nogil=True)
def sample(values, xs, ys):  # pragma: no cover
    """``values`` at the points ``(xs[i], ys[i])`` (flat arrays), see :func:`_bilinear`."""
    out = np.empty(xs.size)
    for i in range(xs.size):
        out[i] = _bilinear(values, xs[i], ys[i])
    return out


@numba.njit(cache=True, nogil=True)
def forstner(gx, gy, corners, ox, oy, weight, iterations):  # pragma: no cover
    """Förstner's iteration for every corner at once (see ``refine_corners``): ``ox, oy``
    the window's offsets, ``weight`` their ``corners × offsets`` weights; stops when no
    corner moves by 1e-4 px or more."""
    q = corners.copy()
    new = corners.copy()
    for _ in range(iterations):
        shift = 0.0
        for i in range(q.shape[0]):
            axx = axy = ayy = bx = by = 0.0
            for k in range(ox.size):
                w = weight[i, k]
                if w == 0.0:
                    continue
                px = q[i, 0] + ox[k]
                py = q[i, 1] + oy[k]
                sx = _bilinear(gx, px, py)
                sy = _bilinear(gy, px, py)
                axx += w * sx * sx
                axy += w * sx * sy
                ayy += w * sy * sy
                bx += w * (sx * sx * px + sx * sy * py)
                by += w * (sx * sy * px + sy * sy * py)
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
