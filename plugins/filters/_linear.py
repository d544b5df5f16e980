"""Linear filters: correlation, convolution, Gaussian, box and sharpening."""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from graphvision import Conformance, FloatImage, Image, ImageT, Kernel, node

from ..shared.checks import check_window
from ._boundary import Boundary, crop_valid, scipy_mode

__all__ = [
    "box",
    "box_kernel",
    "convolve",
    "correlate",
    "gaussian",
    "gaussian_kernel",
    "gaussian_kernel_1d",
    "sharpen",
    "to_image",
]

Sigma = Annotated[float, Field(gt=0, le=100, description="Standard deviation in pixels.")]
Size = Annotated[int, Field(ge=1, le=255, description="Window side in pixels.")]
_NUMPY_PAD: dict[str, Literal["symmetric", "edge", "wrap"]] = {
    "reflect": "symmetric",
    "nearest": "edge",
    "grid-wrap": "wrap",
}


def _rank_one_factors(kernel: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    r"""``(column, row)`` taps with :math:`H = c\, r^\top` when ``H`` has rank one, else None.

    From the singular value decomposition :math:`H = \sum_i s_i u_i v_i^\top`:
    rank one when :math:`s_2 \le 10^{-12} s_1`; then :math:`c = s_1 u_1`,
    :math:`r = v_1`. Only kernels with odd sides (a centre tap) are factored.
    """
    if kernel.shape[0] % 2 == 0 or kernel.shape[1] % 2 == 0 or not np.any(kernel):
        return None
    u, s, vt = np.linalg.svd(kernel.astype(np.float64))
    if s.size > 1 and s[1] > 1e-12 * s[0]:
        return None
    return u[:, 0] * s[0], vt[0]


@lru_cache(maxsize=64)
def _padded_index(length: int, before: int, after: int, boundary: str) -> np.ndarray:
    """Source index of each padded position along an axis (−1: zero; crop pads too); kept
    for the next call of the same size (read-only: np.pad costs as much as a small filter)."""
    positions = np.arange(length, dtype=np.int64)
    if boundary == "zero":
        return np.pad(positions, (before, after), mode="constant", constant_values=-1)
    return np.pad(positions, (before, after), mode=_NUMPY_PAD[scipy_mode(boundary)])


def _boundary_index(length: int, before: int, after: int, boundary: str) -> np.ndarray:
    """The cached index, read-only (it is shared between calls)."""
    index = _padded_index(length, before, after, boundary)
    index.flags.writeable = False
    return index


def _correlate_any(image: np.ndarray, kernel: np.ndarray, boundary: str) -> np.ndarray:
    """2-D correlation of one plane with any kernel, centre ``(kh // 2, kw // 2)``, compiled."""
    from ._correlate_kernels import correlate_2d

    (kh, kw), (rows, cols) = kernel.shape, image.shape
    out = np.empty((rows, cols), dtype=np.float32)
    correlate_2d(
        np.ascontiguousarray(image, dtype=np.float32),
        np.ascontiguousarray(kernel, dtype=np.float64),
        _boundary_index(rows, kh // 2, kh - 1 - kh // 2, boundary),
        _boundary_index(cols, kw // 2, kw - 1 - kw // 2, boundary),
        out,
    )
    return out


def _filter(image: np.ndarray, kernel: np.ndarray, boundary: str) -> np.ndarray:
    """Correlate each channel of ``image`` with the 2-D ``kernel`` (factored when separable)."""
    from ..shared.separable import correlate_separable

    if boundary == "crop":
        check_window(image, kernel.shape, "kernel")
    factors = _rank_one_factors(kernel)
    if factors is not None:
        out = correlate_separable(image, *factors, scipy_mode(boundary))
    elif image.ndim == 3:
        out = np.stack(
            [_correlate_any(image[..., c], kernel, boundary) for c in range(image.shape[2])],
            axis=2,
        )
    else:
        out = _correlate_any(image, kernel, boundary)
    return crop_valid(out, kernel.shape) if boundary == "crop" else out


def _separable(image: np.ndarray, taps: np.ndarray, boundary: str) -> np.ndarray:
    """Correlate rows then columns with the same 1-D ``taps`` (the compiled separable core)."""
    from ..shared.separable import correlate_separable

    if boundary == "crop":
        check_window(image, (taps.size, taps.size), "filter window")
    out = correlate_separable(image, taps, taps, scipy_mode(boundary))
    return crop_valid(out, (taps.size, taps.size)) if boundary == "crop" else out


@node(
    "filters.correlate",
    version=1,
    conformance=Conformance("max_abs", 1e-5),
)
def correlate(image: FloatImage, kernel: Kernel, *, boundary: Boundary = "mirror") -> FloatImage:
    r"""Cross-correlation: each pixel becomes the kernel-weighted sum of its window.

    .. math:: G(i, j) = \sum_{u=-k}^{k} \sum_{v=-k}^{k} H(u, v)\, F(i + u, j + v)

    The kernel's centre is element ``(rows // 2, cols // 2)``; colour images
    are filtered channel by channel. Pixels whose window leaves the image are
    handled by ``boundary`` (see :mod:`._boundary`); ``crop`` returns only the
    valid part, smaller by the kernel size minus one. A kernel of rank one
    with odd sides (a Gaussian, a box, Sobel) is factored as
    :math:`H = c\, r^\top` and applied as two 1-D passes by the compiled
    separable core, :math:`O(k)` instead of :math:`O(k^2)` per pixel; any
    other kernel is applied tap by tap over whole rows by a compiled loop
    that accumulates in float32, as OpenCV's ``filter2D`` does: an output
    differs from scipy's float64 sum by at most about
    :math:`(k_h \lceil k_w / 5 \rceil + 5)\, 2^{-24} \sum |H|\, \max |F|`
    (3·10⁻⁶ for a 5×5 kernel of total weight 1 on a [0, 1] image).

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
    kernel : (kh, kw) float64 ndarray
    boundary : {"mirror", "replicate", "wrap", "zero", "crop"}

    Returns
    -------
    filtered : float32 ndarray (any range: kernels may have negative weights)

    References
    ----------
    .. [1] Szeliski, *Computer Vision: Algorithms and Applications*, 2nd ed.,
       2022, section 3.2 (eq. 3.12).
    """
    return _filter(image, kernel, boundary)


@node(
    "filters.convolve",
    version=1,
    conformance=Conformance("max_abs", 1e-5),
)
def convolve(image: FloatImage, kernel: Kernel, *, boundary: Boundary = "mirror") -> FloatImage:
    r"""Convolution: correlation with the kernel flipped in both dimensions.

    .. math:: G(i, j) = \sum_{u=-k}^{k} \sum_{v=-k}^{k} H(u, v)\, F(i - u, j - v)

    Convolution is commutative and associative, so a cascade of filters is
    one filter; for a symmetric kernel it equals correlation. The flipped
    kernel's centre is again ``(rows // 2, cols // 2)``.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
    kernel : (kh, kw) float64 ndarray
    boundary : {"mirror", "replicate", "wrap", "zero", "crop"}

    Returns
    -------
    filtered : float32 ndarray

    References
    ----------
    .. [1] Szeliski (2022), section 3.2 (eq. 3.14).
    """
    return _filter(image, np.ascontiguousarray(kernel[::-1, ::-1]), boundary)


def gaussian_kernel_1d(sigma: float, half_size: int | None = None) -> np.ndarray:
    r"""Sampled, normalised 1-D Gaussian :math:`g(u) \propto e^{-u^2 / 2\sigma^2}`.

    Samples :math:`|u| \le h`, where ``h`` defaults to the course's half size
    :math:`\lceil 3\sigma \rceil`.
    """
    h = math.ceil(3.0 * sigma) if half_size is None else half_size
    u = np.arange(-h, h + 1, dtype=np.float64)
    taps = np.exp(-(u * u) / (2.0 * sigma * sigma))
    return taps / taps.sum()


@node("filters.gaussian_kernel", version=1)
def gaussian_kernel(
    *, sigma: Sigma = 1.0, half_size: Annotated[int, Field(ge=0, le=300)] | None = None
) -> Kernel:
    r"""A normalised 2-D Gaussian kernel of half size :math:`h = \lceil 3\sigma \rceil`.

    .. math:: H(u, v) = \frac{1}{Z} \exp\left(-\frac{u^2 + v^2}{2\sigma^2}\right),
              \quad |u|, |v| \le h, \quad \sum H = 1

    Parameters
    ----------
    sigma : float
        Standard deviation in pixels; larger smooths more.
    half_size : int, optional
        Overrides :math:`h`; the kernel is :math:`(2h + 1) \times (2h + 1)`.

    Returns
    -------
    kernel : (2h + 1, 2h + 1) float64 ndarray

    Examples
    --------
    >>> gaussian_kernel(sigma=1.0).shape
    (7, 7)
    """
    taps = gaussian_kernel_1d(sigma, half_size)
    return np.outer(taps, taps)


@node("filters.box_kernel", version=1)
def box_kernel(*, size: Size = 3) -> Kernel:
    """A ``size × size`` kernel of equal weights summing to one (a moving average).

    Parameters
    ----------
    size : int
        Odd side of the kernel.

    Returns
    -------
    kernel : (size, size) float64 ndarray
    """
    return np.full((size, size), 1.0 / (size * size))


@node(
    "filters.gaussian",
    version=1,
    conformance=Conformance("max_abs", 1e-5),
)
def gaussian(image: ImageT, *, sigma: Sigma = 1.0, boundary: Boundary = "mirror") -> ImageT:
    r"""Gaussian smoothing, separably: rows then columns with the 1-D Gaussian.

    :math:`G_\sigma * F = g_\sigma * (g_\sigma^T * F)` because the 2-D Gaussian
    is the outer product of two 1-D ones; this costs :math:`2(2h+1)` instead
    of :math:`(2h+1)^2` multiplications per pixel, :math:`h = \lceil 3\sigma \rceil`.
    It removes Gaussian noise by averaging each pixel with its neighbours,
    weighted by distance, and is a low-pass filter with compact support in
    both image and frequency space.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
    sigma : float
        Standard deviation in pixels.
    boundary : {"mirror", "replicate", "wrap", "zero", "crop"}

    Returns
    -------
    smoothed : float32 ndarray, same kind as ``image``

    References
    ----------
    .. [1] Szeliski (2022), section 3.2.1; Forsyth & Ponce, *Computer Vision:
       A Modern Approach*, 2nd ed., 2012, section 4.2.
    """
    out = _separable(image, gaussian_kernel_1d(sigma), boundary)
    return np.clip(out, 0.0, 1.0, out=out)


@node(
    "filters.box",
    version=1,
    conformance=Conformance("max_abs", 1e-5),
)
def box(image: ImageT, *, size: Size = 3, boundary: Boundary = "mirror") -> ImageT:
    """Moving average over a ``size × size`` window (separable, like :func:`gaussian`).

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
    size : int
        Window side; even sizes put the centre at ``size // 2``.
    boundary : {"mirror", "replicate", "wrap", "zero", "crop"}

    Returns
    -------
    smoothed : float32 ndarray, same kind as ``image``
    """
    out = _separable(image, np.full(size, 1.0 / size), boundary)
    return np.clip(out, 0.0, 1.0, out=out)


@node("filters.sharpen", version=1)
def sharpen(
    image: ImageT,
    *,
    amount: Annotated[float, Field(ge=0, le=20)] = 1.0,
    smoothing: Literal["box", "gaussian"] = "box",
    size: Size = 3,
    sigma: Sigma = 1.0,
    boundary: Boundary = "mirror",
) -> ImageT:
    r"""Sharpening: add back the difference between the image and its local average.

    .. math:: S = F + a\,(F - B * F) = \big((1 + a)\,\delta - a\,B\big) * F

    With the defaults (3×3 box, :math:`a = 1`) this is the course's
    sharpening kernel :math:`2\delta - \frac{1}{9}\mathbf{1}_{3\times3}`;
    ``smoothing="gaussian"`` uses :math:`G_\sigma` for :math:`B` (unsharp
    masking). The result is clipped to [0, 1].

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
    amount : float
        :math:`a`, the strength (0 returns the image).
    smoothing : {"box", "gaussian"}
    size : int
        Box side, for ``smoothing="box"``.
    sigma : float
        Gaussian standard deviation, for ``smoothing="gaussian"``.
    boundary : {"mirror", "replicate", "wrap", "zero", "crop"}

    Returns
    -------
    sharpened : float32 ndarray, same kind as ``image``

    References
    ----------
    .. [1] Szeliski (2022), section 3.2 ("unsharp masking").
    """
    taps = np.full(size, 1.0 / size) if smoothing == "box" else gaussian_kernel_1d(sigma)
    smooth = _separable(image, taps, boundary)
    base = crop_valid(image, (taps.size, taps.size)) if boundary == "crop" else image
    out = (1.0 + amount) * base - np.float32(amount) * smooth
    return np.clip(out, 0.0, 1.0).astype(np.float32, copy=False)


@node("filters.to_image", version=1)
def to_image(image: FloatImage, *, method: Literal["clip", "minmax"] = "clip") -> Image:
    r"""Turn a filter response into an image in [0, 1].

    ``clip`` keeps values and clips them to [0, 1]; ``minmax`` rescales
    linearly, :math:`(F - \min F) / (\max F - \min F)` (a constant image
    becomes 0).

    Parameters
    ----------
    image : FloatImage
        A filter response (any range).
    method : {"clip", "minmax"}
        ``clip`` keeps values in [0, 1] and clips the rest; ``minmax`` maps the
        smallest value to 0 and the largest to 1.

    Returns
    -------
    image : float32 ndarray in [0, 1]
    """
    if method == "clip":
        return np.clip(image, 0.0, 1.0).astype(np.float32)
    low, high = float(image.min()), float(image.max())
    if high == low:
        return np.zeros_like(image, dtype=np.float32)
    return ((image - low) / (high - low)).astype(np.float32)
