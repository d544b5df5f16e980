"""numba kernel of normalised cross-correlation's denominator (imported on first use).

The window sums of the image and of its square come from two integral images built in
one pass, each by running sums down the columns then along the rows (the order of
``cumsum(axis=0).cumsum(axis=1)``); the four-corner differences, the spread and the
division follow the array formulas they replace operation by operation, so the map is
the same to the bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["normalise_response"]


@njit(cache=True, nogil=True)
def _integrals(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    rows, cols = data.shape
    plain = np.zeros((rows + 1, cols + 1))
    square = np.zeros((rows + 1, cols + 1))
    for r in range(rows):  # running sums down each column
        for c in range(cols):
            value = data[r, c]
            plain[r + 1, c + 1] = plain[r, c + 1] + value
            square[r + 1, c + 1] = square[r, c + 1] + value * value
    for r in range(1, rows + 1):  # then along each row
        for c in range(2, cols + 1):
            plain[r, c] = plain[r, c - 1] + plain[r, c]
            square[r, c] = square[r, c - 1] + square[r, c]
    return plain, square


@njit(cache=True, nogil=True)
def normalise_response(
    data: np.ndarray, response: np.ndarray, h: int, w: int, energy: float, tiny: float
) -> np.ndarray:  # pragma: no cover
    """``response / sqrt(spread · energy)`` (0 where the denominator is at most ``tiny``),
    ``spread`` the sum of squared deviations of ``data`` over each ``h × w`` window."""
    plain, square = _integrals(data)
    count = h * w
    out = np.empty_like(response)
    for r in range(response.shape[0]):
        for c in range(response.shape[1]):
            sums = plain[r + h, c + w] - plain[r, c + w] - plain[r + h, c] + plain[r, c]
            squares = square[r + h, c + w] - square[r, c + w] - square[r + h, c] + square[r, c]
            spread = max(squares - sums * sums / count, 0.0)
            denominator = np.sqrt(spread * energy)
            if denominator > tiny:
                out[r, c] = response[r, c] / max(denominator, tiny)
            else:
                out[r, c] = 0.0
    return out
