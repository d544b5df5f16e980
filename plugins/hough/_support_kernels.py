"""numba kernels of the lines' support (imported on first use: numba loads slowly): the
points within a tolerance of a line and the distinct cells they cover along it, bounds
that prune candidates (the selection of lines is in ``_select_kernels``)."""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = [
    "line_support",
    "pruned_support",
    "support_bounds",
]


@njit(cache=True, nogil=True, inline="always")
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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
