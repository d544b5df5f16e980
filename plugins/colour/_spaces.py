r"""Colour spaces: RGB ↔ HSV, CIE L\*a\*b\* (D65, 2° observer) and YCbCr (BT.601).

Conventions are scikit-image's (``skimage.color``), so values agree with it:
HSV all in [0, 1] (hue as a fraction of a turn); L\* in [0, 100], a\* and b\*
roughly in [-128, 127]; YCbCr in the studio range, Y in [16, 235] and Cb, Cr
in [16, 240].
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from graphvision import ColorImage, Conformance, FloatImage, node

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


def _hsv_to_rgb(hsv: np.ndarray) -> np.ndarray:
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    sector = h * 6.0
    k = np.stack([(5.0 + sector) % 6.0, (3.0 + sector) % 6.0, (1.0 + sector) % 6.0], axis=-1)
    ramp = np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0)
    return v[..., None] - (v * s)[..., None] * ramp


def _lab_to_rgb(lab: np.ndarray) -> np.ndarray:
    fy = (lab[..., 0] + 16.0) / 116.0
    f = np.stack([fy + lab[..., 1] / 500.0, fy, fy - lab[..., 2] / 200.0], axis=-1)
    cube = f**3
    xyz = np.where(cube > LAB_EPSILON, cube, (f - 16.0 / 116.0) / LAB_SLOPE) * D65_WHITE
    linear = xyz @ np.linalg.inv(XYZ_FROM_RGB).T
    linear = np.clip(linear, 0.0, None)
    return np.where(linear > 0.0031308, 1.055 * linear ** (1 / 2.4) - 0.055, 12.92 * linear)


def _forward(rgb: np.ndarray, space: str, dtype: type) -> np.ndarray:
    """RGB to ``space`` by the compiled kernels, computed in float64 (YCbCr: in ``dtype``)
    and stored as ``dtype``."""
    from ._lab_kernels import rgb_to_lab_single, srgb_levels
    from ._spaces_kernels import (
        rgb_to_hsv,
        rgb_to_hsv_single,
        rgb_to_lab,
        rgb_to_linear,
    )

    work = dtype if space == "ycbcr" else np.float64
    if space != "ycbcr" and np.asarray(rgb).dtype == np.float32:
        work = np.float32  # read as it is, each value widened to float64 in the kernel
    pixels: np.ndarray = np.ascontiguousarray(rgb, dtype=work).reshape(-1, 3)
    out: np.ndarray = np.empty(pixels.shape, dtype=dtype)
    if space == "hsv" and dtype == np.float32 and pixels.dtype == np.float32:
        rgb_to_hsv_single(pixels, out)  # within 2⁻²³ of float64 rounded (its docstring)
    elif space == "hsv":
        rgb_to_hsv(pixels, out)
    elif space == "lab" and dtype == np.float32:
        rgb_to_lab_single(pixels, XYZ_FROM_RGB / D65_WHITE[:, None], LAB_EPSILON, LAB_SLOPE, out)
    elif space == "lab":
        levels, linear = srgb_levels(pixels.dtype)
        matrix = XYZ_FROM_RGB / D65_WHITE[:, None]
        rgb_to_lab(pixels, matrix, LAB_EPSILON, LAB_SLOPE, levels, linear, out)
    else:
        rgb_to_linear(pixels, YCBCR_FROM_RGB.astype(work), YCBCR_OFFSET.astype(work), out)
    return out.reshape(np.shape(rgb))


def _ycbcr_to_rgb(ycbcr: np.ndarray) -> np.ndarray:
    return (ycbcr - YCBCR_OFFSET) @ np.linalg.inv(YCBCR_FROM_RGB).T


_BACKWARD = {"hsv": _hsv_to_rgb, "lab": _lab_to_rgb, "ycbcr": _ycbcr_to_rgb}


def rgb_to(rgb: np.ndarray, space: str) -> np.ndarray:
    """RGB in [0, 1] to ``space``, computed in float64 (YCbCr, linear, in the input's float)."""
    rgb = np.asarray(rgb)
    if rgb.shape[-1:] != (3,):
        raise ValueError(f"rgb must have 3 channels in its last axis, got shape {rgb.shape}")
    dtype = np.float32 if space == "ycbcr" and rgb.dtype == np.float32 else np.float64
    return _forward(rgb, space, dtype)


def to_rgb_from(values: np.ndarray, space: str) -> np.ndarray:
    """``space`` back to RGB in float64 (not clipped)."""
    return _BACKWARD[space](np.asarray(values, dtype=np.float64))


@node(
    "colour.from_rgb",
    version=1,
    conformance=Conformance(
        "max_abs",
        0.6,
        note=(
            "OpenCV's float L*a*b* differs by up to 0.6 units (its own rounding of the sRGB matrix "
            "and white point); HSV and YCbCr agree to 1e-5"
        ),
    ),
)
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
    return _forward(image, space, np.float32)


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
