r"""Colour spaces: RGB ↔ HSV, CIE L\*a\*b\* (D65, 2° observer) and YCbCr (BT.601).

Conventions are scikit-image's (``skimage.color``), so values agree with it:
HSV all in [0, 1] (hue as a fraction of a turn); L\* in [0, 100], a\* and b\*
roughly in [-128, 127]; YCbCr in the studio range, Y in [16, 235] and Cb, Cr
in [16, 240].
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from graphvision import ColorImage, FloatImage, node

__all__ = ["SPACES", "Space", "from_rgb", "rgb_to", "to_rgb", "to_rgb_from"]

Space = Literal["hsv", "lab", "ycbcr"]
SPACES: tuple[str, ...] = ("hsv", "lab", "ycbcr")

# sRGB primaries with the D65 white point (IEC 61966-2-1), XYZ of white Y = 1
XYZ_FROM_RGB = np.array(
    [
        [0.412453, 0.357580, 0.180423],
        [0.212671, 0.715160, 0.072169],
        [0.019334, 0.119193, 0.950227],
    ]
)
D65_WHITE = np.array([0.95047, 1.0, 1.08883])
# ITU-R BT.601 studio range, for R, G, B in [0, 1]
YCBCR_FROM_RGB = np.array(
    [[65.481, 128.553, 24.966], [-37.797, -74.203, 112.0], [112.0, -93.786, -18.214]]
)
YCBCR_OFFSET = np.array([16.0, 128.0, 128.0])
LAB_EPSILON = 0.008856  # (6/29)³ rounded, as CIE publishes it
LAB_SLOPE = 7.787  # 1 / (3 (6/29)²) rounded


def _rgb_to_hsv(rgb: np.ndarray) -> np.ndarray:
    value = rgb.max(axis=-1)
    chroma = value - rgb.min(axis=-1)
    safe_chroma = np.where(chroma > 0, chroma, 1.0)
    saturation = np.where(value > 0, chroma / np.where(value > 0, value, 1.0), 0.0)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    hue = np.where(
        value == r,
        ((g - b) / safe_chroma) % 6.0,
        np.where(value == g, (b - r) / safe_chroma + 2.0, (r - g) / safe_chroma + 4.0),
    )
    hue = np.where(chroma > 0, hue / 6.0, 0.0)
    return np.stack([hue, saturation, value], axis=-1)


def _hsv_to_rgb(hsv: np.ndarray) -> np.ndarray:
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    sector = h * 6.0
    k = np.stack([(5.0 + sector) % 6.0, (3.0 + sector) % 6.0, (1.0 + sector) % 6.0], axis=-1)
    ramp = np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0)
    return v[..., None] - (v * s)[..., None] * ramp


def _rgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    linear = rgb / 12.92
    curved = rgb > 0.04045
    linear[curved] = ((rgb[curved] + 0.055) / 1.055) ** 2.4
    xyz = _linear(linear, XYZ_FROM_RGB / D65_WHITE[:, None], np.zeros(3))
    f = LAB_SLOPE * xyz + 16.0 / 116.0
    above = xyz > LAB_EPSILON
    f[above] = np.cbrt(xyz[above])
    lab = np.empty_like(f)
    lab[..., 0] = 116.0 * f[..., 1] - 16.0
    lab[..., 1] = 500.0 * (f[..., 0] - f[..., 1])
    lab[..., 2] = 200.0 * (f[..., 1] - f[..., 2])
    return lab


def _lab_to_rgb(lab: np.ndarray) -> np.ndarray:
    fy = (lab[..., 0] + 16.0) / 116.0
    f = np.stack([fy + lab[..., 1] / 500.0, fy, fy - lab[..., 2] / 200.0], axis=-1)
    cube = f**3
    xyz = np.where(cube > LAB_EPSILON, cube, (f - 16.0 / 116.0) / LAB_SLOPE) * D65_WHITE
    linear = xyz @ np.linalg.inv(XYZ_FROM_RGB).T
    linear = np.clip(linear, 0.0, None)
    return np.where(linear > 0.0031308, 1.055 * linear ** (1 / 2.4) - 0.055, 12.92 * linear)


def _linear(image: np.ndarray, matrix: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """``matrix @ pixel + offset`` for every pixel, channel plane by plane, in the input's float."""
    out = np.empty_like(image)
    for row in range(3):
        plane = out[..., row]
        plane[...] = offset[row]
        for col in range(3):
            plane += image.dtype.type(matrix[row, col]) * image[..., col]
    return out


def _rgb_to_ycbcr(rgb: np.ndarray) -> np.ndarray:
    return _linear(rgb, YCBCR_FROM_RGB, YCBCR_OFFSET)


def _ycbcr_to_rgb(ycbcr: np.ndarray) -> np.ndarray:
    return (ycbcr - YCBCR_OFFSET) @ np.linalg.inv(YCBCR_FROM_RGB).T


_FORWARD = {"hsv": _rgb_to_hsv, "lab": _rgb_to_lab, "ycbcr": _rgb_to_ycbcr}
_BACKWARD = {"hsv": _hsv_to_rgb, "lab": _lab_to_rgb, "ycbcr": _ycbcr_to_rgb}


def rgb_to(rgb: np.ndarray, space: str) -> np.ndarray:
    """RGB in [0, 1] to ``space``, computed in float64 (YCbCr, linear, in the input's float)."""
    if space == "ycbcr" and np.asarray(rgb).dtype == np.float32:
        return _rgb_to_ycbcr(rgb).astype(np.float32)
    return _FORWARD[space](np.asarray(rgb, dtype=np.float64))


def to_rgb_from(values: np.ndarray, space: str) -> np.ndarray:
    """``space`` back to RGB in float64 (not clipped)."""
    return _BACKWARD[space](np.asarray(values, dtype=np.float64))


@node("colour.from_rgb", version=1)
def from_rgb(image: ColorImage, *, space: Space = "lab") -> FloatImage:
    r"""An RGB image in another colour space (channels in the space's own ranges).

    * ``hsv``: :math:`V = \max(R, G, B)`, :math:`S = (V - \min)/V`, hue the
      angle around the grey axis, as a fraction of a turn;
    * ``lab``: sRGB linearised (:math:`((c + 0.055)/1.055)^{2.4}` above
      0.04045), to XYZ, divided by the D65 white, then
      :math:`L^* = 116 f(Y) - 16`, :math:`a^* = 500 (f(X) - f(Y))`,
      :math:`b^* = 200 (f(Y) - f(Z))` with :math:`f(t) = t^{1/3}` above
      :math:`(6/29)^3`. Euclidean distances in L\*a\*b\* approximate
      perceived colour differences;
    * ``ycbcr``: BT.601, luma and two colour differences, studio range.

    Parameters
    ----------
    image : (H, W, 3) float32 ndarray
        RGB in [0, 1].
    space : {"hsv", "lab", "ycbcr"}
        The target space.

    Returns
    -------
    converted : (H, W, 3) float32 ndarray

    References
    ----------
    .. [1] Szeliski (2022), section 2.3.2; CIE 15:2004, *Colorimetry*.
    """
    return rgb_to(image, space).astype(np.float32)


@node("colour.to_rgb", version=1)
def to_rgb(image: FloatImage, *, space: Space = "lab") -> ColorImage:
    """An image in ``space`` back to RGB, clipped to [0, 1] (the inverse of ``colour.from_rgb``).

    Parameters
    ----------
    image : (H, W, 3) float32 ndarray
        Channels in the space's ranges (see ``colour.from_rgb``).
    space : {"hsv", "lab", "ycbcr"}
        The space ``image`` is in.

    Returns
    -------
    rgb : (H, W, 3) float32 ndarray
    """
    if image.ndim != 3:
        raise ValueError(f"image must be H×W×3 in {space}, got shape {image.shape}")
    return np.clip(to_rgb_from(image, space), 0.0, 1.0).astype(np.float32)
