"""Mean squared error and peak signal-to-noise ratio between two images."""

from __future__ import annotations

import numpy as np

from graphvision import Float, Image, node

from ..shared.checks import check_same_shape

__all__ = ["mse", "psnr"]


@node("metrics.mse", version=1)
def mse(a: Image, b: Image) -> Float:
    r"""Mean squared error :math:`\frac{1}{N}\sum_i (a_i - b_i)^2` over all pixels and channels.

    Parameters
    ----------
    a, b : (H, W) or (H, W, 3) float32 ndarray of the same shape

    Returns
    -------
    mse : float

    Examples
    --------
    >>> mse(np.zeros((2, 2), np.float32), np.full((2, 2), 0.5, np.float32))
    0.25
    """
    check_same_shape(a, b)
    difference = a.astype(np.float64) - b
    return float(np.mean(difference * difference))


@node("metrics.psnr", version=1)
def psnr(a: Image, b: Image) -> Float:
    r"""Peak signal-to-noise ratio in dB for images in [0, 1] (peak 1).

    .. math:: \mathrm{PSNR} = 10 \log_{10} \frac{1}{\mathrm{MSE}(a, b)}

    The MSE is floored at 1e-10, so identical images give 100 dB rather than
    infinity.

    Parameters
    ----------
    a, b : (H, W) or (H, W, 3) float32 ndarray of the same shape

    Returns
    -------
    psnr : float, dB

    References
    ----------
    .. [1] Gonzalez & Woods, *Digital Image Processing*, 4th ed., 2018, section 8.1.
    """
    error = max(mse(a, b), 1e-10)
    return float(10.0 * np.log10(1.0 / error))
