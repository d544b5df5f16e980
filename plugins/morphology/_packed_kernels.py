"""numba kernel of the bit-packed binary erosion and dilation (imported on first use: numba
loads slowly); see :mod:`._packed` for the layout.

Each horizontal shift of the element's offsets is made once (a word's bits moved by
``s`` and the next word's first ``s``), and each offset ANDs (erosion) or ORs (dilation)
its shifted rows into the result. The loops run without the GIL: on the thread executor,
a batch's files erode and dilate at the same time (the NumPy loop it replaces, array
operations on a few thousand words each, held the GIL between them; a coins mask's
erosion by a 5×5 disk took 100 µs, now 46).
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["combine_shifted"]


@njit(cache=True, nogil=True)
def _shifted(words, shift, erode, out):
    """``words`` moved left by ``shift`` pixels (0 to 63) into ``out``: bit ``x`` takes bit
    ``x + shift``; past the last word, ones when ``erode``."""
    height, count = words.shape
    if shift == 0:
        out[:] = words
        return
    left, right = np.uint64(shift), np.uint64(64 - shift)
    tail = ((np.uint64(1) << left) - np.uint64(1)) if erode else np.uint64(0)
    for row in range(height):
        for w in range(count - 1):
            out[row, w] = (words[row, w] << left) | (words[row, w + 1] >> right)
        out[row, count - 1] = (words[row, count - 1] << left) | tail


@njit(cache=True, nogil=True)
def combine_shifted(words, rows, row_offsets, shifts, erode):
    """The ``rows`` output rows of packed ``words``: for output word ``(r, w)``, over each
    offset ``k`` (sorted by ``shifts``), the input row ``r + row_offsets[k]`` moved left by
    ``shifts[k]`` pixels (:func:`_shifted`), ANDed when ``erode``, else ORed. Each shift is
    made once, and each offset is one pass of contiguous rows."""
    height, count = words.shape
    out = np.empty((rows, count), np.uint64)
    out[:] = np.uint64(0xFFFFFFFFFFFFFFFF) if erode else np.uint64(0)
    moved = np.empty((height, count), np.uint64)
    made = -1
    for k in range(row_offsets.shape[0]):
        if shifts[k] != made:
            made = shifts[k]
            _shifted(words, made, erode, moved)
        first = row_offsets[k]
        for r in range(rows):
            if erode:
                for w in range(count):
                    out[r, w] &= moved[first + r, w]
            else:
                for w in range(count):
                    out[r, w] |= moved[first + r, w]
    return out
