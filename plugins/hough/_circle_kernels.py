"""numba kernels of circle voting and of peak picking (imported on first use: numba loads slowly).

Votes go straight into the accumulator (no ``radii × points`` index arrays), one radius
at a time folded into the best score over radii (never the whole stack), window maxima are
taken along rows then down columns, and the greedy suppression of close peaks is one
loop. The arithmetic is the array form's, operation for operation, so results are the
same to the bit.
"""

from __future__ import annotations

import numba
import numpy as np

from ..shared.separable_kernels import correlate_both

__all__ = [
    "best_over_radii",
    "fold_plane",
    "greedy_suppression",
    "vote_circles",
    "vote_plane",
    "window_maxima",
]


@numba.njit(cache=True, nogil=True)
def vote_circles(rows, cols, ux, uy, radii, signs, height, width):  # pragma: no cover
    """Accumulator ``(len(radii), height, width)``: point ``i`` votes 1 at
    ``rint((col, row) + sign · r · u_i)`` for every radius and sign, when inside."""
    votes = np.zeros((radii.size, height, width))
    for sign in signs:
        for k in range(radii.size):
            step = sign * radii[k]
            for i in range(rows.size):
                cx = int(np.rint(cols[i] + step * ux[i]))
                cy = int(np.rint(rows[i] + step * uy[i]))
                if 0 <= cx < width and 0 <= cy < height:
                    votes[k, cy, cx] += 1.0
    return votes


@numba.njit(cache=True, nogil=True)
def vote_plane(rows, cols, ux, uy, radius, signs, plane):  # pragma: no cover
    """:func:`vote_circles` for one radius, into ``plane`` (cleared first)."""
    height, width = plane.shape
    plane[:] = 0.0
    for sign in signs:
        step = sign * radius
        for i in range(rows.size):
            cx = int(np.rint(cols[i] + step * ux[i]))
            cy = int(np.rint(rows[i] + step * uy[i]))
            if 0 <= cx < width and 0 <= cy < height:
                plane[cy, cx] += 1.0
    return plane


@numba.njit(cache=True, nogil=True)
def fold_plane(plane, k, last, spread, circumference, best, k_best, below, above, previous):
    """Fold the votes of radius ``k`` (of ``0..last``) into the running maximum over radii:
    the score ``plane · spread / circumference``; ``best`` and ``k_best`` the largest score
    and its first radius, ``below`` and ``above`` the scores of the radii either side of it
    (its own at the ends), ``previous`` the scores of radius ``k - 1``. Equals
    ``scores.max(0)``, ``argmax(0)`` and ``scores[k ± 1]`` of the whole stack of scores,
    without holding it. Selections without branches, one row at a time, so that the
    compiler makes SIMD code of them."""  # pragma: no cover
    height, width = plane.shape
    for y in range(height):
        votes, top, which = plane[y], best[y], k_best[y]
        low, high, before = below[y], above[y], previous[y]
        if k == 0:
            for x in range(width):
                score = votes[x] * spread / circumference
                top[x] = score
                which[x] = 0
                low[x] = score
                high[x] = score if last == 0 else high[x]
                before[x] = score
            continue
        for x in range(width):
            score = votes[x] * spread / circumference
            high[x] = score if which[x] == k - 1 else high[x]
            better = score > top[x]
            top[x] = score if better else top[x]
            which[x] = k if better else which[x]
            low[x] = before[x] if better else low[x]
            before[x] = score
        if k == last:
            for x in range(width):
                high[x] = top[x] if which[x] == k else high[x]


@numba.njit(cache=True, nogil=True)
def best_over_radii(voters, radii, signs, spread, shape, smoothing):  # pragma: no cover
    """:func:`vote_plane`, the spreading of its votes and :func:`fold_plane` for every
    radius in one call: ``voters`` the points' ``(rows, cols, ux, uy)``, ``smoothing``
    the arguments of ``shared.separable_kernels.correlate_both`` after the image and the
    output (no spreading when its taps are empty). Returns ``(best, k_best, below,
    above)``."""
    rows, cols, ux, uy = voters
    height, width = shape
    plane = np.empty((height, width))
    spread_votes = np.empty((height, width))
    best = np.empty((height, width))
    below = np.empty((height, width))
    above = np.empty((height, width))
    previous = np.empty((height, width))
    k_best = np.zeros((height, width), dtype=np.int64)
    taps, symmetry, row_index, column_index = smoothing
    last = radii.size - 1
    for k in range(radii.size):
        vote_plane(rows, cols, ux, uy, radii[k], signs, plane)
        votes = plane
        if taps.size > 0:
            correlate_both(
                plane, taps, symmetry, row_index, taps, symmetry, column_index, spread_votes
            )
            votes = spread_votes
        circumference = 2.0 * np.pi * radii[k]
        fold_plane(votes, k, last, spread, circumference, best, k_best, below, above, previous)
    return best, k_best, below, above


@numba.njit(cache=True, nogil=True)
def window_maxima(values, size, floor):  # pragma: no cover
    """``(row, col)`` of the cells equal to the maximum of their ``size × size`` window
    (the image edge replicated, as ``maximum_filter(mode="nearest")``) and above
    ``floor``, row-major."""
    height, width = values.shape
    before = size // 2
    after = size - 1 - before
    across = np.empty((height, width))
    for y in range(height):
        for x in range(width):
            best = values[y, max(x - before, 0)]
            for u in range(max(x - before, 0), min(x + after, width - 1) + 1):
                best = max(best, values[y, u])
            across[y, x] = best
    rows = []
    cols = []
    for y in range(height):
        for x in range(width):
            value = values[y, x]
            if not value > floor:
                continue
            best = across[max(y - before, 0), x]
            for v in range(max(y - before, 0), min(y + after, height - 1) + 1):
                best = max(best, across[v, x])
            if value == best:
                rows.append(y)
                cols.append(x)
    out = np.empty((len(rows), 2), dtype=np.int64)
    for i in range(len(rows)):
        out[i, 0] = rows[i]
        out[i, 1] = cols[i]
    return out


@numba.njit(cache=True, nogil=True)
def greedy_suppression(positions, order, min_distance, limit):  # pragma: no cover
    """Indices from ``order`` (strongest first) kept when at least ``min_distance``
    (Euclidean) from every index kept before, at most ``limit``."""
    kept = np.empty(min(limit, order.size), dtype=np.intp)
    count = 0
    for index in order:
        if count == limit:
            break
        close = False
        for j in range(count):
            total = 0.0
            for d in range(positions.shape[1]):
                gap = positions[kept[j], d] - positions[index, d]
                total += gap * gap
            if np.sqrt(total) < min_distance:
                close = True
                break
        if not close:
            kept[count] = index
            count += 1
    return kept[:count]
