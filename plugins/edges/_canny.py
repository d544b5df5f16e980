"""Canny's edge detector: derivative of Gaussian, non-maximum suppression, hysteresis."""

from __future__ import annotations

from typing import Annotated, Any, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import BinaryImage, Conformance, FloatImage, GrayImage, node

from ..shared.checks import all_of, ordered
from ._derivatives import EdgeBoundary, gradient_images

__all__ = ["Canny", "canny", "canny_edges", "hysteresis", "non_maximum_suppression"]


def non_maximum_suppression(
    dx: np.ndarray, dy: np.ndarray, magnitude: np.ndarray, low: float
) -> np.ndarray:
    r"""Pixels of magnitude at least ``low`` (and above 0) that are a maximum along the gradient.

    The two neighbours are the points :math:`p \pm u` with
    :math:`u = \nabla I / \|\nabla I\|_\infty` (on the 3×3 square around the
    pixel), their magnitudes interpolated linearly between the two pixels
    they fall between (the image edge replicated). With u turned towards
    increasing x (increasing y when u is vertical), a pixel survives when it
    exceeds the neighbour behind, :math:`m(p) > m(p - u)`, and is at least the
    one ahead, :math:`m(p) \ge m(p + u)`: of two equal pixels across a step
    that lies exactly between them, the first survives, so the edge stays one
    pixel thick (the symmetric test :math:`\ge` on both sides keeps both; the
    rule is OpenCV's). One compiled pass (:mod:`._kernels`).
    """
    from ._kernels import suppress_non_maxima

    return suppress_non_maxima(dx, dy, magnitude, np.float32(low))


def hysteresis(weak: np.ndarray, strong: np.ndarray) -> np.ndarray:
    """Pixels of ``weak`` 8-connected (through ``weak``) to a pixel of ``strong``.

    Tracing a curve from every strong pixel while the magnitude stays above
    the low threshold reaches exactly the 8-connected components of the weak
    mask that contain a strong pixel: one labelling pass finds them all.
    """
    from ..regions import label_components

    labels = label_components(weak, connectivity=8)
    keep = np.zeros(int(labels.max()) + 1, dtype=bool)
    keep[labels[strong & weak]] = True
    keep[0] = False
    return keep[labels]


def canny_edges(
    image: np.ndarray,
    sigma: float = 1.0,
    low: float = 0.05,
    high: float = 0.1,
    thresholds: str = "absolute",
    boundary: str = "mirror",
) -> tuple[np.ndarray, np.ndarray]:
    """Edge mask and gradient magnitude (see :func:`canny`)."""
    from ._kernels import gradient_magnitude

    dx, dy = gradient_images(image, "gaussian", sigma, boundary)
    if dx.dtype == np.float32 and dy.dtype == np.float32:
        magnitude = gradient_magnitude(np.ascontiguousarray(dx), np.ascontiguousarray(dy))
    else:
        magnitude = np.hypot(dx, dy).astype(np.float32)
    if thresholds == "quantile":
        low, high = (float(q) for q in np.quantile(magnitude, [low, high]))
    # a zero gradient is never an edge, whatever the thresholds (constant images have none);
    # one compiled pass: suppression, then hysteresis as a flood from the strong pixels
    from ._kernels import canny_mask

    edges = canny_mask(dx, dy, magnitude, np.float32(low), np.float32(high))
    return edges, magnitude


class Canny(NamedTuple):
    edges: BinaryImage
    magnitude: FloatImage


Threshold = Annotated[float, Field(ge=0, description="Absolute magnitude or quantile in [0, 1].")]


def _quantiles(**params: Any) -> None:
    """Quantile thresholds lie in [0, 1] (``low`` is at most ``high``, checked apart)."""
    if params["thresholds"] == "quantile" and params["high"] > 1:
        raise ValueError(f"quantile thresholds lie in [0, 1], got high={params['high']:g}")


@node(
    "edges.canny",
    version=3,
    check=all_of(ordered(("low", "high")), _quantiles),
    conformance=Conformance(
        "recall",
        0.9,
        radius=1.0,
        note=(
            "OpenCV suppresses non-maxima along four quantised directions without interpolation, "
            "on 16-bit gradients; weak edges near the thresholds may join or leave a chain (92 % "
            "of edge pixels within one pixel on a noisy scene with quantile thresholds)"
        ),
    ),
)
def canny(
    image: GrayImage,
    *,
    sigma: Annotated[float, Field(gt=0, le=50)] = 1.0,
    low: Threshold = 0.05,
    high: Threshold = 0.1,
    thresholds: Literal["absolute", "quantile"] = "absolute",
    boundary: EdgeBoundary = "mirror",
) -> Canny:
    r"""Canny's edge detector.

    1. Filter with the derivative of a Gaussian (smooth and differentiate in
       one separable pass): :math:`\nabla (G_\sigma * I) = \nabla G_\sigma * I`.
    2. Gradient magnitude :math:`m = \|\nabla\|` and direction.
    3. Non-maximum suppression: keep pixels whose magnitude is a maximum
       along the gradient direction, the neighbours' magnitudes interpolated;
       a tie between two pixels keeps the one at lower x (lower y), so a step
       lying exactly between two pixels is marked once.
    4. Hysteresis: start tracing an edge only at pixels with
       :math:`m \ge k_\text{high}` and continue while :math:`m \ge k_\text{low}`
       (8-connected).

    The magnitude is in intensity per pixel (a unit step blurred by
    :math:`\sigma` peaks at :math:`1/(\sigma\sqrt{2\pi})`, 0.4 for
    :math:`\sigma = 1`). With ``thresholds="quantile"``, ``low`` and ``high``
    are quantiles of the magnitude over the image (0.8 and 0.9 keep the
    strongest tenth as seeds), as in scikit-image's ``use_quantiles``. An
    image without gradient has no edges whatever the thresholds.

    Parameters
    ----------
    image : (H, W) float32 ndarray
        The gray image.
    sigma : float
        Standard deviation of the Gaussian: the scale of the edges found.
    low, high : float
        Hysteresis thresholds :math:`k_\text{low} \le k_\text{high}`.
    thresholds : {"absolute", "quantile"}
        How ``low`` and ``high`` are read.
    boundary : {"mirror", "replicate", "wrap", "zero"}
        What the filter sees beyond the image.

    Returns
    -------
    edges : (H, W) bool ndarray, one pixel thick
    magnitude : (H, W) float32 ndarray, the gradient magnitude

    References
    ----------
    .. [1] J. Canny, "A computational approach to edge detection", IEEE
       TPAMI 8(6), 1986.
    .. [2] Szeliski (2022), section 7.2.1.
    """
    edges, magnitude = canny_edges(image, sigma, low, high, thresholds, boundary)
    return Canny(edges, magnitude)
