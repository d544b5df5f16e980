"""Depth and 3-D points from disparity (notes: "3D coordinates from disparity")."""

from __future__ import annotations

import numpy as np

from graphvision import Camera, Points3D, node

from ..shared.params import Count, Positive
from ._ports import Depth, Disparity

__all__ = ["depth_from_disparity", "depth_points"]


@node("stereo.depth_from_disparity", version=1)
def depth_from_disparity(
    disparity: Disparity,
    *,
    focal: Positive = 1.0,
    baseline: Positive = 1.0,
    doffs: float = 0.0,
) -> Depth:
    r"""Depth of every pixel of a rectified pair from its disparity.

    .. math:: Z = \frac{f\, b}{d + d_{\text{offs}}}

    with :math:`f` the focal length in pixels, :math:`b` the baseline and
    :math:`d_{\text{offs}}` the difference of the principal points' x
    (Middlebury's ``doffs``; 0 when both cameras share it). A pixel with
    :math:`d + d_{\text{offs}} \le 0` (a point at or beyond infinity) is
    invalid (NaN), like a pixel without disparity.

    Parameters
    ----------
    disparity : Disparity
        Disparity in pixels (NaN where invalid).
    focal : float
        Focal length f, pixels (with the default 1 and ``baseline`` 1, Z = 1/d).
    baseline : float
        Distance b between the camera centres; Z comes in its unit.
    doffs : float
        x-difference of the principal points, pixels.

    References
    ----------
    .. [1] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., §9.1 (a
       rectified pair), and the Middlebury 2014 calibration files' ``doffs``.
    """
    shifted = disparity.astype(np.float64) + doffs
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.where(shifted > 0, focal * baseline / shifted, np.nan)
    return depth.astype(np.float32)


@node("stereo.depth_points", version=1)
def depth_points(depth: Depth, camera: Camera, *, step: Count = 1) -> Points3D:
    r"""The 3-D point of every valid pixel, in the camera's coordinates.

    :math:`(X, Y, Z) = Z\, K^{-1} (x, y, 1)^T`.

    Parameters
    ----------
    depth : Depth
        Depth along the optical axis (NaN where invalid).
    camera : Camera
        Gives K (its pose is not applied: points are in camera coordinates).
    step : int
        Keep every ``step``-th pixel along each axis (a lighter cloud).

    Returns
    -------
    Points3D
        One row per valid pixel, row-major.
    """
    rows, cols = depth.shape
    y, x = np.mgrid[0:rows:step, 0:cols:step]
    z = depth[::step, ::step].astype(np.float64)
    valid = np.isfinite(z)
    pixels = np.stack([x[valid], y[valid], np.ones(int(valid.sum()))])
    rays = np.linalg.solve(camera.K, pixels)
    return np.ascontiguousarray((rays * z[valid]).T)
