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

__all__ = [
    "forstner",
    "gradient",
    "grid_homography",
    "grow",
    "next_row",
    "saddle_peaks",
    "saddle_response",
    "sample",
    "x_junctions",
]


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
    inside the image there). A row's pixels are first compared with their 8 neighbours
    without branches, which rejects almost every pixel; only the rest scan the whole
    square."""
    height, width = response.shape
    border = radius + 1
    rows = []
    cols = []
    local = np.zeros(width, dtype=np.bool_)
    for y in range(border, height - border):
        above, row, below = response[y - 1], response[y], response[y + 1]
        for x in range(border, width - border):  # no branches: SIMD code
            value = row[x]
            local[x] = (
                (value > 0.0)
                & (row[x - 1] <= value)
                & (row[x + 1] <= value)
                & (above[x - 1] <= value)
                & (above[x] <= value)
                & (above[x + 1] <= value)
                & (below[x - 1] <= value)
                & (below[x] <= value)
                & (below[x + 1] <= value)
            )
        for x in range(border, width - border):
            if local[x] and _peak_of(response, y, x, radius, row[x]):
                rows.append(y)
                cols.append(x)
    return np.array(rows, dtype=np.int64), np.array(cols, dtype=np.int64)


@numba.njit(cache=True, nogil=True, inline="always")
def _peak_of(response, y, x, radius, value):  # pragma: no cover
    """No pixel of the square ``(y, x) ± radius`` exceeds ``value``."""
    for v in range(y - radius, y + radius + 1):
        for u in range(x - radius, x + radius + 1):
            if response[v, u] > value:
                return False
    return True


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
def _axis_samples(q, half, length, first, second, weight, inside):  # pragma: no cover
    """For the ``2 half + 1`` positions ``q + o`` (o = −half … half) along one axis of
    ``length`` pixels, what :func:`_bilinear` derives from each: the lower and upper pixel
    (``first``, ``second``), the weight of the upper one and whether it lies inside
    ``[0, length - 1]``, computed as :func:`_bilinear` computes them."""
    for c in range(2 * half + 1):
        p = q + float(c - half)
        inside[c] = 0.0 <= p <= length - 1
        lower = min(int(np.floor(p)), length - 1) if inside[c] else 0
        first[c] = lower
        second[c] = min(lower + 1, length - 1)
        weight[c] = p - lower


@numba.njit(cache=True, nogil=True)
def _forstner_sums(gx, gy, qx, qy, half, weight, columns, rows):  # pragma: no cover
    """Förstner's normal equations ``(axx, axy, ayy, bx, by)`` of one corner at ``(qx,
    qy)``: the window's samples in row-major order, each as :func:`_bilinear` gives it
    at ``q + offset`` (``columns`` and ``rows`` hold :func:`_axis_samples` of each axis)."""
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
                upper = (1.0 - wx) * gx[top, left] + wx * gx[top, right]
                lower = (1.0 - wx) * gx[bottom, left] + wx * gx[bottom, right]
                sx = (1.0 - wy) * upper + wy * lower
                upper = (1.0 - wx) * gy[top, left] + wx * gy[top, right]
                lower = (1.0 - wx) * gy[bottom, left] + wx * gy[bottom, right]
                sy = (1.0 - wy) * upper + wy * lower
            axx += w * sx * sx
            axy += w * sx * sy
            ayy += w * sy * sy
            bx += w * (sx * sx * px + sx * sy * py)
            by += w * (sx * sy * px + sy * sy * py)
    return axx, axy, ayy, bx, by


@numba.njit(cache=True, nogil=True)
def forstner(gx, gy, corners, half, weight, iterations):  # pragma: no cover
    """Förstner's iteration for every corner at once (see ``refine_corners``): the window's
    offsets are the ``(2 half + 1)²`` integer ones, row-major (x fastest), ``weight`` their
    ``corners × offsets`` weights; stops when no corner moves by 1e-4 px or more. The
    samples' pixels and weights are found once per row and column of a window, not once
    per sample; the arithmetic is :func:`_bilinear`'s."""
    height, width = gx.shape
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
    q = corners.copy()
    new = corners.copy()
    for _ in range(iterations):
        shift = 0.0
        for i in range(q.shape[0]):
            _axis_samples(q[i, 0], half, width, *columns)
            _axis_samples(q[i, 1], half, height, *rows)
            axx, axy, ayy, bx, by = _forstner_sums(
                gx, gy, q[i, 0], q[i, 1], half, weight[i], columns, rows
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


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
def _strongest_near(candidates, x, y, radius):  # pragma: no cover
    """The first (strongest) candidate within ``radius`` of ``(x, y)``, or -1."""
    for i in range(candidates.shape[0]):
        dx = candidates[i, 0] - x
        dy = candidates[i, 1] - y
        if np.sqrt(dx * dx + dy * dy) <= radius:
            return i
    return -1


@numba.njit(cache=True, nogil=True)
def x_junctions(smooth, points, radius, cos, sin, max_asymmetry):  # pragma: no cover
    """Every point is point-symmetric at its ``radius`` (``_corners._Photo.x_junctions``)."""
    for i in range(points.shape[0]):
        high = -np.inf
        low = np.inf
        worst = 0.0
        for a in range(cos.size):
            ox = radius[i] * cos[a]
            oy = radius[i] * sin[a]
            ahead = _bilinear(smooth, points[i, 0] + ox, points[i, 1] + oy)
            behind = _bilinear(smooth, points[i, 0] - ox, points[i, 1] - oy)
            high = max(high, ahead, behind)
            low = min(low, ahead, behind)
            worst = max(worst, abs(ahead - behind))
        if not worst <= max_asymmetry * max(high - low, 1e-9):
            return False
    return True


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
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
