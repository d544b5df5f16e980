"""numba helper shared by the filter kernels: one padded image row, built as it is read.

The boundary rule is an index array along each axis (the source of every
padded position, −1 for zero), so no padded copy of the image is made.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["fill_line"]


@njit(cache=True, nogil=True)
def fill_line(
    line: np.ndarray, image: np.ndarray, source: int, column_index: np.ndarray, before: int
) -> None:  # pragma: no cover
    """``line`` = image row ``source`` (−1: zeros) padded by ``column_index``.

    ``before`` padded positions precede the row (an even kernel pads unequally).
    """
    if source < 0:
        line[:] = 0.0
        return
    row = image[source]
    cols = row.size
    inside = line[before : before + cols]
    for k in range(cols):  # a loop, not ``inside[:] = row``: numba's slice copy took 3×
        inside[k] = row[k]
    for k in range(before):
        index = column_index[k]
        line[k] = row[index] if index >= 0 else 0.0
    for k in range(before + cols, line.size):
        index = column_index[k]
        line[k] = row[index] if index >= 0 else 0.0
