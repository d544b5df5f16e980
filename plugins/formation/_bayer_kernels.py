"""numba kernel of demosaicking (imported on first use: compiling costs time).

Every output value is a short list of taps ``(dy, dx, weight)`` chosen by the pixel's
place in the 2×2 tile and the channel (``_bayer.py`` builds the lists), read from the
mosaic padded by ``numpy.pad``'s ``reflect`` rule (which keeps the tile's parity). The
array formulas this replaces formed each tap's product in float64 (the weights are
dyadic, so it is exact) and added it to a float32 sum, taps in the same order; taps on
samples of another colour, which added zeros, are left out.

A weight that is a power of two (all of bilinear's, 15 of Malvar's 20 a pixel) gives a
product that is exact in float32 too, and the float64 sum of two float32 numbers rounded
to float32 is their float32 sum (53 ≥ 2·24 + 2 bits: the double rounding is innocuous),
so those taps are added in float32, eight lanes to a SIMD step and no conversions, with
the same bits. The others (5/8, 3/16, 3/4) keep the float64 product. A product can only
lose bits in float32 below the normal range: an output row whose 5×5 windows read a value
in (0, 2⁻¹⁰⁰) takes the float64 path for every tap (each value depends on its own window
only, so the other rows keep the float32 path and their bits).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["demosaic_taps"]

TINY = 2.0**-100  # below it, a product by a weight ≥ 1/16 could leave float32's normal range


@njit(cache=True, nogil=True)
def _mirror(index: int, length: int) -> int:  # pragma: no cover
    """``numpy.pad``'s ``reflect`` (``c b | a b c``) for an index at most a length away."""
    return -index if index < 0 else (2 * (length - 1) - index if index >= length else index)


@njit(cache=True, nogil=True)
def _every_second(source: np.ndarray, first: int, out: np.ndarray) -> None:  # pragma: no cover
    """``out[k] = source[mirror(first + 2k)]``: the ends by the rule, the rest one strided
    loop."""
    cols = source.size
    low = 0
    while low < out.size and first + 2 * low < 0:
        out[low] = source[_mirror(first + 2 * low, cols)]
        low += 1
    high = out.size
    while high > low and first + 2 * (high - 1) >= cols:
        high -= 1
        out[high] = source[_mirror(first + 2 * high, cols)]
    for k in range(low, high):
        out[k] = source[first + 2 * k]


@njit(cache=True, nogil=True)
def _fill_padded(
    raw: np.ndarray, p: int, even: np.ndarray, odd: np.ndarray, tiny: np.ndarray
) -> None:  # pragma: no cover
    """Row ``p`` of ``raw`` padded by 2 (``numpy.pad``'s ``reflect``), its even columns into
    ``even[p % 5]`` and its odd ones into ``odd[p % 5]``; ``tiny[p % 5]``: whether it holds
    a value in (0, TINY) in magnitude (checked while the row is in cache)."""
    source = raw[_mirror(p - 2, raw.shape[0])]
    _every_second(source, -2, even[p % 5])
    _every_second(source, -1, odd[p % 5])
    found = 0
    for x in range(source.size):
        size = abs(source[x])
        found += (size > 0) & (size < TINY)
    tiny[p % 5] = found > 0


@njit(cache=True, nogil=True)
def _add_taps(
    total: np.ndarray,
    even: np.ndarray,
    odd: np.ndarray,
    row: int,
    column: int,
    taps: np.ndarray,
    count: int,
    single: bool,
) -> None:  # pragma: no cover
    """``total[j] (+)= Σ_t w_t · padded[row + dy_t, column + 2j + dx_t]``, rounded to float32
    after each tap, taps in order; ``single``: the power-of-two weights in float32."""
    n = total.size
    for t in range(count):
        start = column + np.int64(taps[t, 1])
        slot = (row + np.int64(taps[t, 0])) % 5
        line = even[slot] if start % 2 == 0 else odd[slot]
        source = line[start // 2 : start // 2 + n]
        weight = taps[t, 2]
        if t == 0 and single and taps[t, 3] > 0:
            exact = np.float32(weight)
            for j in range(n):
                total[j] = exact * source[j]
        elif t == 0:
            for j in range(n):
                total[j] = np.float32(weight * np.float64(source[j]))
        elif single and taps[t, 3] > 0:
            exact = np.float32(weight)
            for j in range(n):
                total[j] = total[j] + exact * source[j]
        else:
            for j in range(n):
                total[j] = np.float32(np.float64(total[j]) + weight * np.float64(source[j]))


@njit(cache=True, nogil=True)
def demosaic_taps(
    raw: np.ndarray,
    taps: np.ndarray,
    counts: np.ndarray,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """``out[y, x, c]`` from ``taps[c, tile, :counts[c, tile]]`` (``tile = 2 (y % 2) + x % 2``;
    each tap ``(dy, dx, weight, power of two)``) over ``raw`` padded by 2 (``reflect``); a
    count of −1 copies the sample. Results are clipped to [0, 1]. An output row whose five
    padded rows hold a value below float32's normal range (see the module docstring) is
    summed in float64 throughout: the choice is made row by row, as the rows are read
    (each value depends on its own 5×5 only), not by a pass over the whole mosaic first.

    The five padded rows an output row reads are kept split into their even and their odd
    columns, in a ring (padded row ``p`` in slot ``p % 5``, one new row per output row), so
    nothing the size of the mosaic is made beside the output. Per output row, the six runs
    (channel × column parity) are summed tap after tap, each a loop over one contiguous row
    of the ring, then interleaved into the row.
    """
    rows, cols = out.shape[0], out.shape[1]
    width = cols + 4
    even = np.empty((5, (width + 1) // 2), dtype=np.float32)
    odd = np.empty((5, width // 2), dtype=np.float32)
    tiny = np.zeros(5, dtype=np.bool_)
    for p in range(4):
        _fill_padded(raw, p, even, odd, tiny)
    sums = np.empty((3, 2, (cols + 1) // 2), dtype=np.float32)
    low, high = np.float32(0.0), np.float32(1.0)
    for y in range(rows):
        _fill_padded(raw, y + 4, even, odd, tiny)
        single = not tiny.any()
        for c in range(3):
            for tx in range(2):
                tile = 2 * (y % 2) + tx
                count = counts[c, tile]
                n = (cols - tx + 1) // 2
                total = sums[c, tx, :n]
                if count < 0:
                    source = even[(y + 2) % 5] if tx == 0 else odd[(y + 2) % 5]
                    total[:] = source[1 : 1 + n]
                else:
                    _add_taps(total, even, odd, y + 2, tx + 2, taps[c, tile], count, single)
        _interleave(sums, low, high, out[y].reshape(-1))


@njit(cache=True, nogil=True)
def _interleave(
    sums: np.ndarray, low: np.float32, high: np.float32, out: np.ndarray
) -> None:  # pragma: no cover
    """One output row, RGB per pixel, from the six runs ``sums[channel, column parity]``,
    clipped to [``low``, ``high``]: one loop over the pixel pairs, six loads and six stores
    each (a SIMD shuffle), instead of a pass per run writing every sixth value."""
    r0, r1, g0, g1, b0, b1 = sums[0, 0], sums[0, 1], sums[1, 0], sums[1, 1], sums[2, 0], sums[2, 1]
    pairs = out.size // 6
    for j in range(pairs):
        out[6 * j] = min(max(r0[j], low), high)
        out[6 * j + 1] = min(max(g0[j], low), high)
        out[6 * j + 2] = min(max(b0[j], low), high)
        out[6 * j + 3] = min(max(r1[j], low), high)
        out[6 * j + 4] = min(max(g1[j], low), high)
        out[6 * j + 5] = min(max(b1[j], low), high)
    if out.size % 6:  # an odd width: the last pixel, an even column
        out[6 * pairs] = min(max(r0[pairs], low), high)
        out[6 * pairs + 1] = min(max(g0[pairs], low), high)
        out[6 * pairs + 2] = min(max(b0[pairs], low), high)
