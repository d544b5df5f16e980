"""numba kernel of line voting (imported on first use: numba loads slowly).

Each edge point's votes go straight into the accumulator, split linearly
between the two nearest ρ bins: no ``points × θ`` temporaries.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = [
    "edge_points",
    "line_peaks",
    "peak_offsets",
    "points_by_row_and_column",
    "vote_lines",
    "vote_lines_into",
]


@njit(cache=True, nogil=True)
def vote_lines(x, y, weights, first, width, cos, sin, rho0, n_rho, pad):
    """Accumulator ``(len(cos), n_rho)``: point ``i`` votes for the ``width`` θ bins from
    ``first[i]`` (modulo the bin count) with weight ``weights[i]``; ``cos`` and ``sin`` are
    divided by the ρ step and ``rho0`` is ρ of bin 0 in steps. With ``pad`` > 0 it comes
    extended by ``pad`` rows each way, θ wrapping with ρ negated (θ + π is the line of θ
    with ρ negated: row ``-1`` is the last row reversed along ρ), written in place."""
    extended = np.empty((cos.size + 2 * pad, n_rho))
    vote_lines_into(extended, x, y, weights, first, width, cos, sin, rho0, pad)
    return extended


@njit(cache=True, nogil=True)
def vote_lines_into(extended, x, y, weights, first, width, cos, sin, rho0, pad):
    """:func:`vote_lines` written into ``extended`` (``len(cos) + 2 pad`` rows, zeroed
    here): a caller that reuses one array pays no page faults for a fresh one."""
    n_theta = cos.size
    n_rho = extended.shape[1]
    extended[:] = 0.0
    accumulator = extended[pad : pad + n_theta]
    if width == n_theta:  # every point votes for every θ: one θ row at a time (in cache),
        fracs = np.empty(x.size)  # each cell's votes still summed in the points' order;
        lowers = np.empty(x.size, dtype=np.int64)  # positions first, in a loop free of
        for t in range(n_theta):  # stores to the row (SIMD), then the votes
            row = accumulator[t]
            for i in range(x.size):
                position = x[i] * cos[t] + y[i] * sin[t] - rho0
                lower = np.floor(position)
                fracs[i] = position - lower
                lowers[i] = int(lower)
            for i in range(x.size):
                lower, frac = lowers[i], fracs[i]
                if lower >= 0 and lower + 1 < n_rho:
                    row[lower] += weights[i] * (1.0 - frac)
                    row[lower + 1] += weights[i] * frac
    else:
        for i in range(x.size):
            for k in range(width):
                t = (first[i] + k) % n_theta
                position = x[i] * cos[t] + y[i] * sin[t] - rho0
                lower = int(np.floor(position))
                frac = position - lower
                if lower >= 0 and lower + 1 < n_rho:
                    accumulator[t, lower] += weights[i] * (1.0 - frac)
                    accumulator[t, lower + 1] += weights[i] * frac
    for i in range(pad):
        for r in range(n_rho):
            extended[i, r] = extended[n_theta + i, n_rho - 1 - r]
            extended[pad + n_theta + i, r] = extended[pad + i, n_rho - 1 - r]


@njit(cache=True, nogil=True)
def line_peaks(extended, pad, theta_bins):
    """``(θ row, ρ column)`` of the cells of ``extended`` (θ padded by ``pad`` rows each way)
    in rows ``[pad, pad + theta_bins)`` and columns ``(0, n_rho - 1)`` that are positive and
    the maximum of their 3×3 neighbourhood, row-major (``local_maxima(extended, 3, 0)``
    restricted to those cells, where the window lies inside the array).

    A cell is such a maximum when it is at least the largest of its 3×3 (no NaN in votes):
    each row's maximum over 3 columns is computed once, branch-free over whole rows, and a
    cell compares with the largest of the three rows' (the test of every neighbour one by
    one mispredicted a branch at most cells)."""
    n_rho = extended.shape[1]
    across = np.empty((3, n_rho))
    for k in range(2):
        _max3(extended[pad - 1 + k], across[k])
    rows = []
    cols = []
    for t in range(pad, pad + theta_bins):
        _max3(extended[t + 1], across[(t - pad + 2) % 3])  # rows t - 1 … t + 1, rotating
        one, two, three = across[0], across[1], across[2]
        row = extended[t]
        for r in range(1, n_rho - 1):
            value = row[r]
            if value > 0.0 and value >= max(max(one[r], two[r]), three[r]):
                rows.append(t)
                cols.append(r)
    out = np.empty((len(rows), 2), dtype=np.int64)
    for i in range(len(rows)):
        out[i, 0] = rows[i]
        out[i, 1] = cols[i]
    return out


@njit(cache=True, nogil=True, inline="always")
def _max3(row, out):
    """``out[r] = max(row[r - 1], row[r], row[r + 1])`` for ``0 < r < len(row) - 1``."""
    for r in range(1, row.size - 1):
        out[r] = max(max(row[r - 1], row[r]), row[r + 1])


@njit(cache=True, nogil=True)
def _counting_order(keys, size, within):
    """The order of ``within`` (a permutation) stably sorted by ``keys`` in [0, size), and
    where each key's run starts (``size + 1`` entries)."""
    starts = np.zeros(size + 1, dtype=np.int64)
    for i in range(keys.size):
        starts[keys[i] + 1] += 1
    for k in range(size):
        starts[k + 1] += starts[k]
    fill = starts[:size].copy()
    order = np.empty(within.size, dtype=np.int64)
    for i in within:
        order[fill[keys[i]]] = i
        fill[keys[i]] += 1
    return order, starts


@njit(cache=True, nogil=True)
def points_by_row_and_column(x, y, height, width):
    """The points (on the pixel grid) by row, each row's by column, and by column, each
    column's by row: ``(row starts, order, columns, column starts, order, rows)``, row or
    column ``v`` being ``order[starts[v]:starts[v + 1]]`` (``np.lexsort`` of ``(x, y)`` and
    ``(y, x)`` by two stable counting sorts each)."""
    rows = y.astype(np.int64)
    columns = x.astype(np.int64)
    everyone = np.arange(x.size)
    by_row, row_starts = _counting_order(rows, height, _counting_order(columns, width, everyone)[0])
    by_column, column_starts = _counting_order(
        columns, width, _counting_order(rows, height, everyone)[0]
    )
    return row_starts, by_row, x[by_row], column_starts, by_column, y[by_column]


@njit(cache=True, nogil=True)
def _parabola(left, centre, right):
    """``_peaks.parabolic_offset`` of one peak."""
    curvature = left - 2.0 * centre + right
    if curvature < 0:
        return min(max((left - right) / (2.0 * curvature), -0.5), 0.5)
    return 0.0


@njit(cache=True, nogil=True)
def peak_offsets(array, rows, cols, solve):
    """``_peaks.quadratic_peak_2d`` peak by peak (``solve`` its 6×9 pseudo-inverse; each
    coefficient summed in the patch's order, so equal to it up to rounding)."""
    out = np.empty((rows.size, 2))
    patch = np.empty(9)
    coef = np.empty(6)
    for k in range(rows.size):
        r, c = rows[k], cols[k]
        for m in range(9):
            patch[m] = array[r + m // 3 - 1, c + m % 3 - 1]
        coef[:] = 0.0
        for j in range(1, 6):
            for m in range(9):
                coef[j] += solve[j, m] * patch[m]
        b, cc, d, e, g = coef[1], coef[2], coef[3], coef[4], coef[5]
        det = 4.0 * d * e - g * g
        du = dv = 0.0
        maximum = d < 0 and det > 0
        if maximum:
            du = (-2.0 * e * b + g * cc) / det
            dv = (-2.0 * d * cc + g * b) / det
        if not (maximum and abs(du) <= 1 and abs(dv) <= 1):
            du = _parabola(patch[1], patch[4], patch[7])
            dv = _parabola(patch[3], patch[4], patch[5])
        out[k, 0] = min(max(du, -0.5), 0.5)
        out[k, 1] = min(max(dv, -0.5), 0.5)
    return out


@njit(cache=True, nogil=True)
def edge_points(edges):
    """Columns ``x`` and rows ``y`` (float64) of the true pixels of ``edges``, row-major:
    ``np.nonzero`` in one pass, without its index arrays and their conversions."""
    height, width = edges.shape
    count = 0
    for r in range(height):
        for c in range(width):
            count += edges[r, c]
    x = np.empty(count)
    y = np.empty(count)
    k = 0
    for r in range(height):
        for c in range(width):
            if edges[r, c]:
                x[k] = c
                y[k] = r
                k += 1
    return x, y
