"""numba kernel of normalised cross-correlation's denominator (imported on first use).

The window sums of the image and of its square come from two integral images, each by
running sums down the columns then along the rows (the order of
``cumsum(axis=0).cumsum(axis=1)``); the four-corner differences, the spread and the
division follow the array formulas they replace operation by operation, so the map is
the same to the bit. Only the ``h + 1`` integral rows a window reads are kept, in a ring
(row ``r`` in slot ``r % (h + 1)``), each made from the running column sums when the
output row that ends there is due: nothing the size of the image is made beside the
output (two image-sized float64 tables cost page faults and memory traffic at 2048²).
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["normalise_response"]


@njit(cache=True, nogil=True)
def _integral_row(
    data: np.ndarray,
    r: int,
    plain_run: np.ndarray,
    square_run: np.ndarray,
    plain: np.ndarray,
    square: np.ndarray,
) -> None:  # pragma: no cover
    """Integral row ``r + 1`` (of ``data[:r + 1]``) into ``plain`` and ``square``: the running
    column sums advanced by row ``r``, then summed along the row."""
    cols = data.shape[1]
    for c in range(cols):  # running sums down each column
        value = data[r, c]
        plain_run[c] = plain_run[c] + value
        square_run[c] = square_run[c] + value * value
    plain[0] = 0.0
    square[0] = 0.0
    if cols > 0:
        plain[1] = plain_run[0]
        square[1] = square_run[0]
    for c in range(2, cols + 1):  # then along the row
        plain[c] = plain[c - 1] + plain_run[c - 1]
        square[c] = square[c - 1] + square_run[c - 1]


@njit(cache=True, nogil=True)
def normalise_response(
    data: np.ndarray, response: np.ndarray, h: int, w: int, energy: float, tiny: float
) -> np.ndarray:  # pragma: no cover
    """``response / sqrt(spread · energy)`` (0 where the denominator is at most ``tiny``),
    ``spread`` the sum of squared deviations of ``data`` over each ``h × w`` window."""
    cols = data.shape[1]
    ring = h + 1
    plain = np.zeros((ring, cols + 1))  # integral row r in slot r % ring; row 0 is zeros
    square = np.zeros((ring, cols + 1))
    plain_run = np.zeros(cols)
    square_run = np.zeros(cols)
    count = h * w
    out = np.empty_like(response)
    for r in range(h):
        _integral_row(data, r, plain_run, square_run, plain[(r + 1) % ring], square[(r + 1) % ring])
    for r in range(response.shape[0]):
        # integral rows r (top) and r + h (bottom); row r + h is made now
        bottom = (r + h) % ring
        if r > 0:
            _integral_row(data, r + h - 1, plain_run, square_run, plain[bottom], square[bottom])
        top_p, top_s = plain[r % ring], square[r % ring]
        low_p, low_s = plain[bottom], square[bottom]
        for c in range(response.shape[1]):
            sums = low_p[c + w] - top_p[c + w] - low_p[c] + top_p[c]
            squares = low_s[c + w] - top_s[c + w] - low_s[c] + top_s[c]
            spread = max(squares - sums * sums / count, 0.0)
            denominator = np.sqrt(spread * energy)
            if denominator > tiny:
                out[r, c] = response[r, c] / max(denominator, tiny)
            else:
                out[r, c] = 0.0
    return out
