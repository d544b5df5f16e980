"""numba kernels of the RGB → HSV / L*a*b* / YCbCr conversions (imported on first use).

One pass over the pixels, each converted in registers with the same operations in the
same order as the array formulas they replace (``_spaces.py``), so the results are the
same to the bit: no ``fastmath`` (no reassociation, no fused multiply-add). The array
formulas made a dozen full-size temporaries per conversion (``np.where`` evaluates every
branch); here nothing but the output is written.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["rgb_to_hsv", "rgb_to_hsv_single", "rgb_to_lab", "rgb_to_linear"]


@njit(cache=True, nogil=True, error_model="numpy")  # no zero-divisor check: it vectorises
def rgb_to_hsv(rgb: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """``rgb`` (N, 3) to HSV in ``out``, computed in float64: hue a fraction of a turn.

    Branch-free, so the loop runs in SIMD lanes: the three hue formulas are one, their
    numerator and offset (0, 2 or 4 sixths) chosen by the channel holding the maximum, and
    the divisions by a zero chroma or value are made and their results not taken. The
    same operations on the values kept as ``numpy``'s formulas, so the same bits: the
    offset 0 is added exactly (``x + 0.0 = x``, but for −0.0, which both map to 0)."""
    pixels = rgb.reshape(-1)
    result = out.reshape(-1)
    for i in range(rgb.shape[0]):
        r = np.float64(pixels[3 * i])
        g = np.float64(pixels[3 * i + 1])
        b = np.float64(pixels[3 * i + 2])
        value = max(max(r, g), b)
        chroma = value - min(min(r, g), b)
        saturation = chroma / value if value > 0 else 0.0
        red, green = value == r, value != r and value == g
        numerator = g - b if red else (b - r if green else r - g)
        offset = 0.0 if red else (2.0 if green else 4.0)
        sector = numerator / chroma + offset  # in [-1, 1] for red: ``% 6.0`` by hand
        hue = sector + 6.0 if sector < 0 else (sector if sector > 0 or not red else 0.0)
        result[3 * i] = hue / 6.0 if chroma > 0 else 0.0
        result[3 * i + 1] = saturation
        result[3 * i + 2] = value


@njit(cache=True, nogil=True, error_model="numpy")
def rgb_to_hsv_single(rgb: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """:func:`rgb_to_hsv` of a float32 ``rgb`` into a float32 ``out``, computed in float32:
    eight lanes per SIMD step instead of four, the divisions (three a pixel) the cost. Value
    is the same; hue and saturation within 2⁻²³ of the float64 result rounded (a float32
    rounding at each of their three steps instead of once at the end)."""
    pixels = rgb.reshape(-1)
    result = out.reshape(-1)
    zero, two, four, six = np.float32(0.0), np.float32(2.0), np.float32(4.0), np.float32(6.0)
    for i in range(rgb.shape[0]):
        r, g, b = pixels[3 * i], pixels[3 * i + 1], pixels[3 * i + 2]
        value = max(max(r, g), b)
        chroma = value - min(min(r, g), b)
        saturation = chroma / value if value > 0 else zero
        red, green = value == r, value != r and value == g
        numerator = g - b if red else (b - r if green else r - g)
        hue = numerator / chroma + (zero if red else (two if green else four))
        hue = hue + six if hue < 0 else (hue if hue > 0 or not red else zero)
        result[3 * i] = hue / six if chroma > 0 else zero
        result[3 * i + 1] = saturation
        result[3 * i + 2] = value


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
    ``rgb``'s float (``matrix`` and ``offset`` given in that float); the nine weights are
    held in registers."""
    m00, m01, m02 = matrix[0, 0], matrix[0, 1], matrix[0, 2]
    m10, m11, m12 = matrix[1, 0], matrix[1, 1], matrix[1, 2]
    m20, m21, m22 = matrix[2, 0], matrix[2, 1], matrix[2, 2]
    o0, o1, o2 = offset[0], offset[1], offset[2]
    pixels = rgb.reshape(-1)  # flat, so the loop reads three interleaved lanes in SIMD
    result = out.reshape(-1)
    for i in range(rgb.shape[0]):
        r, g, b = pixels[3 * i], pixels[3 * i + 1], pixels[3 * i + 2]
        result[3 * i] = ((o0 + m00 * r) + m01 * g) + m02 * b
        result[3 * i + 1] = ((o1 + m10 * r) + m11 * g) + m12 * b
        result[3 * i + 2] = ((o2 + m20 * r) + m21 * g) + m22 * b
