"""numba kernel of non-maximum suppression (imported on first use: numba loads slowly).

One compiled pass over the pixels: the gradient direction picks, for each
pixel above the low threshold, the two points one step ahead and behind on
the 3×3 square around it, whose magnitudes are interpolated linearly between
the two pixels each falls between. A pixel must exceed the neighbour on the
side of decreasing coordinates and at least equal the other one, so of two
pixels of equal magnitude across an edge (a step exactly between two pixels)
one survives: the one on the left (or above). No full-size temporaries
besides the output mask.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["canny_mask", "gradient_magnitude", "suppress_non_maxima"]


@njit(cache=True, nogil=True, inline="always")
def _sample(magnitude, y, x, fy, fx):
    """Magnitude at ``(y + fy, x + fx)`` for |fx|, |fy| <= 1, one of them ±1, edge-replicated."""
    height, width = magnitude.shape
    y0 = int(np.floor(fy))
    x0 = int(np.floor(fx))
    wy = fy - y0
    wx = fx - x0
    total = 0.0
    for dy, ky in ((y0, 1.0 - wy), (y0 + 1, wy)):
        if ky == 0.0:
            continue
        row = min(max(y + dy, 0), height - 1)
        for dx, kx in ((x0, 1.0 - wx), (x0 + 1, wx)):
            if kx == 0.0:
                continue
            col = min(max(x + dx, 0), width - 1)
            total += ky * kx * magnitude[row, col]
    return total


@njit(cache=True, nogil=True)
def _is_maximum(dx, dy, magnitude, y, x):
    """Whether pixel ``(y, x)`` is a maximum along the gradient direction: above the
    neighbour behind, at least the one ahead, "ahead" pointing to increasing x (to
    increasing y for a vertical gradient). Only called where ``magnitude > 0``."""
    m = magnitude[y, x]
    gx = float(dx[y, x])
    gy = float(dy[y, x])
    scale = max(abs(gx), abs(gy))
    ux = gx / scale
    uy = gy / scale
    if ux < 0.0 or (ux == 0.0 and uy < 0.0):
        ux, uy = -ux, -uy  # the same two neighbours, "ahead" towards +x (then +y)
    return m >= _sample(magnitude, y, x, uy, ux) and m > _sample(magnitude, y, x, -uy, -ux)


@njit(cache=True, nogil=True)
def suppress_non_maxima(dx, dy, magnitude, low):
    """Mask of the pixels with ``magnitude >= low`` (and > 0) that :func:`_is_maximum` keeps."""
    height, width = magnitude.shape
    keep = np.zeros((height, width), dtype=np.bool_)
    for y in range(height):
        for x in range(width):
            m = magnitude[y, x]
            if m >= low and m > 0.0 and _is_maximum(dx, dy, magnitude, y, x):
                keep[y, x] = True
    return keep


@njit(cache=True, nogil=True)
def canny_mask(dx, dy, magnitude, low, high):
    """Canny's edges: the non-maxima suppressed (:func:`_is_maximum`), then hysteresis by a
    flood from every kept pixel of ``magnitude >= high`` through the kept pixels,
    8-connected (exactly the 8-connected components of the kept mask that hold a strong
    pixel). One pass and a stack; no labels, no full-size temporaries besides the masks."""
    height, width = magnitude.shape
    weak = np.zeros((height, width), dtype=np.bool_)
    edges = np.zeros((height, width), dtype=np.bool_)
    stack = np.empty(height * width, dtype=np.int64)  # pages are touched only as used
    top = 0
    for y in range(height):
        for x in range(width):
            m = magnitude[y, x]
            if m >= low and m > 0.0 and _is_maximum(dx, dy, magnitude, y, x):
                if m >= high:
                    edges[y, x] = True
                    stack[top] = y * width + x
                    top += 1
                else:
                    weak[y, x] = True
    while top > 0:
        top -= 1
        y = stack[top] // width
        x = stack[top] - y * width
        for v in range(max(y - 1, 0), min(y + 2, height)):
            for u in range(max(x - 1, 0), min(x + 2, width)):
                if weak[v, u]:
                    weak[v, u] = False
                    edges[v, u] = True
                    stack[top] = v * width + u
                    top += 1
    return edges


@njit(cache=True, nogil=True)
def gradient_magnitude(dx: np.ndarray, dy: np.ndarray) -> np.ndarray:  # pragma: no cover
    """``np.hypot(dx, dy)`` of float32 gradients, to the bit: each square and their sum
    in float64 (the squares are exact there), one square root, rounded to float32, as
    glibc's ``hypotf`` computes it, in a loop that vectorises (NumPy's calls ``hypotf``
    per pixel)."""
    out = np.empty(dx.shape, dtype=np.float32)
    flat_x, flat_y, flat = dx.ravel(), dy.ravel(), out.ravel()
    for i in range(flat.size):
        a, b = np.float64(flat_x[i]), np.float64(flat_y[i])
        flat[i] = np.float32(np.sqrt(a * a + b * b))
    return out
