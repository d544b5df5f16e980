"""numba kernels of the SIFT descriptor (imported on first use: numba loads slowly).

The descriptor is a scatter of every pixel of a rotated window into 8
trilinearly interpolated histogram bins; in numpy that is a ``bincount``
over eight times the window's pixels, in a compiled loop it is a few
floating-point operations per pixel (about ten times faster, measured in
``bench/bench_homography.py``).
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["descriptor_histograms"]


@numba.njit(cache=True, nogil=True)
def descriptor_histograms(magnitude, angle, cx, cy, width, theta, cells, bins):
    """Raw (cells × cells × bins) histograms for keypoints at (cx, cy) in one pyramid level.

    ``width`` is the cell width (3σ) and ``theta`` the orientation of each keypoint.
    """
    count = cx.shape[0]
    rows, cols = magnitude.shape
    out = np.zeros((count, cells * cells * bins), np.float32)
    hist = np.zeros((cells + 2, cells + 2, bins + 2), np.float64)
    two_pi = 2.0 * math.pi
    half = 0.5 * cells
    for k in range(count):
        hist[:] = 0.0
        cos_t = math.cos(theta[k])
        sin_t = math.sin(theta[k])
        w = width[k]
        radius = int(round(w * math.sqrt(2.0) * (cells + 1) * 0.5))
        radius = min(radius, int(math.sqrt(rows * rows + cols * cols)))
        x0 = int(round(cx[k]))
        y0 = int(round(cy[k]))
        for dy in range(-radius, radius + 1):
            y = y0 + dy
            if y <= 0 or y >= rows - 1:
                continue
            for dx in range(-radius, radius + 1):
                x = x0 + dx
                if x <= 0 or x >= cols - 1:
                    continue
                ox = x - cx[k]
                oy = y - cy[k]
                x_rot = (cos_t * ox + sin_t * oy) / w
                y_rot = (-sin_t * ox + cos_t * oy) / w
                rbin = y_rot + half - 0.5
                cbin = x_rot + half - 0.5
                if rbin <= -1.0 or rbin >= cells or cbin <= -1.0 or cbin >= cells:
                    continue
                weight = math.exp(-(x_rot * x_rot + y_rot * y_rot) / (2.0 * half * half))
                weight *= magnitude[y, x]
                obin = (angle[y, x] - theta[k]) % two_pi * bins / two_pi
                r0 = int(math.floor(rbin))
                c0 = int(math.floor(cbin))
                o0 = int(math.floor(obin))
                fr = rbin - r0
                fc = cbin - c0
                fo = obin - o0
                for dr in range(2):
                    wr = weight * (fr if dr else 1.0 - fr)
                    for dc in range(2):
                        wrc = wr * (fc if dc else 1.0 - fc)
                        for do in range(2):
                            hist[r0 + 1 + dr, c0 + 1 + dc, o0 + do] += wrc * (
                                fo if do else 1.0 - fo
                            )
        for r in range(cells):
            for c in range(cells):
                for o in range(bins):
                    value = hist[r + 1, c + 1, o]
                    if o == 0:
                        value += hist[r + 1, c + 1, bins]  # orientation bins wrap around
                    out[k, (r * cells + c) * bins + o] = value
    return out
