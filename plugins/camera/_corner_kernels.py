"""numba kernels of checkerboard corners (imported on first use: numba loads slowly).

The σ = 1 smoothing, the saddle response and its peaks in one pass each, and bilinear
samples of an image at sub-pixel points (Förstner's iteration is in
``_forstner_kernels``). The arithmetic is NumPy's and SciPy's: :func:`gradient` is
``np.gradient`` to the bit, :func:`sample` is ``scipy.ndimage.map_coordinates(order=1)``
(mode ``constant``: 0 outside the pixel centres' range).
"""

from __future__ import annotations

import functools

import numpy as np

from ..shared.jit import njit

__all__ = [
    "bilinear",
    "gradient",
    "gradient_samples",
    "parabola_peaks",
    "saddle_peaks",
    "saddle_response",
    "sample",
    "smooth_reflect",
    "smooth_unit",
]


@njit(cache=True, nogil=True, inline="always")
def _dy(f, y, x):  # pragma: no cover
    """``np.gradient(f, axis=0)`` at ``(y, x)``: central inside, one-sided at the border."""
    height = f.shape[0]
    if 0 < y < height - 1:
        return (f[y + 1, x] - f[y - 1, x]) / 2.0
    if y == 0:
        return f[1, x] - f[0, x]
    return f[y, x] - f[y - 1, x]


@njit(cache=True, nogil=True, inline="always")
def _dx(f, y, x):  # pragma: no cover
    """``np.gradient(f, axis=1)`` at ``(y, x)``."""
    width = f.shape[1]
    if 0 < x < width - 1:
        return (f[y, x + 1] - f[y, x - 1]) / 2.0
    if x == 0:
        return f[y, 1] - f[y, 0]
    return f[y, x] - f[y, x - 1]


@njit(cache=True, nogil=True, inline="always")
def _rows_apart(f, y):  # pragma: no cover
    """The rows ``np.gradient(f, axis=0)`` subtracts at row ``y`` and the factor of their
    difference: ``(f[y + 1], f[y - 1], 0.5)`` inside, ``(f[1], f[0], 1.0)`` at the top,
    ``(f[y], f[y - 1], 1.0)`` at the bottom (a product by 0.5 is the division by 2.0 to
    the bit, by 1.0 changes nothing)."""
    height = f.shape[0]
    if 0 < y < height - 1:
        return f[y + 1], f[y - 1], 0.5
    if y == 0:
        return f[1], f[0], 1.0
    return f[y], f[y - 1], 1.0


@njit(cache=True, nogil=True, inline="always")
def _row_derivatives(f, y, dy, dx):  # pragma: no cover
    """Row ``y`` of ``np.gradient(f)`` into ``dy`` and ``dx``: the cases of the border
    chosen once per row and at the row's two ends, so the inside is one loop without
    branches (SIMD code); the arithmetic is :func:`_dy`'s and :func:`_dx`'s."""
    width = f.shape[1]
    after, before, factor = _rows_apart(f, y)
    row = f[y]
    for x in range(width):
        dy[x] = (after[x] - before[x]) * factor
    for x in range(1, width - 1):
        dx[x] = (row[x + 1] - row[x - 1]) * 0.5
    dx[0] = row[1] - row[0]
    dx[width - 1] = row[width - 1] - row[width - 2]


@njit(cache=True, nogil=True)
def gradient(f):  # pragma: no cover
    """``np.gradient(f)`` of a 2-D array (both sides at least 2 long), ``(d/dy, d/dx)``."""
    height, width = f.shape
    gy = np.empty((height, width))
    gx = np.empty((height, width))
    for y in range(height):
        _row_derivatives(f, y, gy[y], gx[y])
    return gy, gx


@njit(cache=True, nogil=True)
def saddle_response(smooth):  # pragma: no cover
    r""":math:`-(I_{xx} I_{yy} - I_{xy} I_{yx})` with every derivative by ``np.gradient``
    (one pass over the first derivatives; the second ones a row at a time)."""
    iy, ix = gradient(smooth)
    height, width = smooth.shape
    out = np.empty((height, width))
    iyy, iyx = np.empty(width), np.empty(width)
    ixy, ixx = np.empty(width), np.empty(width)
    for y in range(height):
        _row_derivatives(iy, y, iyy, iyx)
        _row_derivatives(ix, y, ixy, ixx)
        row = out[y]
        for x in range(width):
            row[x] = -(ixx[x] * iyy[x] - ixy[x] * iyx[x])
    return out


@njit(cache=True, nogil=True)
def saddle_peaks(response, radius):  # pragma: no cover
    """Rows and columns (row-major order) of the pixels at least ``radius + 1`` from the
    border with a positive response equal to the maximum of their ``2 radius + 1``
    square (``response == maximum_filter(response, 2 radius + 1)``, whose window lies
    inside the image there). A row's pixels are first compared with their 8 neighbours
    without branches, which rejects almost every pixel; the rest are gathered without
    branches too, then each scans its whole square. Every row is read through views
    indexed from 0 (no index can be negative: the compiled loops have no wrap-around
    test and the first is SIMD code)."""
    height, width = response.shape
    border = radius + 1
    inner = max(width - 2 * border, 0)
    span = 2 * radius + 1
    rows = []
    cols = []
    local = np.zeros(inner, dtype=np.bool_)
    found = np.empty(inner, dtype=np.int64)
    for y in range(border, height - border):
        above, row, below = response[y - 1], response[y], response[y + 1]
        a_left, a_mid, a_right = above[border - 1 :], above[border:], above[border + 1 :]
        left, mid, right = row[border - 1 :], row[border:], row[border + 1 :]
        b_left, b_mid, b_right = below[border - 1 :], below[border:], below[border + 1 :]
        for k in range(inner):  # pixel border + k; no branches: SIMD code
            value = mid[k]
            local[k] = (
                (value > 0.0)
                & (left[k] <= value)
                & (right[k] <= value)
                & (a_left[k] <= value)
                & (a_mid[k] <= value)
                & (a_right[k] <= value)
                & (b_left[k] <= value)
                & (b_mid[k] <= value)
                & (b_right[k] <= value)
            )
        count = 0
        for k in range(inner):  # the local maxima's places, gathered without branches
            found[count] = k
            count += local[k]
        for i in range(count):
            k = found[i]
            if _peak_of(response, y - radius, k + border - radius, span, mid[k]):
                rows.append(y)
                cols.append(border + k)
    return np.array(rows, dtype=np.int64), np.array(cols, dtype=np.int64)


@njit(cache=True, nogil=True, inline="always")
def _peak_of(response, top, left, span, value):  # pragma: no cover
    """No pixel of the ``span × span`` square at ``(top, left)`` exceeds ``value`` (each
    row read whole, through a view indexed from 0)."""
    for v in range(span):
        window = response[top + v, left:]
        above = False
        for u in range(span):
            above |= window[u] > value
        if above:
            return False
    return True


@njit(cache=True, nogil=True)
def parabola_peaks(response, rows, cols):  # pragma: no cover
    """``(x, y)`` of each peak ``(rows[i], cols[i])`` of ``response`` placed by a parabola
    through its 3 samples along each axis, the offset within ±0.5 (a flat or upward
    curvature counts as −1e-300), ``N×2``: NumPy's arithmetic of
    ``coarse_saddle_candidates`` (``np.minimum``, ``np.clip``: a NaN stays NaN), per peak."""
    out = np.empty((rows.size, 2))
    for i in range(rows.size):
        r, c = rows[i], cols[i]
        centre = response[r, c]
        for axis in range(2):
            before = response[r - 1, c] if axis == 0 else response[r, c - 1]
            after = response[r + 1, c] if axis == 0 else response[r, c + 1]
            curvature = before - 2 * centre + after
            if not (curvature < -1e-300 or np.isnan(curvature)):
                curvature = -1e-300
            offset = (before - after) / (2 * curvature)
            if offset < -0.5:
                offset = -0.5
            elif offset > 0.5:
                offset = 0.5
            if axis == 0:
                out[i, 1] = 2.0 * (r + offset)
            else:
                out[i, 0] = 2.0 * (c + offset)
    return out


@njit(cache=True, nogil=True, inline="always")
def bilinear(values, x, y):  # pragma: no cover
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


@njit(cache=True, nogil=True)
def sample(values, xs, ys):  # pragma: no cover
    """``values`` at the points ``(xs[i], ys[i])`` (flat arrays), see :func:`bilinear`."""
    out = np.empty(xs.size)
    for i in range(xs.size):
        out[i] = bilinear(values, xs[i], ys[i])
    return out


@njit(cache=True, nogil=True)
def gradient_samples(smooth, xs, ys):  # pragma: no cover
    """:func:`sample` of both images of :func:`gradient` of ``smooth`` at the points, the
    four pixels' gradients computed where read: ``(d/dx, d/dy)``."""
    height, width = smooth.shape
    gx = np.zeros(xs.size)
    gy = np.zeros(xs.size)
    for i in range(xs.size):
        x, y = xs[i], ys[i]
        if not (0.0 <= x <= width - 1 and 0.0 <= y <= height - 1):
            continue
        x0 = min(int(np.floor(x)), width - 1)
        y0 = min(int(np.floor(y)), height - 1)
        wx, wy = x - x0, y - y0
        x1, y1 = min(x0 + 1, width - 1), min(y0 + 1, height - 1)
        top = (1.0 - wx) * _dx(smooth, y0, x0) + wx * _dx(smooth, y0, x1)
        bottom = (1.0 - wx) * _dx(smooth, y1, x0) + wx * _dx(smooth, y1, x1)
        gx[i] = (1.0 - wy) * top + wy * bottom
        top = (1.0 - wx) * _dy(smooth, y0, x0) + wx * _dy(smooth, y0, x1)
        bottom = (1.0 - wx) * _dy(smooth, y1, x0) + wx * _dy(smooth, y1, x1)
        gy[i] = (1.0 - wy) * top + wy * bottom
    return gx, gy


@functools.lru_cache(maxsize=32)
def _smoothing_plan(
    height: int, width: int, sigma: float
) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
    """``smooth_gaussian``'s arguments of its compiled call for an image ``height × width``
    (reflect): the taps, their symmetry, and the source row and column under each tap,
    made once per shape and scale (they are read, never written)."""
    from ..shared.separable import gaussian_taps

    taps = gaussian_taps(sigma)
    symmetry = 1 if np.array_equal(taps, taps[::-1]) else 0
    half = taps.size // 2  # scipy's "reflect" is numpy's "symmetric" padding
    rows = np.pad(np.arange(height, dtype=np.int64), half, mode="symmetric")
    columns = np.pad(np.arange(width, dtype=np.int64), half, mode="symmetric")
    for array in (taps, rows, columns):
        array.flags.writeable = False
    return taps, symmetry, rows, columns


def smooth_reflect(image: np.ndarray, sigma: float) -> np.ndarray:
    """``smooth_gaussian(image, sigma)`` of a 2-D ``float64`` image (reflect), the same
    bits, without building the boundary's index arrays again at every call."""
    from ..shared.separable_kernels import correlate_both

    data = np.ascontiguousarray(image, dtype=np.float64)
    taps, symmetry, rows, columns = _smoothing_plan(*data.shape, float(sigma))
    out = np.empty(data.shape, np.float64)
    correlate_both(data, taps, symmetry, rows, taps, symmetry, columns, out)
    return out


def smooth_unit(image: np.ndarray) -> np.ndarray:
    """``smooth_gaussian(image.astype(np.float64), 1.0)`` (reflect), the same bits: a
    ``float32`` image is widened where the filter's first pass reads it
    (``correlate_both`` into a ``float64`` out), not copied to ``float64`` first."""
    from ..shared.separable import smooth_gaussian
    from ..shared.separable_kernels import correlate_both

    if image.dtype != np.float32 or image.ndim != 2:
        return np.ascontiguousarray(smooth_gaussian(np.asarray(image, np.float64), 1.0))
    data = np.ascontiguousarray(image)
    taps, _, rows, columns = _smoothing_plan(*data.shape, 1.0)
    out = np.empty(data.shape, np.float64)
    correlate_both(data, taps, 1, rows, taps, 1, columns, out)
    return out
