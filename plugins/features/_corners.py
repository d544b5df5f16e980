"""Harris and Hessian corners, Laplacian-of-Gaussian blobs with scale selection."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import GrayImage, Keypoints, KeypointSet, node

from ..shared.checks import ordered
from ..shared.params import Count, Fraction

__all__ = ["harris", "harris_response", "hessian", "log_blobs"]

Sigma = Annotated[float, Field(gt=0, le=50)]


def _peaks(
    response: np.ndarray, min_distance: int, threshold_rel: float, limit: int, scale: float
) -> KeypointSet:
    """Local maxima (non-maximum suppression in a (2d+1)² window) above a relative threshold."""
    import scipy.ndimage as ndi

    top = float(response.max())
    if top <= 0:
        return KeypointSet.empty()
    local = ndi.maximum_filter(response, size=2 * min_distance + 1, mode="constant", cval=-np.inf)
    peak = (response == local) & (response > threshold_rel * top)
    border = min_distance
    peak[:border] = peak[-border:] = False
    peak[:, :border] = peak[:, -border:] = False
    ys, xs = np.nonzero(peak)
    strength = response[ys, xs].astype(np.float64)
    order = np.argsort(-strength, kind="stable")
    if limit:
        order = order[:limit]
    count = len(order)
    return KeypointSet(
        np.column_stack([xs[order], ys[order]]).astype(np.float64),
        np.full(count, scale),
        np.zeros(count),
        strength[order],
    )


def harris_response(image: np.ndarray, sigma_d: float, sigma_i: float, alpha: float) -> np.ndarray:
    r""":math:`R = \det M - \alpha\,\mathrm{tr}^2 M`, M the weighted gradient covariance."""
    from ..shared.separable import correlate_separable, gaussian_taps, smooth_gaussian

    data = image.astype(np.float32)
    smooth, slope = gaussian_taps(sigma_d, 3.0), gaussian_taps(sigma_d, 3.0, order=1)
    ix = correlate_separable(data, smooth, slope)
    iy = correlate_separable(data, slope, smooth)
    sxx = smooth_gaussian(ix * ix, sigma_i, truncate=3.0)
    syy = smooth_gaussian(iy * iy, sigma_i, truncate=3.0)
    sxy = smooth_gaussian(ix * iy, sigma_i, truncate=3.0)
    trace = sxx + syy
    return (sxx * syy - sxy * sxy - np.float32(alpha) * trace * trace).astype(np.float64)


@node("features.harris", version=1)
def harris(
    image: GrayImage,
    *,
    sigma_d: Sigma = 1.0,
    sigma_i: Sigma = 2.0,
    alpha: Annotated[float, Field(ge=0, le=0.25)] = 0.04,
    threshold_rel: Fraction = 0.01,
    min_distance: Count = 3,
    max_keypoints: Annotated[int, Field(ge=0)] = 2000,
) -> Keypoints:
    r"""Harris corners: both eigenvalues of the gradient covariance large.

    .. math::
        M = \begin{bmatrix} G(\sigma_i) * I_x^2 & G(\sigma_i) * I_x I_y \\
                            G(\sigma_i) * I_x I_y & G(\sigma_i) * I_y^2 \end{bmatrix},
        \qquad R = \det M - \alpha\, \mathrm{tr}^2 M

    with derivatives of a Gaussian of :math:`\sigma_d` (kernels of half size
    :math:`3\sigma`, float32); corners are local
    maxima of :math:`R` (non-maximum suppression within ``min_distance``)
    above ``threshold_rel`` times the strongest.

    Parameters
    ----------
    image : GrayImage
        The image to detect in.
    sigma_d : float
        Derivative scale: σ of the Gaussian derivative filters.
    sigma_i : float
        Integration scale: σ of the Gaussian window over the gradient products.
    alpha : float
        The α of :math:`R = \det M - \alpha \operatorname{tr}^2 M` (0.04–0.06).
    threshold_rel : float
        Keep responses above this fraction of the largest response.
    min_distance : int
        Minimum distance in pixels between two kept corners (non-maximum suppression).
    max_keypoints : int
        Keep at most this many, strongest first (0: no limit).

    Returns
    -------
    keypoints : scale :math:`\sigma_i`, orientation 0, response R, strongest first

    References
    ----------
    .. [1] C. Harris, M. Stephens, "A combined corner and edge detector",
       Alvey Vision Conference, 1988.
    """
    response = harris_response(image, sigma_d, sigma_i, alpha)
    return _peaks(response, min_distance, threshold_rel, max_keypoints, sigma_i)


@node("features.hessian", version=1)
def hessian(
    image: GrayImage,
    *,
    sigma: Sigma = 2.0,
    threshold_rel: Fraction = 0.01,
    min_distance: Count = 3,
    max_keypoints: Annotated[int, Field(ge=0)] = 2000,
) -> Keypoints:
    r"""Hessian detector: maxima of the scale-normalised determinant of the Hessian.

    .. math:: R = \sigma^4 \det \begin{bmatrix} I_{xx} & I_{xy} \\ I_{xy} & I_{yy} \end{bmatrix}
              = \sigma^4 (I_{xx} I_{yy} - I_{xy}^2)

    with second derivatives of a Gaussian of :math:`\sigma`. It responds to
    blobs and corners (strong curvature in both directions), not to edges.

    Parameters
    ----------
    image : GrayImage
        The image to detect in.
    sigma : float
        Scale of the Gaussian second derivatives.
    threshold_rel : float
        Keep responses above this fraction of the largest response.
    min_distance : int
        Minimum distance in pixels between two kept points.
    max_keypoints : int
        Keep at most this many, strongest first (0: no limit).

    Returns
    -------
    keypoints : scale σ, orientation 0, response R

    References
    ----------
    .. [1] P. R. Beaudet, "Rotationally invariant image operators", ICPR 1978.
    """
    from ..shared.separable import gaussian_derivative

    data = image.astype(np.float64)
    ixx = gaussian_derivative(data, sigma, (0, 2))
    iyy = gaussian_derivative(data, sigma, (2, 0))
    ixy = gaussian_derivative(data, sigma, (1, 1))
    response = sigma**4 * (ixx * iyy - ixy * ixy)
    return _peaks(response, min_distance, threshold_rel, max_keypoints, sigma)


@node("features.log", version=1, check=ordered(("min_sigma", "max_sigma")))
def log_blobs(
    image: GrayImage,
    *,
    min_sigma: Sigma = 2.0,
    max_sigma: Sigma = 16.0,
    scales: Annotated[int, Field(ge=2, le=64)] = 10,
    threshold: Annotated[float, Field(ge=0)] = 0.05,
    max_keypoints: Annotated[int, Field(ge=0)] = 2000,
) -> Keypoints:
    r"""Blobs at their characteristic scale: extrema of the scale-normalised LoG in scale space.

    .. math:: L(x, y, \sigma) = \sigma^2 \,|\nabla^2 G(\sigma) * I|

    over ``scales`` values of σ spaced geometrically from ``min_sigma`` to
    ``max_sigma``; a keypoint is a maximum among its 26 neighbours in
    (x, y, σ) above ``threshold``, and its σ is the characteristic scale (a
    disk of radius r responds most at :math:`\sigma = r / \sqrt 2`).

    Parameters
    ----------
    image : GrayImage
        The image to detect in.
    min_sigma, max_sigma : float
        The range of scales searched.
    scales : int
        Number of scales, spaced geometrically from ``min_sigma`` to ``max_sigma``.
    threshold : float
        Minimum absolute scale-normalised response.
    max_keypoints : int
        Keep at most this many, strongest first (0: no limit).

    Returns
    -------
    keypoints : scale σ, orientation 0, response L

    References
    ----------
    .. [1] T. Lindeberg, "Feature detection with automatic scale selection",
       IJCV 30(2), 1998.
    """
    import scipy.ndimage as ndi

    from ..shared.separable import gaussian_derivative

    sigmas = np.geomspace(min_sigma, max_sigma, scales)
    data = image.astype(np.float64)

    def laplacian(s: float) -> np.ndarray:  # ndi.gaussian_laplace, compiled
        return gaussian_derivative(data, s, (2, 0)) + gaussian_derivative(data, s, (0, 2))

    stack = np.stack([s * s * np.abs(laplacian(s)) for s in sigmas])
    local = ndi.maximum_filter(stack, size=3, mode="constant", cval=-np.inf)
    peak = (stack == local) & (stack > threshold)
    level, ys, xs = np.nonzero(peak)
    strength = stack[level, ys, xs]
    order = np.argsort(-strength, kind="stable")
    if max_keypoints:
        order = order[:max_keypoints]
    return KeypointSet(
        np.column_stack([xs[order], ys[order]]).astype(np.float64),
        sigmas[level[order]],
        np.zeros(len(order)),
        strength[order],
    )
