"""numba kernel of HOG's cell histograms (imported on first use: numba loads slowly).

One pass over the pixels of each image computes the central differences, the
magnitude and unsigned orientation, the bin and the vote, in the order
:func:`~graphvision_plugins.recognition._hog.hog_cells` documents, where a NumPy
version made seven full-size temporaries and a ``searchsorted`` and a ``bincount``
over every pixel.
"""

from __future__ import annotations

import math

import numpy as np

from ..shared.jit import njit

__all__ = ["cell_histograms"]


@njit(cache=True, nogil=True)
def cell_histograms(
    images: np.ndarray, orientations: int, rows: int, cols: int, edges: np.ndarray
) -> np.ndarray:
    """Summed votes (N, cells_row, cells_col, orientations) of float images (N, H, W).

    ``edges`` are the bins' lower edges in degrees (float64 of float32 values, as
    scikit-image's); a pixel whose angle reaches the last edge votes nothing.
    Pixels are visited row by row, so each bin sums its votes in the order a
    ``bincount`` over the row-major pixels would.
    """
    count, height, width = images.shape
    cells_row, cells_col = height // rows, width // cols
    out = np.zeros((count, cells_row, cells_col, orientations))
    degrees = 180.0 / math.pi
    for n in range(count):
        for r in range(cells_row * rows):
            for c in range(cells_col * cols):
                g_row = 0.0
                g_col = 0.0
                if 0 < r < height - 1:
                    g_row = np.float64(images[n, r + 1, c] - images[n, r - 1, c])
                if 0 < c < width - 1:
                    g_col = np.float64(images[n, r, c + 1] - images[n, r, c - 1])
                angle = math.atan2(g_row, g_col) * degrees  # then mod 180, as Python's %
                if angle < 0.0:
                    angle += 180.0
                elif angle >= 180.0:
                    angle -= 180.0
                index = orientations  # searchsorted(edges, angle, side="right") - 1
                while index > 0 and edges[index] > angle:
                    index -= 1
                if index >= orientations:
                    continue
                out[n, r // rows, c // cols, index] += math.hypot(g_col, g_row)
    return out
