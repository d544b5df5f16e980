"""numba kernel of 2-D correlation with any kernel (imported on first use: compiling costs time)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ._padded_rows import fill_line

__all__ = ["correlate_2d"]


@njit(cache=True, fastmath=True, nogil=True)
def correlate_2d(
    image: np.ndarray,
    kernel: np.ndarray,
    row_index: np.ndarray,
    column_index: np.ndarray,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """``out[r, c] = Σ_ij kernel[i, j] · padded[r + i, c + j]``, accumulated in float64.

    Padded row ``p`` is image row ``row_index[p]`` with columns
    ``column_index`` (−1: zero), built as it is needed into one line; each tap
    adds a shifted line to a float64 row (a SIMD loop), as scipy accumulates
    in double, then the row is rounded once to float32.
    """
    rows, cols = out.shape
    kh, kw = kernel.shape
    before = kw // 2
    line = np.empty(column_index.size, dtype=np.float32)
    total = np.empty(cols, dtype=np.float64)
    for r in range(rows):
        total[:] = 0.0
        for i in range(kh):
            fill_line(line, image, row_index[r + i], column_index, before)
            for j in range(kw):
                weight = kernel[i, j]
                if weight == 0.0:
                    continue
                for c in range(cols):
                    total[c] += weight * line[c + j]
        for c in range(cols):
            out[r, c] = total[c]
