"""Depth and 3-D points from disparity (notes: "3D coordinates from disparity")."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from graphvision import Camera, Image, Points3D, node

from ..shared.params import Count, Positive
from ._ports import Depth, Disparity, PointColours

__all__ = ["ColouredPoints", "coloured_points", "depth_from_disparity", "depth_points"]


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
    return _points(depth, camera.K, step)


def _points(depth: np.ndarray, K: np.ndarray, step: int) -> np.ndarray:
    rows, cols = depth.shape
    y, x = np.mgrid[0:rows:step, 0:cols:step]
    z = depth[::step, ::step].astype(np.float64)
    valid = np.isfinite(z)
    pixels = np.stack([x[valid], y[valid], np.ones(int(valid.sum()))])
    rays = np.linalg.solve(K, pixels)
    return np.ascontiguousarray((rays * z[valid]).T)


class ColouredPoints(NamedTuple):
    points: Points3D
    colours: PointColours


@node("stereo.coloured_points", version=1)
def coloured_points(
    depth: Depth, camera: Camera, image: Image, *, step: Count = 1
) -> ColouredPoints:
    r"""The 3-D point of every valid pixel (as ``stereo.depth_points``) with its colour.

    :math:`(X, Y, Z) = Z\, K^{-1} (x, y, 1)^T`, and the colour of point :math:`k` is
    the image's pixel :math:`(x, y)` it came from, so viewers can draw the cloud in the
    scene's colours as well as by depth.

    Parameters
    ----------
    depth : Depth
        Depth along the optical axis (NaN where invalid).
    camera : Camera
        Gives K (its pose is not applied: points are in camera coordinates).
    image : Image
        The image the depth was measured for (the left view), of the depth's size; a
        gray image gives gray colours.
    step : int
        Keep every ``step``-th pixel along each axis (a lighter cloud).

    Returns
    -------
    points : Points3D
        One row per valid pixel, row-major (the rows of ``stereo.depth_points``).
    colours : PointColours
        The RGB of each point's pixel, row for row.

    References
    ----------
    .. [1] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., §6.1 (back-projecting
       a pixel at known depth along its ray :math:`K^{-1} x`).
    """
    if image.shape[:2] != depth.shape:
        raise ValueError(
            f"the image is {image.shape[1]}×{image.shape[0]} but the depth map is "
            f"{depth.shape[1]}×{depth.shape[0]}: give the image the depth was measured for"
        )
    valid = np.isfinite(depth[::step, ::step])
    picked = image[::step, ::step][valid]
    colours = picked[:, :3] if picked.ndim == 2 else np.repeat(picked[:, None], 3, axis=1)
    return ColouredPoints(_points(depth, camera.K, step), colours.astype(np.float32))
