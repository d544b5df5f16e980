"""Intensity and chromaticity: grayscale conversion and normalised rgb (seed: "Image processing 1",
"Color").

Moved from the former ``color`` family: ``color.to_gray`` is now ``colour.to_gray`` and
``color.chromaticity`` is ``colour.chromaticity`` (see ``RENAMED_OPS`` in the family).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from graphvision import ColorImage, Conformance, GrayImage, Image, node

__all__ = ["LUMINANCE_WEIGHTS", "chromaticity", "to_gray"]

#: ITU-R BT.601 luma weights for R, G, B (as in OpenCV's and MATLAB's rgb2gray).
LUMINANCE_WEIGHTS = np.array([0.299, 0.587, 0.114], dtype=np.float32)


@node(
    "colour.to_gray",
    version=1,
    conformance=Conformance("max_abs", 1e-5),
)
def to_gray(image: Image, *, method: Literal["mean", "luminance"] = "mean") -> GrayImage:
    r"""Convert an RGB image to gray; a gray image passes through unchanged.

    ``mean`` is the course's definition, the channel average

    .. math:: I(x, y) = \frac{I(x, y, 1) + I(x, y, 2) + I(x, y, 3)}{3};

    ``luminance`` weights the channels by the eye's sensitivity,
    :math:`0.299 R + 0.587 G + 0.114 B` (ITU-R BT.601).

    Parameters
    ----------
    image : (H, W, 3) or (H, W) float32 ndarray
    method : {"mean", "luminance"}

    Returns
    -------
    gray : (H, W) float32 ndarray in [0, 1]

    References
    ----------
    .. [1] ITU-R Recommendation BT.601-7 (2011), section 2.5.1.

    Examples
    --------
    >>> rgb = np.array([[[0.3, 0.6, 0.9]]], dtype=np.float32)
    >>> round(float(to_gray(rgb)[0, 0]), 6)
    0.6
    """
    if image.ndim == 2:
        return image
    gray = image.mean(axis=2, dtype=np.float32) if method == "mean" else image @ LUMINANCE_WEIGHTS
    return np.clip(gray, 0.0, 1.0, out=gray)


@node("colour.chromaticity", version=1)
def chromaticity(image: ColorImage) -> ColorImage:
    r"""Normalised rgb chromaticity: each channel divided by the pixel's sum.

    .. math:: r = \frac{R}{R + G + B},\quad g = \frac{G}{R + G + B},\quad
              b = \frac{B}{R + G + B}

    so :math:`r + g + b = 1` and the result does not change when the light's
    intensity is scaled. A black pixel (:math:`R + G + B = 0`) has no
    chromaticity; it is given the neutral value 1/3 in each channel.

    Parameters
    ----------
    image : (H, W, 3) float32 ndarray

    Returns
    -------
    rgb : (H, W, 3) float32 ndarray, channels summing to 1

    References
    ----------
    .. [1] Gevers & Smeulders, "Color-based object recognition", Pattern
       Recognition 32(3), 1999.
    """
    total = image.sum(axis=2, keepdims=True, dtype=np.float32)
    out = np.full(image.shape, 1.0 / 3.0, dtype=np.float32)
    np.divide(image, total, out=out, where=total > 0)
    return np.clip(out, 0.0, 1.0, out=out)
