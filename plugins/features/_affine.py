"""Affine shape adaptation of keypoints by the iterated second-moment matrix."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import GrayImage, Keypoints, KeypointSet, node

from ..shared.params import Positive

__all__ = ["affine_adapt"]

GRID = 15  # samples per side of the normalised window


def _inverse_sqrt(m: np.ndarray) -> np.ndarray:
    """:math:`M^{-1/2}` of symmetric positive definite 2×2 matrices, batched."""
    values, vectors = np.linalg.eigh(m)
    values = np.maximum(values, 1e-12)
    return vectors @ (vectors.transpose(0, 2, 1) / np.sqrt(values)[:, :, None])


@node("features.affine_adapt", version=1)
def affine_adapt(
    image: GrayImage,
    keypoints: Keypoints,
    *,
    iterations: Annotated[int, Field(ge=1, le=50)] = 10,
    window: Positive = 3.0,
    isotropy: Annotated[float, Field(gt=0, le=1)] = 0.95,
) -> Keypoints:
    r"""Affine adaptation: make each keypoint's region isotropic in its own frame.

    Iteratively (Lindeberg & Gårding; Mikolajczyk & Schmid):

    1. in the current normalised frame :math:`x = c + s\,U g` (a circular
       window of ``window`` scales), compute the gradient covariance
       :math:`M = \sum w\, \nabla I \nabla I^T`;
    2. update :math:`U \leftarrow M^{-1/2} U`, scaled to :math:`\det U = 1`;
    3. stop when :math:`\lambda_{min}(M) / \lambda_{max}(M) \ge` ``isotropy``.

    The ellipse :math:`\{c + s U g : |g| \le 1\}` is the adapted region;
    in :math:`E = U S U^T` terms, the rotation is :math:`U^{-1}`, the scale
    :math:`S^{-1/2}`.

    Parameters
    ----------
    image : GrayImage
        The image the keypoints were detected in.
    keypoints : Keypoints
        Keypoints to adapt (their scales set the integration windows).
    iterations : int
        Maximum number of normalise–re-estimate steps per keypoint.
    window : float
        Integration window radius in units of the keypoint's scale.
    isotropy : float
        Stop when the ratio of the second-moment eigenvalues reaches this (1 = a circle).

    Returns
    -------
    keypoints : the same keypoints with ``affine`` set to U (2×2, det 1, acting on (x, y))

    References
    ----------
    .. [1] T. Lindeberg, J. Gårding, "Shape-adapted smoothing in estimation
       of 3-D shape cues from affine deformations of local 2-D brightness
       structure", Image and Vision Computing 15(6), 1997.
    .. [2] K. Mikolajczyk, C. Schmid, "Scale & affine invariant interest
       point detectors", IJCV 60(1), 2004.
    """
    import scipy.ndimage as ndi

    from ..shared.separable import smooth_gaussian

    count = len(keypoints)
    if count == 0:
        return keypoints
    smooth = smooth_gaussian(image.astype(np.float64), 1.0)
    axis = np.linspace(-1.0, 1.0, GRID)
    gx, gy = np.meshgrid(axis, axis)
    grid = np.stack([gx.ravel(), gy.ravel()])  # (2, G²), (x, y)
    weight = np.exp(-(gx**2 + gy**2) / (2 * 0.5**2))
    shape = keypoints.affine.copy()
    active = np.ones(count, bool)
    for _ in range(iterations):
        index = np.flatnonzero(active)
        if not len(index):
            break
        span = (window * keypoints.scale[index])[:, None, None]
        points = keypoints.xy[index][:, :, None] + span * (shape[index] @ grid)
        patch = ndi.map_coordinates(
            smooth, [points[:, 1].ravel(), points[:, 0].ravel()], order=1, mode="nearest"
        ).reshape(len(index), GRID, GRID)
        dy, dx = np.gradient(patch, axis=(1, 2))
        moment = np.empty((len(index), 2, 2))
        moment[:, 0, 0] = (weight * dx * dx).sum(axis=(1, 2))
        moment[:, 1, 1] = (weight * dy * dy).sum(axis=(1, 2))
        moment[:, 0, 1] = moment[:, 1, 0] = (weight * dx * dy).sum(axis=(1, 2))
        values = np.linalg.eigvalsh(moment)
        flat = values[:, 1] <= 1e-12
        isotropic = flat | (values[:, 0] >= isotropy * values[:, 1])
        update = index[~isotropic]
        new = _inverse_sqrt(moment[~isotropic]) @ shape[update]
        det = np.sqrt(np.abs(np.linalg.det(new)))[:, None, None]
        shape[update] = new / det
        active[index[isotropic]] = False
    return KeypointSet(
        keypoints.xy, keypoints.scale, keypoints.orientation, keypoints.response, shape
    )
