"""numba kernel of line voting (imported on first use: numba loads slowly).

Each edge point's votes go straight into the accumulator, split linearly
between the two nearest ρ bins: no ``points × θ`` temporaries.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = [
    "edge_points",
    "line_peaks",
    "line_support",
    "peak_offsets",
    "points_by_row_and_column",
    "pruned_support",
    "select_lines",
    "support_bounds",
    "vote_lines",
    "vote_lines_into",
]


@numba.njit(cache=True, nogil=True)
def vote_lines(x, y, weights, first, width, cos, sin, rho0, n_rho, pad):
    """Accumulator ``(len(cos), n_rho)``: point ``i`` votes for the ``width`` θ bins from
    ``first[i]`` (modulo the bin count) with weight ``weights[i]``; ``cos`` and ``sin`` are
    divided by the ρ step and ``rho0`` is ρ of bin 0 in steps. With ``pad`` > 0 it comes
    extended by ``pad`` rows each way, θ wrapping with ρ negated (θ + π is the line of θ
    with ρ negated: row ``-1`` is the last row reversed along ρ), written in place."""
    extended = np.empty((cos.size + 2 * pad, n_rho))
    vote_lines_into(extended, x, y, weights, first, width, cos, sin, rho0, pad)
    return extended


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True, inline="always")
def _max3(row, out):
    """``out[r] = max(row[r - 1], row[r], row[r + 1])`` for ``0 < r < len(row) - 1``."""
    for r in range(1, row.size - 1):
        out[r] = max(max(row[r - 1], row[r]), row[r + 1])


@numba.njit(cache=True, nogil=True, inline="always")
def _visit(
    i, x, y, orientation, check, free, c, s, t, rho, tolerance, window, cells, stamp, on, mark
):
    """Point ``i`` supports the line (``_gather``): marks it and returns 1 when it covers a
    new cell along the line, else 0."""
    if not free[i] or abs(x[i] * c + y[i] * s - rho) > tolerance:
        return 0
    if check:
        gap = abs(orientation[i] - t)
        if min(gap, np.pi - gap) > window:
            return 0
    if mark:
        on[i] = True
    cell = int(np.floor(y[i] * c - x[i] * s)) + cells.size // 2
    if cells[cell] == stamp:
        return 0
    cells[cell] = stamp
    return 1


@numba.njit(cache=True, nogil=True)
def _band(x, y, free, rho, theta, tolerance, cells, stamp, on, mark, index):
    """``_gather`` without the orientation check, visiting only the points within
    ``tolerance`` (plus a pixel for rounding) of the line: ``index`` (``_lines._point_index``)
    holds the points by row and by column, each line sorted; a line nearer to the x axis
    is taken row by row (the columns each row's stretch of the band covers, found by
    bisection), one nearer to the y axis column by column."""
    c, s = np.cos(theta), np.sin(theta)
    if abs(s) >= abs(c):  # v = row, u = column: v s + u c = rho
        starts, order, keys, a, b, extent = index[0], index[1], index[2], s, c, index[6]
    else:
        starts, order, keys, a, b, extent = index[3], index[4], index[5], c, s, index[7]
    majors = starts.size - 1
    ends = ((rho - tolerance) / a, (rho + tolerance) / a, (rho - tolerance - extent * b) / a)
    low = min(min(ends[0], ends[1]), min(ends[2], (rho + tolerance - extent * b) / a))
    high = max(max(ends[0], ends[1]), max(ends[2], (rho + tolerance - extent * b) / a))
    first = int(max(np.floor(low) - 1.0, 0.0))
    last = int(min(np.ceil(high) + 1.0, majors - 1.0))
    covered = 0
    for v in range(first, last + 1):
        begin, end = starts[v], starts[v + 1]
        if begin == end:
            continue
        if abs(b) > 1e-9:
            one, two = (rho - tolerance - v * a) / b, (rho + tolerance - v * a) / b
            u0, u1 = min(one, two) - 1.0, max(one, two) + 1.0
            begin += np.searchsorted(keys[begin:end], u0)
        else:
            u1 = np.inf
        for j in range(begin, end):
            if keys[j] > u1:
                break
            covered += _visit(
                order[j],
                x,
                y,
                x,
                False,
                free,
                c,
                s,
                0.0,
                rho,
                tolerance,
                0.0,
                cells,
                stamp,
                on,
                mark,
            )
    return covered


@numba.njit(cache=True, nogil=True)
def _scan_ranges(orientation, check, theta, window):
    """Index ranges ``(a0, a1, b0, b1)`` of the points, sorted by ``orientation`` in [0, π),
    whose orientation can be within ``window`` of ``theta`` mod π (all of them unless
    ``check``)."""
    n = orientation.size
    if not check or window >= 0.5 * np.pi:
        return 0, n, 0, 0
    t = theta % np.pi
    low, high = t - window, t + window
    if low < 0:
        return np.searchsorted(orientation, low + np.pi), n, 0, np.searchsorted(orientation, high)
    if high >= np.pi:
        return np.searchsorted(orientation, low), n, 0, np.searchsorted(orientation, high - np.pi)
    return np.searchsorted(orientation, low), np.searchsorted(orientation, high), 0, 0


@numba.njit(cache=True, nogil=True)
def _gather(
    x, y, orientation, check, free, rho, theta, tolerance, window, cells, stamp, on, mark, index
):
    """Mark in ``on`` (if ``mark``; cleared first) the free points supporting the line
    ``(rho, theta)``: within ``tolerance`` of it and, where ``check``, with ``orientation``
    within ``window`` of ``theta`` mod π. Returns how many 1-px cells along the line they
    cover (``cells`` holds ``stamp`` where covered; positions are offset by half its size).
    Without ``check``, only the pixels near the line are visited (:func:`_band` on
    ``index``); with it, the points whose orientation is near ``theta``.
    """
    if mark:
        on[:] = False
    if not check:
        return _band(x, y, free, rho, theta, tolerance, cells, stamp, on, mark, index)
    c, s = np.cos(theta), np.sin(theta)
    t = theta % np.pi
    covered = 0
    a0, a1, b0, b1 = _scan_ranges(orientation, check, theta, window)
    for first, last in ((a0, a1), (b0, b1)):
        for i in range(first, last):
            covered += _visit(
                i,
                x,
                y,
                orientation,
                True,
                free,
                c,
                s,
                t,
                rho,
                tolerance,
                window,
                cells,
                stamp,
                on,
                mark,
            )
    return covered


@numba.njit(cache=True, nogil=True)
def line_support(x, y, orientation, check, rho, theta, tolerance, window, extent, index):
    """Length in pixels of each line ``(rho[k], theta[k])`` covered by edge points: the number
    of 1-px cells along it holding the projection of a point within ``tolerance`` of it (and,
    where ``check``, of ``orientation`` within ``window`` radians of ``theta`` mod π). Points
    sorted by ``orientation`` in [0, π); positions along a line within ``±extent``."""
    counts = np.zeros(rho.size, dtype=np.int64)
    cells = np.zeros(2 * int(np.ceil(extent)) + 4, dtype=np.int64)
    free = np.ones(x.size, dtype=np.bool_)
    on = np.zeros(x.size, dtype=np.bool_)
    for k in range(rho.size):
        counts[k] = _gather(
            x,
            y,
            orientation,
            check,
            free,
            rho[k],
            theta[k],
            tolerance,
            window,
            cells,
            k + 1,
            on,
            False,
            index,
        )
    return counts


@numba.njit(cache=True, nogil=True)
def support_bounds(raw, pad, rho, theta, rho0, rho_step, tolerance, xmax, ymax):
    r"""An upper bound of each line's support from unit votes ``raw`` (:func:`vote_lines`,
    every point voting for every θ, unsmoothed; ``rho0`` is ρ of bin 0 in steps).

    A point of ``[0, xmax] × [0, ymax]`` within ``tolerance`` of the line ``(ρ, θ)`` is
    :math:`p = \rho_p n(\theta) + a\, t(\theta)`, :math:`|\rho_p - \rho| \le` tolerance
    and :math:`a` between the least and largest of the image corners' :math:`a`; at the θ
    bin nearest to θ, :math:`\theta + \Delta`, its ρ is
    :math:`\rho_p \cos\Delta + a \sin\Delta` (negated past π), in an interval whose
    ρ bins (widened by 1e-6 bin for rounding) and the next one receive its whole vote. The
    support (distinct cells covered) is at most the number of such points, so at most the
    sum of those cells.
    """
    n_theta = raw.shape[0] - 2 * pad
    n_rho = raw.shape[1]
    step = np.pi / n_theta
    bounds = np.empty(rho.size)
    for k in range(rho.size):
        nearest = int(np.round(theta[k] / step))
        row = nearest % n_theta
        c, s = np.cos(theta[k]), np.sin(theta[k])
        a_low = min(0.0, -xmax * s) + min(0.0, ymax * c)  # a = y cos θ - x sin θ
        a_high = max(0.0, -xmax * s) + max(0.0, ymax * c)
        cd, sd = np.cos(nearest * step - theta[k]), np.sin(nearest * step - theta[k])
        low = (rho[k] - tolerance) * cd + min(a_low * sd, a_high * sd)
        high = (rho[k] + tolerance) * cd + max(a_low * sd, a_high * sd)
        if (nearest - row) // n_theta % 2 != 0:  # θ + π: ρ negated
            low, high = -high, -low
        first = int(min(max(np.floor(low / rho_step - rho0 - 1e-6), 0.0), n_rho - 1.0))
        last = int(min(max(np.floor(high / rho_step - rho0 + 1e-6) + 1.0, 0.0), n_rho - 1.0))
        total = 0.0
        for b in range(first, last + 1):
            total += raw[pad + row, b]
        bounds[k] = total
    return bounds


@numba.njit(cache=True, nogil=True)
def pruned_support(x, y, index, bounds, rho, theta, tolerance, extent, threshold):
    """:func:`line_support` without the orientation check, where only the lines that can
    reach ``threshold`` × the largest support matter: lines are taken by decreasing
    ``bounds`` (:func:`support_bounds`) and the rest are left at 0 once a bound falls
    below ``threshold`` × the largest support found (so are all their supports: the
    largest support and every support at least ``threshold`` × it are exact)."""
    counts = np.zeros(rho.size, dtype=np.int64)
    cells = np.zeros(2 * int(np.ceil(extent)) + 4, dtype=np.int64)
    free = np.ones(x.size, dtype=np.bool_)
    on = np.zeros(0, dtype=np.bool_)
    near = np.empty(x.size, dtype=np.bool_)
    # few points for the image's rows and columns: a branch-free pass over all of them
    # costs less than walking the band's rows (the same points pass the same test)
    scan = x.size <= 4 * (index[0].size + index[3].size)
    largest = 0
    for k in np.argsort(-bounds, kind="mergesort"):
        if bounds[k] + 1e-6 < threshold * largest:
            break
        if scan:
            counts[k] = _scan(x, y, rho[k], theta[k], tolerance, cells, k + 1, near)
        else:
            counts[k] = _band(
                x, y, free, rho[k], theta[k], tolerance, cells, k + 1, on, False, index
            )
        largest = max(largest, counts[k])
    return counts


@numba.njit(cache=True, nogil=True)
def _scan(x, y, rho, theta, tolerance, cells, stamp, near):
    """:func:`_band` with every point free (as in :func:`pruned_support`), by a scan of
    every point: first which lie within ``tolerance`` of the line (one branch-free loop,
    :func:`_visit`'s test), then the cells those cover (the count of distinct cells does
    not depend on the order the points are visited in)."""
    c, s = np.cos(theta), np.sin(theta)
    for i in range(x.size):
        near[i] = abs(x[i] * c + y[i] * s - rho) <= tolerance
    covered = 0
    for i in range(x.size):
        if near[i]:
            cell = int(np.floor(y[i] * c - x[i] * s)) + cells.size // 2
            if cells[cell] != stamp:
                cells[cell] = stamp
                covered += 1
    return covered


@numba.njit(cache=True, nogil=True)
def select_lines(
    x,
    y,
    orientation,
    check,
    rho,
    theta,
    order,
    floor,
    tolerance,
    window,
    extent,
    max_lines,
    min_distance,
    theta_step,
    rho_step,
    index,
):
    """Greedy selection of lines ``(ρ, θ, covered length)`` from candidates ``order``: each
    candidate is refitted twice by total least squares to its free supporting points, kept
    when they still cover ``floor`` cells and it is ``min_distance`` bins from every line
    kept, and then claims those points."""
    cells = np.zeros(2 * int(np.ceil(extent)) + 4, dtype=np.int64)
    stamp = 0
    free = np.ones(x.size, dtype=np.bool_)
    on = np.zeros(x.size, dtype=np.bool_)
    out = np.zeros((min(max_lines, order.size), 3))
    count = 0
    for k in order:
        if count == max_lines:
            break
        r, t = rho[k], theta[k]
        stamp += 1
        covered = _gather(
            x, y, orientation, check, free, r, t, tolerance, window, cells, stamp, on, True, index
        )
        if covered < floor:
            continue
        for _ in range(2):  # a peak's θ is coarse for a short segment: fit its points
            n = 0
            mx = 0.0
            my = 0.0
            for i in range(x.size):
                if on[i]:
                    n += 1
                    mx += x[i]
                    my += y[i]
            if n < 2:
                break
            mx /= n
            my /= n
            sxx = 0.0
            sxy = 0.0
            syy = 0.0
            for i in range(x.size):
                if on[i]:
                    dx, dy = x[i] - mx, y[i] - my
                    sxx += dx * dx
                    sxy += dx * dy
                    syy += dy * dy
            normal = 0.5 * np.arctan2(2.0 * sxy, sxx - syy) + 0.5 * np.pi  # least spread
            nx, ny = np.cos(normal), np.sin(normal)
            if nx * np.cos(t) + ny * np.sin(t) < 0:  # stay on the candidate's branch of θ
                nx, ny = -nx, -ny
            t = np.arctan2(ny, nx)
            r = mx * nx + my * ny
            stamp += 1
            covered = _gather(
                x,
                y,
                orientation,
                check,
                free,
                r,
                t,
                tolerance,
                window,
                cells,
                stamp,
                on,
                True,
                index,
            )
        if covered < floor:
            continue
        if abs(t) < 1e-12 or abs(t - np.pi) < 1e-12:  # rounding of an axis-parallel fit
            r, t = (r, 0.0) if abs(t) < 1e-12 else (-r, 0.0)
        if t < 0 or t >= np.pi:  # the same line with θ in [0, π)
            r, t = -r, t % np.pi
        close = False
        for j in range(count):
            d_theta = abs(out[j, 1] - t)
            other = out[j, 0]
            if d_theta > 0.5 * np.pi:
                d_theta, other = np.pi - d_theta, -other
            if np.hypot(d_theta / theta_step, (r - other) / rho_step) < min_distance:
                close = True
                break
        if close:
            continue
        for i in range(x.size):
            if on[i]:
                free[i] = False
        out[count, 0] = r
        out[count, 1] = t
        out[count, 2] = covered
        count += 1
    return out[:count]


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
def _parabola(left, centre, right):
    """``_peaks.parabolic_offset`` of one peak."""
    curvature = left - 2.0 * centre + right
    if curvature < 0:
        return min(max((left - right) / (2.0 * curvature), -0.5), 0.5)
    return 0.0


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
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
