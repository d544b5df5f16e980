"""numba kernel of the median of an image of 8-bit levels: a sliding histogram (Huang).

An image read from an 8-bit file holds only the 256 levels ``k / 255`` (in float32), and
its median is one of them: the ``size × size`` window's histogram over the 256 levels,
slid one column at a time (``size`` values out, ``size`` in), gives the median by walking
from the previous one, as Huang, Yang and Tang do [1]_. Per pixel that is ``2 · size``
histogram updates and a few steps of the walk (neighbouring medians are close), where
the selection network takes a number of comparators growing as ``size²`` (205 for 7×7);
OpenCV's ``medianBlur`` on uint8 uses the same histograms (Perreault and Hébert's
constant-time form, [2]_). The median is the level at rank ``size² // 2`` of the window,
the same value the network selects: only counts are compared, never values.

References
----------
.. [1] T. S. Huang, G. J. Yang, G. Y. Tang, "A fast two-dimensional median filtering
   algorithm", IEEE Trans. Acoustics, Speech, and Signal Processing 27(1), 1979.
.. [2] S. Perreault, P. Hébert, "Median filtering in constant time", IEEE Trans. Image
   Processing 16(9), 2007.
"""

from __future__ import annotations

import math

import numpy as np

from ..shared.jit import njit

__all__ = ["LEVELS", "level_codes", "median_by_histogram"]

# the 256 levels of an 8-bit image in float32, as the engine reads one (k / 255 rounded)
LEVELS = (np.arange(256) / 255.0).astype(np.float32)
LEVELS.flags.writeable = False


@njit(cache=True, nogil=True)
def level_codes(
    image: np.ndarray, levels: np.ndarray, codes: np.ndarray
) -> bool:  # pragma: no cover
    """``codes`` = the level index of each value of ``image``; False at the first value
    that is not one of ``levels`` (``codes`` then partly written). −0.0 is none: its
    median would come back as the level +0.0, where the network keeps its sign bit."""
    top = levels.size - 1
    for r in range(image.shape[0]):
        row, code = image[r], codes[r]
        for c in range(row.size):
            value = row[c]
            near = 1.0 if value > 1 else (np.float64(value) if value >= 0 else 0.0)  # NaN: 0
            k = int(near * top + 0.5)
            if levels[k] != value or (k == 0 and math.copysign(1.0, value) < 0):
                return False
            code[c] = k
    return True


@njit(cache=True, nogil=True)
def _fill_codes(
    line: np.ndarray, codes: np.ndarray, source: int, column_index: np.ndarray
) -> None:  # pragma: no cover
    """``line`` = code row ``source`` padded by ``column_index`` (−1, or ``source`` −1:
    zero, whose code is 0)."""
    if source < 0:
        line[:] = 0
        return
    row = codes[source]
    for k in range(line.size):
        index = column_index[k]
        line[k] = row[index] if index >= 0 else 0


@njit(cache=True, nogil=True)
def median_by_histogram(
    codes: np.ndarray,
    row_index: np.ndarray,
    column_index: np.ndarray,
    levels: np.ndarray,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """``out[r, c]`` = ``levels`` at the median code of the padded window at ``r, c``.

    Padded row ``p`` is code row ``row_index[p]`` with columns ``column_index`` (−1:
    zero), kept in a ring of ``size`` lines (their order does not matter to a histogram).
    Along a row the histogram loses the window's first column and gains the next one;
    ``below`` counts the values under the current median ``m``, which moves down while
    more than ``rank`` values are below it and up while ``rank`` or fewer are at or below.
    """
    rows, cols = out.shape
    size = row_index.size - rows + 1
    rank = size * size // 2
    lines = np.empty((size, column_index.size), dtype=np.uint8)
    histogram = np.zeros(levels.size, dtype=np.int32)
    for r in range(rows):
        first = 0 if r == 0 else r + size - 1
        for p in range(first, r + size):
            _fill_codes(lines[p % size], codes, row_index[p], column_index)
        histogram[:] = 0
        for p in range(size):
            for q in range(size):
                histogram[lines[p, q]] += 1
        m, below = 0, 0
        while below + histogram[m] <= rank:
            below += histogram[m]
            m += 1
        out[r, 0] = levels[m]
        for c in range(1, cols):
            for p in range(size):
                leaving, entering = lines[p, c - 1], lines[p, c + size - 1]
                histogram[leaving] -= 1
                histogram[entering] += 1
                below += (entering < m) - (leaving < m)
            while below > rank:
                m -= 1
                below -= histogram[m]
            while below + histogram[m] <= rank:
                below += histogram[m]
                m += 1
            out[r, c] = levels[m]
