"""numba kernel of the window statistics (imported on first use: numba loads slowly).

Both integral images are built in one pass and every window is read with
four look-ups each, in one compiled loop: no full-size temporaries besides
the two integrals and the outputs.
"""

from __future__ import annotations

import math

import numpy as np

from ..shared.jit import njit

__all__ = ["integral_mean_std"]


@njit(cache=True, nogil=True)
def integral_mean_std(padded, window, rows, cols):
    """Mean and standard deviation of each ``window × window`` block of ``padded``.

    ``padded`` is the image padded by ``window // 2`` on every side; the
    results have shape ``(rows, cols)``.
    """
    height, width = padded.shape
    total = np.zeros((height + 1, width + 1))
    squares = np.zeros((height + 1, width + 1))
    for y in range(height):
        row_sum = 0.0
        row_squares = 0.0
        for x in range(width):
            value = float(padded[y, x])
            row_sum += value
            row_squares += value * value
            total[y + 1, x + 1] = total[y, x + 1] + row_sum
            squares[y + 1, x + 1] = squares[y, x + 1] + row_squares
    area = float(window * window)
    mean = np.empty((rows, cols))
    std = np.empty((rows, cols))
    for y in range(rows):
        for x in range(cols):
            y1 = y + window
            x1 = x + window
            s = total[y1, x1] - total[y, x1] - total[y1, x] + total[y, x]
            q = squares[y1, x1] - squares[y, x1] - squares[y1, x] + squares[y, x]
            m = s / area
            mean[y, x] = m
            std[y, x] = math.sqrt(max(q / area - m * m, 0.0))
    return mean, std
