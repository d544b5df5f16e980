r"""Image derivatives: finite differences, Sobel, Prewitt and derivatives of a Gaussian.

Every kernel is scaled so that a unit ramp ``I(x, y) = x`` gives a derivative
of exactly 1, whatever its kind: magnitudes of different kinds compare
directly (OpenCV's unnormalised Sobel is 8× ours, Prewitt 6×).

x is the column index and y the row index (downwards); the gradient
orientation :math:`\theta = \operatorname{atan2}(\partial_y I, \partial_x I)`
is measured from the x axis towards y.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Conformance, FloatImage, GrayImage, Kernel, node

from ..filters._boundary import scipy_mode

__all__ = [
    "DERIVATIVES",
    "EdgeBoundary",
    "Gradient",
    "derivative",
    "derivative_kernel",
    "derivative_taps",
    "gradient",
    "gradient_images",
]

Derivative = Literal["forward", "central", "sobel", "prewitt", "gaussian"]
DERIVATIVES: tuple[str, ...] = ("forward", "central", "sobel", "prewitt", "gaussian")
EdgeBoundary = Literal["mirror", "replicate", "wrap", "zero"]
Axis = Literal["x", "y"]
Sigma = Annotated[
    float, Field(gt=0, le=50, description="Gaussian standard deviation in pixels (kind gaussian).")
]


def derivative_taps(kind: str, sigma: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    r"""The separable pair (derivative taps, smoothing taps) of a derivative kind, for correlation.

    The derivative taps :math:`d` satisfy :math:`\sum_u u\, d(u) = 1` and the
    smoothing taps sum to one. For ``gaussian``,
    :math:`d(u) \propto u\, e^{-u^2/2\sigma^2}` (correlation with
    :math:`-G'`, i.e. convolution with :math:`G'`) and the smoothing is the
    Gaussian itself, half size :math:`\lceil 3\sigma \rceil`.
    """
    if kind == "forward":  # centre at index 1: I(x + 1) - I(x)
        return np.array([0.0, -1.0, 1.0]), np.array([1.0])
    if kind == "central":
        return np.array([-0.5, 0.0, 0.5]), np.array([1.0])
    if kind == "sobel":
        return np.array([-0.5, 0.0, 0.5]), np.array([0.25, 0.5, 0.25])
    if kind == "prewitt":
        return np.array([-0.5, 0.0, 0.5]), np.full(3, 1.0 / 3.0)
    if kind == "gaussian":
        half = math.ceil(3.0 * sigma)
        u = np.arange(-half, half + 1, dtype=np.float64)
        g = np.exp(-(u * u) / (2.0 * sigma * sigma))
        return u * g / np.sum(u * u * g), g / g.sum()
    raise ValueError(f"unknown derivative kind {kind!r}; expected one of {DERIVATIVES}")


def _derivative(image: np.ndarray, axis: str, kind: str, sigma: float, boundary: str) -> np.ndarray:
    from ..shared.separable import correlate_separable

    d, s = derivative_taps(kind, sigma)
    column_taps, row_taps = (s, d) if axis == "x" else (d, s)
    data = image.astype(np.float32, copy=False)
    return correlate_separable(data, column_taps, row_taps, scipy_mode(boundary))


def gradient_images(
    image: np.ndarray, kind: str = "gaussian", sigma: float = 1.0, boundary: str = "mirror"
) -> tuple[np.ndarray, np.ndarray]:
    """``(∂I/∂x, ∂I/∂y)`` as float32 arrays, by the compiled separable core."""
    return (
        _derivative(image, "x", kind, sigma, boundary),
        _derivative(image, "y", kind, sigma, boundary),
    )


@node("edges.derivative_kernel", version=1)
def derivative_kernel(
    *, axis: Axis = "x", kind: Derivative = "sobel", sigma: Sigma = 1.0
) -> Kernel:
    r"""The 2-D correlation kernel of a derivative: the outer product of its separable taps.

    ``forward`` is the course's :math:`[-1, 1]`, ``central`` is
    :math:`\frac12[-1, 0, 1]`, ``sobel`` and ``prewitt`` smooth across with
    :math:`\frac14[1, 2, 1]` and :math:`\frac13[1, 1, 1]`, ``gaussian`` is the
    derivative of a Gaussian, :math:`\partial G_\sigma / \partial x`.

    Parameters
    ----------
    axis : {"x", "y"}
        Differentiate along columns (x) or rows (y).
    kind : {"forward", "central", "sobel", "prewitt", "gaussian"}
        The derivative filter.
    sigma : float
        Standard deviation of the Gaussian (``kind="gaussian"`` only).

    Returns
    -------
    kernel : float64 ndarray, centred at ``(rows // 2, cols // 2)``

    Examples
    --------
    >>> derivative_kernel(axis="x", kind="sobel") * 8
    array([[-1.,  0.,  1.],
           [-2.,  0.,  2.],
           [-1.,  0.,  1.]])
    """
    d, s = derivative_taps(kind, sigma)
    kernel = np.outer(s, d)
    return kernel if axis == "x" else np.ascontiguousarray(kernel.T)


@node(
    "edges.derivative",
    version=1,
    conformance=Conformance("max_abs", 1e-5),
)
def derivative(
    image: GrayImage,
    *,
    axis: Axis = "x",
    kind: Derivative = "gaussian",
    sigma: Sigma = 1.0,
    boundary: EdgeBoundary = "mirror",
) -> FloatImage:
    r"""A first derivative of the image along x or y, separably.

    Smoothing and differentiating commute (the course's
    :math:`\frac{\partial}{\partial x}(I * G) = I * \frac{\partial G}{\partial x}`),
    so ``kind="gaussian"`` is one separable filter: :math:`\partial G/\partial x`
    along the rows and :math:`G` along the columns.

    Parameters
    ----------
    image : (H, W) float32 ndarray
        The gray image.
    axis : {"x", "y"}
        Differentiate along columns (x) or rows (y).
    kind : {"forward", "central", "sobel", "prewitt", "gaussian"}
        The derivative filter (see :func:`derivative_kernel`).
    sigma : float
        Standard deviation of the Gaussian (``kind="gaussian"`` only).
    boundary : {"mirror", "replicate", "wrap", "zero"}
        What the filter sees beyond the image.

    Returns
    -------
    derivative : (H, W) float32 ndarray, in intensity per pixel

    References
    ----------
    .. [1] Szeliski, *Computer Vision: Algorithms and Applications*, 2nd ed.,
       2022, section 7.2.1.
    """
    return _derivative(image, axis, kind, sigma, boundary)


class Gradient(NamedTuple):
    dx: FloatImage
    dy: FloatImage
    magnitude: FloatImage
    orientation: FloatImage


@node("edges.gradient", version=1)
def gradient(
    image: GrayImage,
    *,
    kind: Derivative = "gaussian",
    sigma: Sigma = 1.0,
    boundary: EdgeBoundary = "mirror",
) -> Gradient:
    r"""Gradient of the image, its magnitude and orientation.

    .. math:: \nabla I = (\partial_x I, \partial_y I)

    .. math:: m = \sqrt{(\partial_x I)^2 + (\partial_y I)^2}, \qquad
              \theta = \operatorname{atan2}(\partial_y I, \partial_x I) \in (-\pi, \pi]

    The gradient points in the direction of the greatest intensity increase.

    Parameters
    ----------
    image : (H, W) float32 ndarray
        The gray image.
    kind : {"forward", "central", "sobel", "prewitt", "gaussian"}
        The derivative filter.
    sigma : float
        Standard deviation of the Gaussian (``kind="gaussian"`` only).
    boundary : {"mirror", "replicate", "wrap", "zero"}
        What the filter sees beyond the image.

    Returns
    -------
    dx, dy : (H, W) float32 ndarray
    magnitude : (H, W) float32 ndarray
    orientation : (H, W) float32 ndarray, radians

    References
    ----------
    .. [1] Szeliski (2022), section 7.2.1 (eq. 7.19).
    """
    dx, dy = gradient_images(image, kind, sigma, boundary)
    magnitude = np.hypot(dx, dy).astype(np.float32)
    orientation = np.arctan2(dy, dx).astype(np.float32)
    return Gradient(dx, dy, magnitude, orientation)
