"""numba kernels of census matching, row by row (imported on first use: compiling costs time).

Block matching never builds the cost volume: each row's census costs go into a ring of
the last ``block + 1`` rows, a running sum over the ring gives each column's sum over
the block's rows (one addition and one subtraction per cost, whatever the block), a
running sum along the row gives the block sums, and the row is resolved at once
(winner take all and the right image's winners). Semi-global matching fills its volume
the same way, then aggregates its paths in two sweeps, the four paths that come from
above and from the left in a forward sweep, the other four in a backward one, each
pixel's predecessors kept in row buffers; each row is resolved as soon as the backward
sweep has finished it. All sums are integers (census bits), so the results are those of
``_kernels.py``'s volume kernels to the bit; ``cost_volume`` documents the layout.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

__all__ = [
    "census_block_match",
    "census_signatures",
    "census_volume",
    "jump_penalties",
    "resolve_row",
]


@intrinsic
def _ctpop(typingctx: Any, value: Any) -> Any:  # pragma: no cover
    """The set bits of a uint64 (LLVM's ctpop: one POPCNT instruction)."""
    signature = types.uint64(types.uint64)

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        return builder.ctpop(args[0])

    return signature, codegen


@njit(cache=True, nogil=True)
def census_signatures(image: np.ndarray, half: int) -> np.ndarray:  # pragma: no cover
    """Census signatures as ``_kernels.census`` makes them (a bit per window pixel darker
    than the centre, edge pixels repeated, row-major window order), a row at a time."""
    rows, cols = image.shape
    padded = np.empty((rows + 2 * half, cols + 2 * half), dtype=image.dtype)
    for y in range(rows + 2 * half):
        source = min(max(y - half, 0), rows - 1)
        for x in range(cols + 2 * half):
            padded[y, x] = image[source, min(max(x - half, 0), cols - 1)]
    out = np.zeros((rows, cols), dtype=np.uint64)
    for y in range(rows):
        bits = out[y]
        centre = padded[y + half, half : half + cols]
        for dy in range(2 * half + 1):
            for dx in range(2 * half + 1):
                if dy == half and dx == half:
                    continue
                other = padded[y + dy, dx : dx + cols]
                for x in range(cols):
                    bits[x] = (bits[x] << np.uint64(1)) | np.uint64(other[x] < centre[x])
    return out


@njit(cache=True, nogil=True)
def _cost_row(
    left: np.ndarray, right: np.ndarray, d_min: int, outside: int, out: np.ndarray
) -> None:  # pragma: no cover
    """``out[k, x]``: Hamming distance of left ``x`` and right ``x − d_min − k`` (``outside``
    where that leaves the image); disparity-major, so each disparity is one vector loop."""
    count, cols = out.shape
    for k in range(count):
        shift, row = d_min + k, out[k]
        start = min(max(shift, 0), cols)
        stop = max(min(cols + shift, cols), start)
        # loops from 0 over slices: a signed index from elsewhere keeps numba's
        # negative-index check in the loop, and then it does not vectorise
        row[:start] = outside
        row[stop:] = outside
        inside, lefts, rights = row[start:stop], left[start:stop], right[start - shift :]
        for i in range(stop - start):
            inside[i] = _ctpop(lefts[i] ^ rights[i])  # type: ignore[call-arg]


@njit(cache=True, nogil=True)
def _block_rows(
    left: np.ndarray, right: np.ndarray, d_min: int, count: int, outside: int, half: int
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """Row pipeline state: the ring of cost rows and the column sums of row 0."""
    rows, cols = left.shape
    ring = np.empty((2 * half + 2, count, cols), dtype=np.uint16)
    for source in range(min(half + 1, rows)):
        _cost_row(left[source], right[source], d_min, outside, ring[source % ring.shape[0]])
    columns = np.zeros((count, cols), dtype=np.uint16)
    for dy in range(-half, half + 1):
        source = ring[min(max(dy, 0), rows - 1) % ring.shape[0]]
        for k in range(count):
            for x in range(cols):
                columns[k, x] += source[k, x]
    return ring, columns


@njit(cache=True, nogil=True)
def _next_columns(
    left: np.ndarray,
    right: np.ndarray,
    d_min: int,
    outside: int,
    half: int,
    y: int,
    ring: np.ndarray,
    columns: np.ndarray,
) -> None:  # pragma: no cover
    """Column sums of row ``y − 1`` → row ``y``: add the entering row, drop the leaving one
    (modulo 2¹⁶: every sum fits)."""
    rows = left.shape[0]
    entering, leaving = min(y + half, rows - 1), max(y - half - 1, 0)
    size = ring.shape[0]
    if y + half <= rows - 1:
        _cost_row(left[entering], right[entering], d_min, outside, ring[entering % size])
    new, old = ring[entering % size].reshape(-1), ring[leaving % size].reshape(-1)
    flat = columns.reshape(-1)
    for i in range(flat.size):
        flat[i] = np.uint16(np.uint16(flat[i] + new[i]) - old[i])


@njit(cache=True, nogil=True, inline="always")
def _clamped_sum(row: np.ndarray, x: int, half: int) -> np.uint16:  # pragma: no cover
    """``Σ row[clamp(x + dx)]`` over ``|dx| ≤ half`` (an end of the row)."""
    total = np.uint16(0)
    cols = row.size
    for dx in range(-half, half + 1):
        total = np.uint16(total + row[min(max(x + dx, 0), cols - 1)])
    return total


@njit(cache=True, nogil=True, inline="always")
def _add_shifted(
    middle: np.ndarray, row: np.ndarray, first: int, taps: int, start: bool
) -> None:  # pragma: no cover
    """``middle[i] (= 0 when start) + Σ row[i + first + t]`` over ``t < taps ≤ 5``, one
    SIMD pass (the partial sum stays in a register across the taps; modulo 2¹⁶)."""
    n = middle.size
    a, b, c = row[first:], row[first + 1 :], row[first + 2 :]
    d, e = row[first + 3 :], row[first + 4 :]
    if taps == 5:
        if start:
            for i in range(n):
                middle[i] = np.uint16(a[i] + b[i] + c[i] + d[i] + e[i])
        else:
            for i in range(n):
                middle[i] = np.uint16(middle[i] + a[i] + b[i] + c[i] + d[i] + e[i])
    elif taps == 4:
        if start:
            for i in range(n):
                middle[i] = np.uint16(a[i] + b[i] + c[i] + d[i])
        else:
            for i in range(n):
                middle[i] = np.uint16(middle[i] + a[i] + b[i] + c[i] + d[i])
    elif taps == 3:
        if start:
            for i in range(n):
                middle[i] = np.uint16(a[i] + b[i] + c[i])
        else:
            for i in range(n):
                middle[i] = np.uint16(middle[i] + a[i] + b[i] + c[i])
    elif taps == 2:
        if start:
            for i in range(n):
                middle[i] = np.uint16(a[i] + b[i])
        else:
            for i in range(n):
                middle[i] = np.uint16(middle[i] + a[i] + b[i])
    elif start:
        middle[:] = a[:n]
    else:
        for i in range(n):
            middle[i] = np.uint16(middle[i] + a[i])


@njit(cache=True, nogil=True)
def _across(columns: np.ndarray, half: int, out: np.ndarray) -> None:  # pragma: no cover
    """``out[k, x] = Σ columns[k, clamp(x + dx)]`` over ``|dx| ≤ half``: inside, up to five
    shifted rows summed in one SIMD pass (two passes for a block of 9, not eight
    read-modify-write passes); the clamped ends apart."""
    count, cols = columns.shape
    inner = max(cols - half, half)
    width = 2 * half + 1
    for k in range(count):
        row, sums = columns[k], out[k]
        middle = sums[half:inner]
        for first in range(0, width, 5):
            _add_shifted(middle, row, first, min(width - first, 5), first == 0)
        for x in range(min(half, cols)):
            sums[x] = _clamped_sum(row, x, half)
        for x in range(inner, cols):
            sums[x] = _clamped_sum(row, x, half)


@njit(cache=True, nogil=True, inline="always")
def _key(cost: np.uint16, k: int) -> np.uint32:  # pragma: no cover
    """``(cost << 10) | k``: the least key is the least cost at the first disparity."""
    return np.uint32((np.uint32(cost) << np.uint32(10)) | np.uint32(k))


@njit(cache=True, nogil=True, inline="always")
def _lower(a: np.uint32, b: np.uint32) -> np.uint32:  # pragma: no cover
    """The smaller, a select on 32-bit lanes (``min`` of unsigned integers widens)."""
    return a if a < b else b


@njit(cache=True, nogil=True, inline="always")
def _least(a: np.uint16, b: np.uint16) -> np.uint16:  # pragma: no cover
    """The smaller, a select on 16-bit lanes (``min`` of unsigned integers widens)."""
    return a if a < b else b


@njit(cache=True, nogil=True)
def _winners(
    costs: np.ndarray, d_min: int, least: np.ndarray, which: np.ndarray
) -> None:  # pragma: no cover
    """``least[x]``, ``which[x]``: the first least cost of ``x`` and its ``k`` over the
    disparities whose right pixel is inside (``k ≤ x − d_min``; 65535 and 0 where none
    is): a min over the disparity rows, then the rows that reach it, last to first, each
    a select on 16-bit lanes."""
    count, cols = costs.shape
    keys = np.full(cols, 0xFFFFFFFF, dtype=np.uint32)
    for k in range(count):
        start = max(0, min(d_min + k, cols))
        row, found = costs[k, start:], keys[start:]
        for i in range(cols - start):
            found[i] = _lower(found[i], _key(row[i], k))
    for x in range(cols):
        least[x] = np.uint16(min(keys[x] >> np.uint32(10), np.uint32(0xFFFF)))
        which[x] = np.uint16(keys[x] & np.uint32(1023)) if keys[x] != np.uint32(0xFFFFFFFF) else 0


@njit(cache=True, nogil=True)
def _rivals(
    costs: np.ndarray, d_min: int, which: np.ndarray, rivals: np.ndarray
) -> None:  # pragma: no cover
    """``rivals[x]``: least cost of ``x`` more than one step from its winner (65535 when
    there is none: the caller tells that case apart), on 16-bit lanes."""
    count, cols = costs.shape
    rivals[:] = 0xFFFF
    for k in range(count):
        start = max(0, min(d_min + k, cols))
        row, winners, found = costs[k, start:], which[start:], rivals[start:]
        for i in range(cols - start):
            offset = np.uint16(np.uint16(k + 1) - winners[i])
            # |k − best| ≤ 1 (a negative offset wraps high): all ones, else none
            mask = np.uint16(np.uint16(0) - np.uint16(offset <= np.uint16(2)))
            found[i] = _least(found[i], np.uint16(row[i] | mask))


@njit(cache=True, nogil=True)
def _right_winners(costs: np.ndarray, d_min: int, out: np.ndarray) -> None:  # pragma: no cover
    """``_kernels.right_disparity`` of one row: right ``x_r`` takes the first least of
    ``costs[k, x_r + d_min + k]`` over the ``k`` that stay inside (NaN if none)."""
    count, cols = costs.shape
    keys = np.full(cols, 0xFFFFFFFF, dtype=np.uint32)
    for k in range(count):
        shift = d_min + k
        start = min(max(0, -shift), cols)
        stop = max(min(cols, cols - shift), start)
        row, found = costs[k, start + shift :], keys[start:stop]
        for i in range(stop - start):
            found[i] = _lower(found[i], _key(row[i], k))
    for xr in range(cols):
        found = keys[xr] != np.uint32(0xFFFFFFFF)
        out[xr] = np.float32(d_min + np.int64(keys[xr] & np.uint32(1023))) if found else np.nan


@njit(cache=True, nogil=True)
def resolve_row(
    costs: np.ndarray,
    d_min: int,
    uniqueness: float,
    subpixel: bool,
    out: np.ndarray,
    right_out: np.ndarray,
) -> None:  # pragma: no cover
    """One row's winners, left (``_kernels.winner_take_all``: the first least cost, refused
    at the range's ends or when a rival more than a step away is within ``uniqueness``;
    the parabola's vertex) and right, from its disparity-major costs ``(count, cols)``."""
    count, cols = costs.shape
    least = np.empty(cols, dtype=np.uint16)
    which = np.empty(cols, dtype=np.uint16)
    rivals = np.empty(cols, dtype=np.uint16)
    _winners(costs, d_min, least, which)
    _rivals(costs, d_min, which, rivals)
    for x in range(cols):
        top = min(count - 1, x - d_min)
        best_k = np.int64(which[x])
        if top < 0 or best_k == top or best_k == 0:
            out[x] = np.nan
            continue
        best = float(least[x])
        # a disparity more than one step from the winner exists (else no rival)
        second = float(rivals[x]) if best_k >= 2 or best_k + 2 <= top else np.inf
        if second < best + abs(best) * uniqueness:
            out[x] = np.nan
            continue
        value = np.float32(best_k)
        if subpixel:
            below = float(costs[best_k - 1, x])
            above = float(costs[best_k + 1, x])
            curvature = below - 2.0 * best + above
            if curvature > 0:
                value += np.float32(0.5 * (below - above) / curvature)
        out[x] = value + d_min
    _right_winners(costs, d_min, right_out)


@njit(cache=True, nogil=True)
def census_block_match(
    left: np.ndarray,
    right: np.ndarray,
    d_min: int,
    count: int,
    outside: int,
    half: int,
    uniqueness: float,
    subpixel: bool,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """Left and right winner-take-all disparities of census signatures ``left``, ``right``,
    costs summed over ``(2 half + 1)²`` blocks (edge pixels repeated), without a volume."""
    rows, cols = left.shape
    out = np.empty((rows, cols), dtype=np.float32)
    right_out = np.empty((rows, cols), dtype=np.float32)
    ring, columns = _block_rows(left, right, d_min, count, outside, half)
    summed = np.empty((count, cols), dtype=np.uint16)
    for y in range(rows):
        if y > 0:
            _next_columns(left, right, d_min, outside, half, y, ring, columns)
        _across(columns, half, summed)
        resolve_row(summed, d_min, uniqueness, subpixel, out[y], right_out[y])
    return out, right_out


@njit(cache=True, nogil=True)
def census_volume(
    left: np.ndarray, right: np.ndarray, d_min: int, count: int, outside: int, half: int
) -> np.ndarray:  # pragma: no cover
    """The census cost volume summed over ``(2 half + 1)²`` blocks, uint16, disparity-major
    ``(rows, count, cols)`` (``box_sum(census_costs(...), half)`` with its last two axes
    swapped, by running sums)."""
    rows, cols = left.shape
    volume = np.empty((rows, count, cols), dtype=np.uint16)
    ring, columns = _block_rows(left, right, d_min, count, outside, half)
    for y in range(rows):
        if y > 0:
            _next_columns(left, right, d_min, outside, half, y, ring, columns)
        _across(columns, half, volume[y])
    return volume


@njit(cache=True, nogil=True)
def jump_penalties(
    image: np.ndarray, steps: np.ndarray, p1: float, p2: float, edge: float
) -> np.ndarray:  # pragma: no cover
    """``uint16(max(P1, P2 / (1 + |I(p) − I(p − r)| / edge)))`` per path ``r`` of ``steps``,
    edge pixels repeated, computed in float64 as ``_disparity._jumps`` does (edge ≤ 0:
    P2 everywhere)."""
    rows, cols = image.shape
    out = np.empty((steps.shape[0], rows, cols), dtype=np.uint16)
    for i in range(steps.shape[0]):
        step_y, step_x = steps[i, 0], steps[i, 1]
        for y in range(rows):
            yb = min(max(y - step_y, 0), rows - 1)
            for x in range(cols):
                if edge <= 0:
                    out[i, y, x] = np.uint16(p2)
                    continue
                xb = min(max(x - step_x, 0), cols - 1)
                change = abs(np.float64(image[y, x]) - np.float64(image[yb, xb]))
                out[i, y, x] = np.uint16(max(p1, p2 / (1.0 + change / edge)))
    return out


@njit(cache=True, nogil=True)
def left_right_keep(
    disparity: np.ndarray, right_disparity: np.ndarray, tolerance: float
) -> np.ndarray:  # pragma: no cover
    """``_disparity.left_right_check`` pixel by pixel: a left pixel is kept when the right
    pixel at ``x − ⌊d⌋`` or at ``x − ⌈d⌉`` (inside the image) holds a disparity within
    ``tolerance`` of ``⌊d⌋`` (resp. ``⌈d⌉``); NaN otherwise."""
    rows, cols = disparity.shape
    out = np.empty((rows, cols), dtype=np.float32)
    for y in range(rows):
        for x in range(cols):
            value = disparity[y, x]
            keep = False
            if np.isfinite(value):
                for whole in (np.floor(value), np.ceil(value)):
                    xr = x - np.int64(whole)
                    if 0 <= xr < cols:
                        keep |= bool(np.float32(abs(whole - right_disparity[y, xr])) <= tolerance)
            out[y, x] = value if keep else np.nan
    return out
