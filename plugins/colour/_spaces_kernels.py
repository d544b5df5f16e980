"""numba kernels of the RGB → HSV / L*a*b* / YCbCr conversions (imported on first use).

One pass over the pixels, each converted in registers with the same operations in the
same order as the array formulas they replace (``_spaces.py``), so the results are the
same to the bit: no ``fastmath`` (no reassociation, no fused multiply-add). The array
formulas made a dozen full-size temporaries per conversion (``np.where`` evaluates every
branch); here nothing but the output is written.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["rgb_to_hsv", "rgb_to_lab", "rgb_to_linear"]


@njit(cache=True, nogil=True)
def rgb_to_hsv(rgb: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """``rgb`` (N, 3) to HSV in ``out``, computed in float64: hue a fraction of a turn."""
    for i in range(rgb.shape[0]):
        r, g, b = np.float64(rgb[i, 0]), np.float64(rgb[i, 1]), np.float64(rgb[i, 2])
        value = max(max(r, g), b)
        chroma = value - min(min(r, g), b)
        saturation = chroma / value if value > 0 else 0.0
        hue = 0.0
        if chroma > 0:
            if value == r:
                hue = (g - b) / chroma  # in [-1, 1]: ``% 6.0`` (floor modulo) by hand
                hue = hue + 6.0 if hue < 0 else (hue if hue > 0 else 0.0)
            elif value == g:
                hue = (b - r) / chroma + 2.0
            else:
                hue = (r - g) / chroma + 4.0
            hue = hue / 6.0
        out[i, 0] = hue
        out[i, 1] = saturation
        out[i, 2] = value


@njit(cache=True, nogil=True)
def rgb_to_lab(
    rgb: np.ndarray,
    matrix: np.ndarray,
    epsilon: float,
    slope: float,
    levels: np.ndarray,
    levels_linear: np.ndarray,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """``rgb`` (N, 3) in [0, 1] to L*a*b* (computed in float64) in ``out``; ``matrix`` is
    XYZ_from_RGB / white.

    A channel value equal to one of ``levels`` (the 256 of an 8-bit image, in ``rgb``'s
    float) takes its linearisation from ``levels_linear`` (computed by the same formula);
    any other value is linearised here.
    """
    linear = np.empty(3)
    f = np.empty(3)
    top = levels.size - 1
    for i in range(rgb.shape[0]):
        for c in range(3):
            value = rgb[i, c]
            k = int(value * top + 0.5) if 0 <= value <= 1 else 0
            if levels[k] == value:
                linear[c] = levels_linear[k]
                continue
            wide = np.float64(value)
            if wide > 0.04045:
                linear[c] = ((wide + 0.055) / 1.055) ** 2.4
            else:
                linear[c] = wide / 12.92
        for row in range(3):
            xyz = 0.0
            for col in range(3):
                xyz += matrix[row, col] * linear[col]
            if xyz > epsilon:
                f[row] = np.cbrt(xyz)
            else:
                f[row] = slope * xyz + 16.0 / 116.0
        out[i, 0] = 116.0 * f[1] - 16.0
        out[i, 1] = 500.0 * (f[0] - f[1])
        out[i, 2] = 200.0 * (f[1] - f[2])


@njit(cache=True, nogil=True)
def rgb_to_linear(
    rgb: np.ndarray, matrix: np.ndarray, offset: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover
    """``out[i] = matrix @ rgb[i] + offset``, summed from the offset in column order, in
    ``rgb``'s float (``matrix`` and ``offset`` given in that float)."""
    for i in range(rgb.shape[0]):
        for row in range(3):
            total = offset[row]
            for col in range(3):
                total += matrix[row, col] * rgb[i, col]
            out[i, row] = total
