"""Adaptive thresholding: a pixel against the mean of its window minus a constant."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from graphvision import BinaryImage, Conformance, GrayImage, node

from ._local import Window

__all__ = ["adaptive", "gaussian_sigma"]


def gaussian_sigma(window: int) -> float:
    """The σ OpenCV gives a ``window``-tap Gaussian when asked for none:
    ``0.3 ((window − 1) / 2 − 1) + 0.8``."""
    return 0.3 * ((window - 1) * 0.5 - 1.0) + 0.8


_NOTE = (
    "OpenCV (cv2.adaptiveThreshold) runs on 8-bit levels: it rounds the window's mean to "
    "a whole level (its Gaussian weights are fixed-point too) and c to whole levels "
    "(up for bright, down for dark): with c a whole number of levels, the pixels that "
    "differ lie within half a level of the reference's threshold (box mean), within one "
    "level (Gaussian); elsewhere the masks are equal"
)


@node(
    "threshold.adaptive",
    version=1,
    conformance=Conformance("max_abs", 0.0, mismatch=0.05, note=_NOTE),
)
def adaptive(
    image: GrayImage,
    *,
    window: Window = 11,
    c: Annotated[float, Field(ge=-1, le=1)] = 0.02,
    method: Literal["mean", "gaussian"] = "mean",
    foreground: Literal["bright", "dark"] = "bright",
) -> BinaryImage:
    r"""Adaptive threshold: each pixel against the mean of its window minus ``c``.

    .. math::

        T(x, y) = \sum_{(u, v) \in W} w(u, v)\, f(x + u, y + v) - c

    with :math:`w` the box :math:`1 / n^2` over the ``window × window`` square
    (``mean``) or the sampled Gaussian of σ :math:`0.3\,((n - 1)/2 - 1) + 0.8`
    cut to the square and normalised (``gaussian``), the image replicated at its
    border. ``bright`` marks :math:`f > T`, ``dark`` :math:`f \le T`: the same rule
    as OpenCV's ``adaptiveThreshold`` (``THRESH_BINARY`` and ``THRESH_BINARY_INV``),
    on the float image without rounding. Where Niblack's rule (``threshold.local``)
    follows the window's contrast, a fixed ``c`` keeps flat regions clean.

    Parameters
    ----------
    image : (H, W) float32 ndarray
    window : int
        Odd side of the window in pixels.
    c : float
        Subtracted from the local mean, in image units (0.02 is about 5 of 255 levels).
    method : {"mean", "gaussian"}
    foreground : {"bright", "dark"}

    Returns
    -------
    mask : (H, W) bool ndarray

    References
    ----------
    .. [1] R. C. Gonzalez, R. E. Woods, *Digital Image Processing*, 4th ed., 2018,
       §10.3.7 (variable thresholding based on local image properties).
    .. [2] G. Bradski, A. Kaehler, *Learning OpenCV*, O'Reilly, 2008, ch. 5
       (``cvAdaptiveThreshold``).
    """
    import scipy.ndimage as ndi

    data = image.astype(np.float64)
    if method == "mean":
        local = ndi.uniform_filter(data, window, mode="nearest")
    else:
        sigma = gaussian_sigma(window)
        local = ndi.gaussian_filter(data, sigma, mode="nearest", truncate=(window // 2) / sigma)
    threshold = local - c
    return data > threshold if foreground == "bright" else data <= threshold
