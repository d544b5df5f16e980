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
def _ctpop(typingctx, value):  # type: ignore[no-untyped-def]  # pragma: no cover
    """The set bits of a uint64 (LLVM's ctpop: one POPCNT instruction)."""
    signature = types.uint64(types.uint64)

    def codegen(context, builder, sig, args):  # type: ignore[no-untyped-def]
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
    """``out[x, k]``: Hamming distance of left ``x`` and right ``x − d_min − k`` (``outside``
    where that leaves the image)."""
    cols, count = out.shape
    for x in range(cols):
        signature, row = left[x], out[x]
        start, stop = max(0, x - d_min - cols + 1), min(count, max(0, x - d_min + 1))
        for k in range(min(start, count)):
            row[k] = outside
        for k in range(start, stop):
            row[k] = _ctpop(signature ^ right[x - d_min - k])
        for k in range(max(stop, start), count):
            row[k] = outside


@njit(cache=True, nogil=True)
def _box_rows(
    left: np.ndarray, right: np.ndarray, d_min: int, outside: int, half: int, ring: np.ndarray
) -> None:  # pragma: no cover
    """Fill ``ring`` with the cost rows the first output row's column sums need."""
    rows = left.shape[0]
    for source in range(min(half + 1, rows)):
        _cost_row(left[source], right[source], d_min, outside, ring[source % ring.shape[0]])


@njit(cache=True, nogil=True)
def _block_rows(
    left: np.ndarray, right: np.ndarray, d_min: int, count: int, outside: int, half: int
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """Row pipeline state: the ring of cost rows and the column sums of row 0."""
    rows, cols = left.shape
    ring = np.empty((2 * half + 2, cols, count), dtype=np.uint16)
    _box_rows(left, right, d_min, outside, half, ring)
    columns = np.zeros((cols, count), dtype=np.uint16)
    for dy in range(-half, half + 1):
        source = ring[min(max(dy, 0), rows - 1) % ring.shape[0]]
        for x in range(cols):
            for k in range(count):
                columns[x, k] += source[x, k]
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
    """Column sums of row ``y − 1`` → row ``y``: add the entering row, drop the leaving one."""
    rows = left.shape[0]
    entering, leaving = min(y + half, rows - 1), max(y - half - 1, 0)
    size = ring.shape[0]
    if y + half <= rows - 1:
        _cost_row(left[entering], right[entering], d_min, outside, ring[entering % size])
    new, old = ring[entering % size], ring[leaving % size]
    cols, count = columns.shape
    for x in range(cols):
        for k in range(count):
            columns[x, k] = np.uint16(np.uint16(columns[x, k] + new[x, k]) - old[x, k])


@njit(cache=True, nogil=True)
def _across(columns: np.ndarray, half: int, out: np.ndarray) -> None:  # pragma: no cover
    """``out[x] = Σ columns[clamp(x + dx)]`` over ``|dx| ≤ half``, as a running sum."""
    cols, count = columns.shape
    running = np.zeros(count, dtype=np.uint16)  # modulo 2¹⁶: each sum fits
    for dx in range(-half, half + 1):
        source = min(max(dx, 0), cols - 1)
        for k in range(count):
            running[k] = np.uint16(running[k] + columns[source, k])
    for x in range(cols):
        for k in range(count):
            out[x, k] = running[k]
        new, old = min(x + half + 1, cols - 1), max(x - half, 0)
        for k in range(count):
            running[k] = np.uint16(np.uint16(running[k] + columns[new, k]) - columns[old, k])


@njit(cache=True, nogil=True, inline="always")
def _least(costs: np.ndarray, start: int, stop: int) -> int:  # pragma: no cover
    """min of ``costs[start:stop]`` (a large value if empty), branch-free so it vectorises."""
    low = np.iinfo(np.int64).max
    for k in range(start, stop):
        low = min(low, np.int64(costs[k]))
    return low


@njit(cache=True, nogil=True, inline="always")
def _first_least(
    costs: np.ndarray, start: int, stop: int, offset: int, stride: int
) -> np.uint32:  # pragma: no cover
    """``(least << 10) | k`` of the first least of ``costs[offset + k stride]``, k in
    [start, stop): one min over keys, so it vectorises (k < 1024, costs < 2²²)."""
    low = np.uint32(0xFFFFFFFF)
    for k in range(start, stop):
        key = (np.uint32(costs[offset + k * stride]) << np.uint32(10)) | np.uint32(k)
        low = min(low, key)
    return low


@njit(cache=True, nogil=True)
def _winner(
    costs: np.ndarray, x: int, d_min: int, uniqueness: float, subpixel: bool
) -> float:  # pragma: no cover
    """``_kernels.winner_take_all`` of one pixel (the same values; NaN if refused): the
    first least cost, its rivals more than a step away, the parabola's vertex."""
    top = min(costs.size - 1, x - d_min)
    if top < 0:
        return np.nan
    key = _first_least(costs, 0, top + 1, 0, 1)
    best_k = int(key & 1023)
    best = float(key >> 10)
    if best_k == top or best_k == 0:
        return np.nan
    rival = min(_least(costs, 0, best_k - 1), _least(costs, best_k + 2, top + 1))
    second = float(rival) if rival < np.iinfo(np.int64).max else np.inf
    if second < best + abs(best) * uniqueness:
        return np.nan
    value = np.float32(best_k)
    if subpixel:
        below = float(costs[best_k - 1])
        above = float(costs[best_k + 1])
        curvature = below - 2.0 * best + above
        if curvature > 0:
            value += np.float32(0.5 * (below - above) / curvature)
    return np.float32(value + d_min)


@njit(cache=True, nogil=True)
def _right_winners(costs: np.ndarray, d_min: int, out: np.ndarray) -> None:  # pragma: no cover
    """``_kernels.right_disparity`` of one row: right ``x_r`` takes the first least of
    ``costs[x_r + d_min + k, k]`` over the ``k`` that stay inside (NaN if none)."""
    cols, count = costs.shape
    flat = costs.reshape(-1)
    for xr in range(cols):
        start, stop = max(0, -xr - d_min), min(count, cols - xr - d_min)
        if start >= stop:
            out[xr] = np.nan
            continue
        key = _first_least(flat, start, stop, (xr + d_min) * count, count + 1)
        out[xr] = np.float32(d_min + int(key & 1023))


@njit(cache=True, nogil=True)
def resolve_row(
    costs: np.ndarray,
    d_min: int,
    uniqueness: float,
    subpixel: bool,
    out: np.ndarray,
    right_out: np.ndarray,
) -> None:  # pragma: no cover
    """One row's winners (left) and the right image's winners from the same costs."""
    for x in range(costs.shape[0]):
        out[x] = _winner(costs[x], x, d_min, uniqueness, subpixel)
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
    summed = np.empty((cols, count), dtype=np.uint16)
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
    """The census cost volume summed over ``(2 half + 1)²`` blocks, uint16 (what
    ``box_sum(census_costs(...), half)`` gives, by running sums)."""
    rows, cols = left.shape
    volume = np.empty((rows, cols, count), dtype=np.uint16)
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
                        keep |= np.float32(abs(whole - right_disparity[y, xr])) <= tolerance
            out[y, x] = value if keep else np.nan
    return out
