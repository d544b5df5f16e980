"""numba kernels of circle voting and of peak picking (imported on first use: numba loads slowly).

Votes go straight into the accumulator (no ``radii × points`` index arrays), one radius
at a time folded into the best score over radii (never the whole stack), window maxima are
taken along rows then down columns, and the greedy suppression of close peaks is one
loop. The spreading of the votes by a Gaussian computes only the columns near a vote
(votes are sparse), four pairs of taps a pass. The arithmetic is the array form's and
``smooth_gaussian``'s, operation for operation, so results are the same to the bit.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit
from ..shared.separable_kernels import _accumulate

__all__ = [
    "best_over_radii",
    "fold_plane",
    "greedy_suppression",
    "vote_circles",
    "vote_plane",
    "window_maxima",
]

CHUNK = 64  # columns: the spreading skips the runs of CHUNK columns that hold no vote nearby


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
def fold_plane(plane, k, last, spread, circumference, best, k_best, below, above, previous):
    """Fold the votes of radius ``k`` (of ``0..last``) into the running maximum over radii:
    the score ``plane · spread / circumference``; ``best`` and ``k_best`` the largest score
    and its first radius, ``below`` and ``above`` the scores of the radii either side of it
    (its own at the ends), ``previous`` the scores of radius ``k - 1``. Equals
    ``scores.max(0)``, ``argmax(0)`` and ``scores[k ± 1]`` of the whole stack of scores,
    without holding it. Selections without branches, one row at a time, every value
    loaded before any is stored, so that the compiler makes SIMD code of them (a
    selection that reads an array it also writes, ``high[x] = score if … else
    high[x]``, kept the loop scalar: 3.6 of the coins' 11 ms)."""  # pragma: no cover
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
            w, t, h, lo, b = which[x], top[x], high[x], low[x], before[x]
            better = score > t
            high[x] = score if w == k - 1 else h
            top[x] = score if better else t
            which[x] = k if better else w
            low[x] = b if better else lo
            before[x] = score
        if k == last:
            for x in range(width):
                high[x] = top[x] if which[x] == k else high[x]


@njit(cache=True, nogil=True)
def _votes_by_row(rows, cols, ux, uy, radii, signs, height, width):  # pragma: no cover
    """Every vote of :func:`vote_plane` for every radius, sorted by radius and row:
    columns ``xs[first[k, y] : first[k, y + 1]]`` are the votes of radius ``k`` in row
    ``y`` (same rounding as :func:`vote_plane`)."""
    count = np.zeros((radii.size, height + 1), dtype=np.int64)
    cells = np.empty((radii.size * signs.size * rows.size, 3), dtype=np.int64)
    n = 0
    for k in range(radii.size):
        for sign in signs:
            step = sign * radii[k]
            for i in range(rows.size):
                cx = int(np.rint(cols[i] + step * ux[i]))
                cy = int(np.rint(rows[i] + step * uy[i]))
                if 0 <= cx < width and 0 <= cy < height:
                    cells[n, 0], cells[n, 1], cells[n, 2] = k, cy, cx
                    count[k, cy + 1] += 1
                    n += 1
    # running count over radius then row: ``first[k, height]`` ends radius k, and
    # ``first[k + 1, 0]`` (no vote counted there) starts radius k + 1 at the same place
    first = np.cumsum(count.reshape(-1)).reshape(count.shape)
    fill = first.copy()
    xs = np.empty(n, dtype=np.int64)
    for i in range(n):
        k, cy = cells[i, 0], cells[i, 1]
        xs[fill[k, cy]] = cells[i, 2]
        fill[k, cy] += 1
    return first, xs


@njit(cache=True, nogil=True)
def _runs(occupied, runs):  # pragma: no cover
    """``(start, stop)`` chunk indices of the runs of True in ``occupied`` into the rows of
    ``runs`` (``(occupied.size + 1) // 2`` rows at least); returns their count."""
    count = 0
    c = 0
    while c < occupied.size:
        if occupied[c]:
            stop = c
            while stop < occupied.size and occupied[stop]:
                stop += 1
            runs[count, 0], runs[count, 1] = c, stop
            count += 1
            c = stop
        c += 1
    return count


@njit(cache=True, nogil=True, fastmath={"contract"})
def _four_pairs(out, lines, row, column, down, across, taps, j):  # pragma: no cover
    """The pairs ``j … j + 3`` of :func:`_symmetric_pass`: ``out[x] += taps[far] (first[x]
    + last[x])`` in order, the sum held in a register between them, each contracted to an
    FMA as ``correlate_both``'s fastmath ``_accumulate`` has it; one pass instead of four.
    (The centre's product stays a pass of its own: in this loop the compiler could fuse
    it with the first pair's instead, another rounding.)"""
    size = taps.size
    n = out.size

    def tap(i):  # the line under tap i
        return lines[row + i * down, column + i * across : column + i * across + n]

    a0, a1, a2, a3 = tap(size - 1 - j), tap(size - 2 - j), tap(size - 3 - j), tap(size - 4 - j)
    b0, b1, b2, b3 = tap(j), tap(j + 1), tap(j + 2), tap(j + 3)
    w0, w1, w2, w3 = taps[size - 1 - j], taps[size - 2 - j], taps[size - 3 - j], taps[size - 4 - j]
    for x in range(n):
        v = out[x]
        v = v + w0 * (a0[x] + b0[x])
        v = v + w1 * (a1[x] + b1[x])
        v = v + w2 * (a2[x] + b2[x])
        v = v + w3 * (a3[x] + b3[x])
        out[x] = v


@njit(cache=True, nogil=True)
def _symmetric_pass(out, lines, row, column, down, across, taps):  # pragma: no cover
    """``out[x] = Σ_i taps[i] · lines[row + i·down, column + i·across + x]`` for symmetric
    ``taps``, as ``correlate_both``'s passes compute it: the centre tap's product, then
    ``+ taps[far] (first + last)`` for the pairs ``far = size − 1 − j``, ``j = 0, 1, …``
    (four at a time by :func:`_four_pairs`, the rest by ``_accumulate``)."""
    size = taps.size
    half = size // 2
    n = out.size
    first = column + half * across
    centre = lines[row + half * down, first : first + n]
    for x in range(n):
        out[x] = taps[half] * centre[x]
    j = 0
    while j + 4 <= half:
        _four_pairs(out, lines, row, column, down, across, taps, j)
        j += 4
    for k in range(j, half):
        far = size - 1 - k
        one = lines[row + far * down, column + far * across : column + far * across + n]
        other = lines[row + k * down, column + k * across : column + k * across + n]
        _accumulate(out, one, other, taps[far], 1)


@njit(cache=True, nogil=True)
def _spread_row(plane, r, near, taps, line, row, runs, spans):  # pragma: no cover
    """Output row ``r`` of ``correlate_both(plane, taps, 1, …, "constant")`` into ``row``:
    the column pass into the padded ``line`` (zero, and left zero), then the row pass,
    each over the runs of :data:`CHUNK` columns that can be nonzero only. ``near[c]``:
    chunk ``c`` of ``plane``'s rows ``r … r + taps.size − 1`` holds a vote. Elsewhere the
    value is zero: every term there is a product of a tap by zero, and a term ``w (a +
    b)`` of zero added to a sum leaves it as it is (an FMA too), so the skipped terms and
    columns change no bit of the others. Each value computed takes the same operations,
    in the same order, as ``correlate_both`` (:func:`_symmetric_pass`)."""
    half = taps.size // 2
    cols = row.size
    centre = line[half : half + cols]
    count = _runs(near, runs)
    for run in range(count):
        x0, x1 = runs[run, 0] * CHUNK, min(runs[run, 1] * CHUNK, cols)
        _symmetric_pass(centre[x0:x1], plane, r, x0, 1, 0, taps)
    reach = (half + CHUNK - 1) // CHUNK  # chunks a row-pass value reaches either side
    wide = 0
    for run in range(count):  # the runs widened by reach, merged where they meet
        start, stop = max(runs[run, 0] - reach, 0), min(runs[run, 1] + reach, near.size)
        if wide > 0 and start <= spans[wide - 1, 1]:
            spans[wide - 1, 1] = stop
        else:
            spans[wide, 0], spans[wide, 1] = start, stop
            wide += 1
    row[:] = 0.0
    padded = line.reshape(1, -1)
    for run in range(wide):
        x0, x1 = spans[run, 0] * CHUNK, min(spans[run, 1] * CHUNK, cols)
        _symmetric_pass(row[x0:x1], padded, 0, x0, 0, 1, taps)
    for run in range(count):
        centre[runs[run, 0] * CHUNK : min(runs[run, 1] * CHUNK, cols)] = 0.0


@njit(cache=True, nogil=True)
def _band_votes(first, xs, k, top, low_row, high_row, half, plane, occupied):  # pragma: no cover
    """Radius ``k``'s votes in rows ``low_row … high_row − 1`` added into ``plane`` (zero;
    row ``y`` at ``y − top + half``), and the chunks of :data:`CHUNK` columns they fall
    in marked in ``occupied``."""
    occupied[:] = False
    for y in range(low_row, high_row):
        for i in range(first[k, y], first[k, y + 1]):
            plane[y - (top - half), xs[i]] += 1.0
            occupied[y - (top - half), xs[i] // CHUNK] = True


@njit(cache=True, nogil=True)
def best_over_radii(voters, radii, signs, spread, shape, taps):  # pragma: no cover
    """:func:`vote_plane`, the spreading of its votes and :func:`fold_plane` for every
    radius in one call: ``voters`` the points' ``(rows, cols, ux, uy)``, ``taps`` the
    symmetric taps of the spreading along both axes, zero outside the image
    (``shared.separable_kernels.correlate_both``; none when empty). Returns ``(best,
    k_best, below, above)``.

    A band of rows at a time, every radius folded into it before the next band, so that
    the band's votes, spread votes and running maxima stay in the processor's cache
    (radius by radius over the whole image streamed seven image-sized arrays per
    radius); each output row is computed by the same arithmetic, so the results are
    those of whole planes to the bit. Votes are sparse (2.7 % of the coins' cells hold
    one): the spreading computes only the columns near one (:func:`_spread_row`), and
    the plane is cleared where votes were added, not whole."""
    rows, cols, ux, uy = voters
    height, width = shape
    half = taps.size // 2
    first, xs = _votes_by_row(rows, cols, ux, uy, radii, signs, height, width)
    band = 16
    plane = np.zeros((band + 2 * half, width))
    occupied = np.zeros((band + 2 * half, (width + CHUNK - 1) // CHUNK), dtype=np.bool_)
    near = np.empty(occupied.shape[1], dtype=np.bool_)
    runs = np.empty(((near.size + 1) // 2, 2), dtype=np.int64)
    spans = np.empty_like(runs)
    line = np.zeros(width + 2 * half)
    spread_votes = np.empty((band, width))
    best = np.empty((height, width))
    below = np.empty((height, width))
    above = np.empty((height, width))
    previous = np.empty((height, width))
    k_best = np.zeros((height, width), dtype=np.int64)
    for top in range(0, height, band):
        bottom = min(top + band, height)
        low_row, high_row = max(top - half, 0), min(bottom + half, height)
        for k in range(radii.size):
            _band_votes(first, xs, k, top, low_row, high_row, half, plane, occupied)
            votes = plane[half : half + bottom - top]
            if taps.size > 0:
                votes = spread_votes[: bottom - top]
                for r in range(bottom - top):
                    for c in range(near.size):
                        near[c] = occupied[r : r + taps.size, c].any()
                    _spread_row(plane, r, near, taps, line, votes[r], runs, spans)
            circumference = 2.0 * np.pi * radii[k]
            fold_plane(
                votes, k, radii.size - 1, spread, circumference, best[top:bottom],
                k_best[top:bottom], below[top:bottom], above[top:bottom],
                previous[top:bottom],
            )  # fmt: skip
            for y in range(low_row, high_row):  # clear the votes added
                for i in range(first[k, y], first[k, y + 1]):
                    plane[y - (top - half), xs[i]] = 0.0
    return best, k_best, below, above


@njit(cache=True, nogil=True)
def _shifted_max(out, line, shift):  # pragma: no cover
    """``out[x] = max(out[x], line[clip(x + shift, 0, size - 1)])``: one shift of a window,
    the edge replicated; the clipped ends apart so the middle is one SIMD loop."""
    size = line.size
    if shift < 0:
        for x in range(min(-shift, size)):
            out[x] = max(out[x], line[0])
        for x in range(-shift, size):
            out[x] = max(out[x], line[x + shift])
    else:
        for x in range(size - shift):
            out[x] = max(out[x], line[x + shift])
        for x in range(max(size - shift, 0), size):
            out[x] = max(out[x], line[size - 1])


@njit(cache=True, nogil=True)
def window_maxima(values, size, floor):  # pragma: no cover
    """``(row, col)`` of the cells equal to the maximum of their ``size × size`` window
    (the image edge replicated, as ``maximum_filter(mode="nearest")``) and above
    ``floor``, row-major. The maximum is taken along rows then down columns, each a
    maximum of shifted whole rows (the order of a maximum does not change it; the values
    hold no NaN, being scores)."""
    height, width = values.shape
    before = size // 2
    after = size - 1 - before
    across = values.copy()
    for y in range(height):
        for shift in range(-before, after + 1):
            if shift != 0:
                _shifted_max(across[y], values[y], shift)
    window = np.empty(width)
    rows = []
    cols = []
    for y in range(height):
        low, high = max(y - before, 0), min(y + after, height - 1)
        window[:] = across[low]
        for v in range(low + 1, high + 1):
            row = across[v]
            for x in range(width):
                window[x] = max(window[x], row[x])
        for x in range(width):
            value = values[y, x]
            if value > floor and value == window[x]:
                rows.append(y)
                cols.append(x)
    out = np.empty((len(rows), 2), dtype=np.int64)
    for i in range(len(rows)):
        out[i, 0] = rows[i]
        out[i, 1] = cols[i]
    return out


@njit(cache=True, nogil=True)
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
