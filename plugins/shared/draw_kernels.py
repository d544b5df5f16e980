"""numba kernel of the drawing helpers (imported on first use: compiling costs time)."""

from __future__ import annotations

import numpy as np

from .jit import njit

__all__ = ["segments"]


@njit(cache=True, nogil=True)
def segments(canvas: np.ndarray, ends: np.ndarray, colours: np.ndarray) -> None:  # pragma: no cover
    """Draw segment k from ``(ends[k, 0], ends[k, 1])`` to ``(ends[k, 2], ends[k, 3])``
    (integer row, column) in ``colours[k]``, in order, clipped to the canvas.

    Bresenham's walk as ``skimage.draw.line`` takes it: along the longer axis, the
    other coordinate stepped while the error term ``d = 2·minor − major`` is not
    negative, and the last pixel set to the end point.
    """
    height, width = canvas.shape[0], canvas.shape[1]
    for k in range(ends.shape[0]):
        r0, c0, r1, c1 = ends[k, 0], ends[k, 1], ends[k, 2], ends[k, 3]
        r, c = r0, c0
        dr, dc = abs(r1 - r0), abs(c1 - c0)
        sc = 1 if c1 - c > 0 else -1
        sr = 1 if r1 - r > 0 else -1
        steep = dr > dc
        if steep:
            r, c, dr, dc, sr, sc = c, r, dc, dr, sc, sr
        d = 2 * dr - dc
        for _ in range(dc):
            row, col = (c, r) if steep else (r, c)
            if 0 <= row < height and 0 <= col < width:
                canvas[row, col] = colours[k]
            while d >= 0:
                r += sr
                d -= 2 * dc
            c += sc
            d += 2 * dr
        if 0 <= r1 < height and 0 <= c1 < width:
            canvas[r1, c1] = colours[k]
