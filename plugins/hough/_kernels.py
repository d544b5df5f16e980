"""numba kernel of line voting (imported on first use: numba loads slowly).

Each edge point's votes go straight into the accumulator, split linearly
between the two nearest ρ bins: no ``points × θ`` temporaries.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["bucket_points", "line_peaks", "line_support", "select_lines", "vote_lines"]


@numba.njit(cache=True, nogil=True)
def vote_lines(x, y, weights, first, width, cos, sin, rho0, n_rho, pad):
    """Accumulator ``(len(cos), n_rho)``: point ``i`` votes for the ``width`` θ bins from
    ``first[i]`` (modulo the bin count) with weight ``weights[i]``; ``cos`` and ``sin`` are
    divided by the ρ step and ``rho0`` is ρ of bin 0 in steps. With ``pad`` > 0 it comes
    extended by ``pad`` rows each way, θ wrapping with ρ negated (θ + π is the line of θ
    with ρ negated: row ``-1`` is the last row reversed along ρ), written in place."""
    n_theta = cos.size
    extended = np.zeros((n_theta + 2 * pad, n_rho))
    accumulator = extended[pad : pad + n_theta]
    if width == n_theta:  # every point votes for every θ: one θ row at a time (in cache),
        for t in range(n_theta):  # each cell's votes still summed in the points' order
            row = accumulator[t]
            for i in range(x.size):
                position = x[i] * cos[t] + y[i] * sin[t] - rho0
                lower = int(np.floor(position))
                frac = position - lower
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
    return extended


@numba.njit(cache=True, nogil=True)
def line_peaks(extended, pad, theta_bins):
    """``(θ row, ρ column)`` of the cells of ``extended`` (θ padded by ``pad`` rows each way)
    in rows ``[pad, pad + theta_bins)`` and columns ``(0, n_rho - 1)`` that are positive and
    the maximum of their 3×3 neighbourhood, row-major (``local_maxima(extended, 3, 0)``
    restricted to those cells, where the window lies inside the array)."""
    n_rho = extended.shape[1]
    rows = []
    cols = []
    for t in range(pad, pad + theta_bins):
        for r in range(1, n_rho - 1):
            value = extended[t, r]
            if value <= 0.0:
                continue
            if _peak_3x3(extended, t, r, value):
                rows.append(t)
                cols.append(r)
    out = np.empty((len(rows), 2), dtype=np.int64)
    for i in range(len(rows)):
        out[i, 0] = rows[i]
        out[i, 1] = cols[i]
    return out


@numba.njit(cache=True, nogil=True, inline="always")
def _peak_3x3(extended, t, r, value):
    """No cell of the 3×3 around ``(t, r)`` exceeds ``value`` (the first larger one ends
    the scan)."""
    if extended[t, r + 1] > value or extended[t, r - 1] > value:
        return False
    for v in (t - 1, t + 1):
        for u in range(r - 1, r + 2):
            if extended[v, u] > value:
                return False
    return True


@numba.njit(cache=True, nogil=True)
def bucket_points(x, y, cos, sin, rho0, n_rho):
    """For each θ bin ``k`` (``cos``, ``sin`` of its angle over the ρ step; ``rho0`` ρ of
    bin 0 in steps), the points ordered by their ρ bin: ``order[k, starts[k, b]:starts[k,
    b + 1]]`` are the points whose ρ at that angle falls in bin ``b`` (clipped to the grid).
    Lets a line's support visit only the points near it instead of all of them."""
    n_theta = cos.size
    starts = np.zeros((n_theta, n_rho + 1), dtype=np.int64)
    order = np.empty((n_theta, x.size), dtype=np.int64)
    bins = np.empty(x.size, dtype=np.int64)
    fill = np.empty(n_rho, dtype=np.int64)
    for k in range(n_theta):
        c, s = cos[k], sin[k]
        for i in range(x.size):  # no stores to the counts here: the compiler vectorises it
            bins[i] = min(max(int(np.floor(x[i] * c + y[i] * s - rho0)), 0), n_rho - 1)
        count = starts[k]
        for i in range(x.size):
            count[bins[i] + 1] += 1
        for b in range(n_rho):
            count[b + 1] += count[b]
        fill[:] = count[:n_rho]
        points = order[k]
        for i in range(x.size):
            points[fill[bins[i]]] = i
            fill[bins[i]] += 1
    return order, starts


@numba.njit(cache=True, nogil=True)
def _near_line(theta, rho, tolerance, buckets, cos, sin, rho0, reach):
    """The slice bounds ``(k, first, last)`` into ``buckets[0][k]`` holding every point
    that can lie within ``tolerance`` of the line ``(rho, theta)``: θ bin ``k`` nearest to
    ``theta`` (modulo π, where ρ changes sign), ρ bins widened by how far ρ of a point at
    distance ``reach`` from the origin moves between ``theta`` and the bin's angle, plus
    one bin for rounding."""
    starts = buckets[1]
    n_theta = cos.size
    n_rho = starts.shape[1] - 1
    step = np.pi / n_theta
    nearest = int(np.round(theta / step))
    k = nearest % n_theta
    sign = 1.0 if (nearest - k) // n_theta % 2 == 0 else -1.0
    scale = np.hypot(cos[0], sin[0])  # 1 / ρ step
    margin = (tolerance + abs(theta - nearest * step) * reach) * scale + 1.0
    centre = sign * rho * scale - rho0
    first = min(max(int(np.floor(centre - margin)), 0), n_rho - 1)
    last = min(max(int(np.floor(centre + margin)), 0), n_rho - 1)
    return k, starts[k, first], starts[k, last + 1]


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
    x, y, orientation, check, free, rho, theta, tolerance, window, cells, stamp, on, mark, near
):
    """Mark in ``on`` (if ``mark``; cleared first) the free points supporting the line
    ``(rho, theta)``: within ``tolerance`` of it and, where ``check``, with ``orientation``
    within ``window`` of ``theta`` mod π. Returns how many 1-px cells along the line they
    cover (``cells`` holds ``stamp`` where covered; positions are offset by half its size).
    Without ``check``, ``near`` (:func:`bucket_points` and the arguments of
    :func:`_near_line`) limits the scan to the points near the line.
    """
    c, s = np.cos(theta), np.sin(theta)
    t = theta % np.pi
    offset = cells.size // 2
    covered = 0
    if mark:
        on[:] = False
    a0, a1, b0, b1 = _scan_ranges(orientation, check, theta, window)
    k = 0
    if not check:
        k, a0, a1 = _near_line(theta, rho, tolerance, *near)
    for first, last in ((a0, a1), (b0, b1)):
        for j in range(first, last):
            i = near[0][0][k, j] if not check else j
            if not free[i] or abs(x[i] * c + y[i] * s - rho) > tolerance:
                continue
            if check:
                gap = abs(orientation[i] - t)
                if min(gap, np.pi - gap) > window:
                    continue
            if mark:
                on[i] = True
            cell = int(np.floor(y[i] * c - x[i] * s)) + offset
            if cells[cell] != stamp:
                cells[cell] = stamp
                covered += 1
    return covered


@numba.njit(cache=True, nogil=True)
def line_support(x, y, orientation, check, rho, theta, tolerance, window, extent, near):
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
            near,
        )
    return counts


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
    near,
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
            x, y, orientation, check, free, r, t, tolerance, window, cells, stamp, on, True, near
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
                near,
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
