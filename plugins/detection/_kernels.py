"""numba kernel of ROI max pooling (imported on first use: numba loads slowly). Each output
cell is the maximum over a rectangle whose bounds depend on the ROI, which no array
operation expresses without building a ragged index."""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["roi_max_pool"]


@njit(cache=True, nogil=True)
def roi_max_pool(features, rois, size):  # pragma: no cover (compiled)
    """Max pooling of ``features`` (C, H, W) over each ROI (R, 4) int64 (x0, y0, x1, y1),
    exclusive ends, inside the map, into ``size`` × ``size`` cells: cell (i, j) spans rows
    ``y0 + floor(i·h / size)`` to ``y0 + ceil((i + 1)·h / size)`` (and the same in x)."""
    count = rois.shape[0]
    channels = features.shape[0]
    out = np.empty((count, channels, size, size))
    for r in range(count):
        x0, y0, x1, y1 = rois[r, 0], rois[r, 1], rois[r, 2], rois[r, 3]
        height = y1 - y0
        width = x1 - x0
        for i in range(size):
            top = y0 + (i * height) // size
            bottom = y0 + -((-(i + 1) * height) // size)
            for j in range(size):
                left = x0 + (j * width) // size
                right = x0 + -((-(j + 1) * width) // size)
                for c in range(channels):
                    best = -np.inf
                    for y in range(top, bottom):
                        for x in range(left, right):
                            if features[c, y, x] > best:
                                best = features[c, y, x]
                    out[r, c, i, j] = best
    return out
