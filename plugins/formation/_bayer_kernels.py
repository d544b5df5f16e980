"""numba kernel of demosaicking (imported on first use: compiling costs time).

Every output value is a short list of taps ``(dy, dx, weight)`` chosen by the pixel's
place in the 2×2 tile and the channel (``_bayer.py`` builds the lists), read from the
mosaic padded by ``numpy.pad``'s ``reflect`` rule (which keeps the tile's parity). Each
tap's product is formed in float64 (the weights are dyadic, so it is exact) and added to
a float32 sum, as the array formulas this replaces did, taps in the same order; taps on
samples of another colour, which added zeros, are left out.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["demosaic_taps", "split_padded"]


@njit(cache=True, nogil=True)
def split_padded(raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """The even and the odd columns of ``raw`` padded by 2 (``numpy.pad``'s ``reflect``)."""
    rows, cols = raw.shape
    width = cols + 4
    even = np.empty((rows + 4, (width + 1) // 2), dtype=np.float32)
    odd = np.empty((rows + 4, width // 2), dtype=np.float32)
    for p in range(rows + 4):
        y = p - 2
        y = -y if y < 0 else (2 * (rows - 1) - y if y >= rows else y)
        source = raw[y]
        for q in range(width):
            x = q - 2
            x = -x if x < 0 else (2 * (cols - 1) - x if x >= cols else x)
            if q % 2 == 0:
                even[p, q // 2] = source[x]
            else:
                odd[p, q // 2] = source[x]
    return even, odd


@njit(cache=True, nogil=True)
def demosaic_taps(
    even: np.ndarray, odd: np.ndarray, taps: np.ndarray, counts: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover
    """``out[y, x, c]`` from ``taps[c, tile, :counts[c, tile]]`` (``tile = 2 (y % 2) + x % 2``)
    over the mosaic padded by 2 (``reflect``), given as its even and its odd columns; a
    count of −1 copies the sample. Results are clipped to [0, 1].

    Per output row, channel and column parity, the taps run one after the other over the
    row's pixels of that parity, each a loop over one contiguous row of ``even`` or ``odd``.
    """
    rows, cols = out.shape[0], out.shape[1]
    total = np.empty((cols + 1) // 2, dtype=np.float32)
    low, high = np.float32(0.0), np.float32(1.0)
    for y in range(rows):
        for c in range(3):
            for tx in range(2):
                tile = 2 * (y % 2) + tx
                count = counts[c, tile]
                n = (cols - tx + 1) // 2
                if count < 0:
                    source = even[y + 2] if tx == 0 else odd[y + 2]
                    for j in range(n):
                        out[y, tx + 2 * j, c] = min(max(source[1 + j], low), high)
                    continue
                total[:n] = 0.0
                for t in range(count):
                    row = y + 2 + np.int64(taps[c, tile, t, 0])
                    start = tx + 2 + np.int64(taps[c, tile, t, 1])
                    source = even[row] if start % 2 == 0 else odd[row]
                    source = source[start // 2 : start // 2 + n]
                    weight = taps[c, tile, t, 2]
                    for j in range(n):
                        term = weight * np.float64(source[j])
                        total[j] = np.float32(np.float64(total[j]) + term)
                for j in range(n):
                    out[y, tx + 2 * j, c] = min(max(total[j], low), high)
