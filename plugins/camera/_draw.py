"""Drawings and summaries: detected board corners, a camera's intrinsics, round-trip residuals."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, Camera, ColorImage, Float, FloatImage, Image, node

from ..shared.draw import colour_canvas, draw_circle, draw_segment
from ._model import check_intrinsics
from ._projection import distort_pixels, undistort_pixels

__all__ = ["draw_board", "intrinsics", "roundtrip_residual"]


@node("camera.draw_board", version=1)
def draw_board(
    views: Array,
    corners: Array,
    *,
    view: Annotated[int, Field(ge=0)] = 0,
) -> ColorImage:
    """One view with its detected corners joined in their order, red (first) to blue (last).

    Parameters
    ----------
    views : Array
        A gray image H×W or a stack N×H×W.
    corners : Array
        Corners M×2, or N×M×2 for a stack (NaN where no board was found).
    view : int
        Which view of the stack to draw.

    Raises
    ------
    ValueError
        When ``view`` is beyond the stack.
    """
    stack = views[None] if views.ndim == 2 else views
    points = corners[None] if corners.ndim == 2 else corners
    if view >= len(stack) or view >= len(points):
        raise ValueError(f"view {view} is out of range: there are {len(stack)} views")
    canvas = colour_canvas(np.clip(stack[view], 0, 1))
    xy = points[view]
    if not np.isfinite(xy).all():
        return canvas
    t = np.linspace(0, 1, len(xy))[:, None]
    colours = (1 - t) * np.array([0.95, 0.1, 0.1]) + t * np.array([0.1, 0.3, 0.95])
    for k in range(len(xy) - 1):
        draw_segment(canvas, xy[k], xy[k + 1], colours[k])
    for (x, y), colour in zip(xy, colours, strict=True):
        draw_circle(canvas, x, y, 4, colour)
    return canvas


class Intrinsics(NamedTuple):
    K: Array
    distortion: Array


@node("camera.intrinsics", version=1)
def intrinsics(camera: Camera) -> Intrinsics:
    """The calibration matrix K and distortion ``(k1, k2, p1, p2, k3)`` of a camera.

    Parameters
    ----------
    camera : Camera
        The camera.
    """
    return Intrinsics(camera.K.copy(), camera.distortion.copy())


class Residual(NamedTuple):
    residual: FloatImage
    rms: Float


@node("camera.roundtrip_residual", version=1)
def roundtrip_residual(original: Image, restored: Image, camera: Camera) -> Residual:
    """The difference between an image and its distorted-then-undistorted copy.

    Only pixels whose round trip stays inside the image count: p must map to
    a distorted position inside the frame and back (borders lost to the
    warp are not errors of the inversion).

    Parameters
    ----------
    original : Image
        The image before distortion.
    restored : Image
        ``camera.undistort_image`` of ``camera.distort_image`` of it.
    camera : Camera
        K and the distortion used.

    Returns
    -------
    residual : restored − original, 0 outside the valid region
    rms : root mean square of the residual over the valid region
    """
    check_intrinsics(camera)
    if original.shape != restored.shape:
        raise ValueError(
            f"original and restored must have the same shape, got {original.shape} and "
            f"{restored.shape}"
        )
    h, w = original.shape[:2]
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    pixels = np.column_stack([u.ravel(), v.ravel()])
    distorted = distort_pixels(pixels, camera.K, camera.distortion)
    back = undistort_pixels(distorted, camera.K, camera.distortion)
    margin = 2.0
    valid = (
        (distorted[:, 0] >= margin) & (distorted[:, 0] <= w - 1 - margin)
        & (distorted[:, 1] >= margin) & (distorted[:, 1] <= h - 1 - margin)
        & (np.abs(back - pixels).max(axis=1) < 1e-6)
    )  # fmt: skip
    # the restored pixel p read the distorted image at d(p), which read the original at
    # d⁻¹(d(p)) = p: both reads stay inside the frame when d(p) does and p does
    mask = valid.reshape(h, w)
    diff = restored.astype(np.float64) - original
    residual = np.where(mask[..., None] if diff.ndim == 3 else mask, diff, 0.0)
    return Residual(residual.astype(np.float32), float(np.sqrt((diff[mask] ** 2).mean())))
