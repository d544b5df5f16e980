"""Local binarisation from window statistics, in O(1) per pixel with integral images."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import AfterValidator, Field

from graphvision import BinaryImage, GrayImage, node

from ..shared.params import odd

__all__ = ["local", "window_mean_std"]


Window = Annotated[int, Field(ge=3, le=1001), AfterValidator(odd)]


def window_mean_std(image: np.ndarray, window: int) -> tuple[np.ndarray, np.ndarray]:
    r"""Mean and standard deviation of every ``window × window`` neighbourhood.

    With the integral images :math:`I(y, x) = \sum_{y' < y, x' < x} f` and
    :math:`I_2` of :math:`f^2` (image mirrored at the border), each window
    sum is four look-ups: :math:`S = I(y_1, x_1) - I(y_0, x_1) - I(y_1, x_0)
    + I(y_0, x_0)`, so the cost per pixel does not depend on the window.
    :math:`\sigma^2 = S_2 / n - (S / n)^2`. The two integral images and the
    look-ups run in one loop compiled with numba.

    References
    ----------
    .. [1] F. Shafait, D. Keysers, T. Breuel, "Efficient implementation of
       local adaptive thresholding techniques using integral images",
       Document Recognition and Retrieval XV, SPIE 6815, 2008.
    """
    from ._kernels import integral_mean_std

    half = window // 2
    padded = np.pad(image, half, mode="symmetric")
    return integral_mean_std(padded, window, image.shape[0], image.shape[1])


@node("threshold.local", version=1)
def local(
    image: GrayImage,
    *,
    window: Window = 25,
    k: Annotated[float, Field(ge=-1, le=1)] = -0.2,
    method: Literal["niblack", "sauvola"] = "niblack",
    r: Annotated[float, Field(gt=0, le=1)] = 0.5,
    foreground: Literal["dark", "bright"] = "dark",
) -> BinaryImage:
    r"""Local binarisation: a threshold per pixel from the statistics of its window ``W``.

    * ``niblack`` (the course's rule): :math:`T_W = \mu_W + k\,\sigma_W`, :math:`k \in [-1, 1]`;
    * ``sauvola``: :math:`T_W = \mu_W \left(1 + k \left(\frac{\sigma_W}{r} - 1\right)\right)`,
      with :math:`r` the dynamic range of σ (0.5 for [0, 1] images) and
      typically :math:`k = 0.2 \ldots 0.5`; it keeps flat background clean.

    Means and deviations come from integral images (:func:`window_mean_std`),
    so the cost per pixel is constant whatever the window.

    Parameters
    ----------
    image : (H, W) float32 ndarray
    window : int
        Odd side of ``W`` in pixels.
    k : float
    method : {"niblack", "sauvola"}
    r : float
        Sauvola's dynamic range of the standard deviation.
    foreground : {"dark", "bright"}
        ``dark`` marks pixels below their threshold (ink on paper), ``bright``
        those above.

    Returns
    -------
    mask : (H, W) bool ndarray

    References
    ----------
    .. [1] W. Niblack, *An Introduction to Digital Image Processing*, 1986.
    .. [2] J. Sauvola, M. Pietikäinen, "Adaptive document image binarization",
       Pattern Recognition 33(2), 2000.
    """
    threshold, std = window_mean_std(image, window)
    if method == "niblack":
        std *= k
        threshold += std
    else:
        std *= k / r
        std += 1.0 - k
        threshold *= std
    return image < threshold if foreground == "dark" else image > threshold
