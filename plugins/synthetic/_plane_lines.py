"""A ground plane ruled by two families of parallel lines, seen by a known camera.

Truth for vanishing points: the lines of direction d meet in the image at
:math:`v \\sim K R d`, and the plane's horizon is :math:`l \\sim K^{-T} R n`
(n the plane normal), the line through both vanishing points.
"""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, Camera, GrayImage, PinholeCamera, node

from ..camera import look_at, project_points
from ..shared.params import Positive, Seed

__all__ = ["plane_lines"]


class PlaneLines(NamedTuple):
    image: GrayImage
    segments: Array
    family: Array
    vanishing_points: Array
    horizon: Array
    camera: Camera


@node("synthetic.plane_lines", version=1)
def plane_lines(
    *,
    angle: Annotated[float, Field(ge=5, le=175)] = 70.0,
    rotation: float = -35.0,
    lines: Annotated[int, Field(ge=2, le=100)] = 8,
    height: Positive = 1.6,
    pitch: Annotated[float, Field(gt=0, lt=90)] = 15.0,
    focal: Positive = 500.0,
    noise: Annotated[float, Field(ge=0)] = 0.3,
    seed: Seed = 0,
) -> PlaneLines:
    """Two families of parallel lines on the ground plane Y = 0, drawn as a 640×480 image.

    The camera stands ``height`` above the plane looking along +Z, pitched down by
    ``pitch`` degrees. Family 0 runs at ``rotation`` degrees from Z (in the plane),
    family 1 at ``rotation + angle``. Each family has ``lines`` segments, clipped to
    the part of the plane between 2 and 30 units ahead; their projected end points
    get Gaussian noise ``noise`` (px).

    Parameters
    ----------
    angle : float
        Angle between the two families, degrees.
    rotation : float
        Direction of family 0 from the view direction, degrees.
    lines : int
        Segments per family.
    height : float
        Camera height above the plane.
    pitch : float
        Downward tilt of the optical axis, degrees.
    focal : float
        Focal length, pixels.
    noise : float
        σ of the end-point noise, pixels.
    seed : int
        Seed of the offsets and the noise.

    Returns
    -------
    image : the drawn segments, 480×640
    segments : (2·lines, 4) end points x0, y0, x1, y1 in pixels
    family : (2·lines,) 0 or 1
    vanishing_points : (2, 3) the true vanishing points, homogeneous, unit norm
    horizon : (3,) the true horizon line (a, b, c), a² + b² = 1
    camera : the camera
    """
    from skimage.draw import line_aa

    rng = np.random.default_rng(seed)
    width, rows = 640, 480
    K = np.array([[focal, 0, (width - 1) / 2], [0, focal, (rows - 1) / 2], [0, 0, 1.0]])
    C = np.array([0.0, -height, 0.0])  # world y points down: the plane Y = 0 is below
    tilt = np.deg2rad(pitch)
    R = look_at(C, C + np.array([0.0, np.sin(tilt), np.cos(tilt)]))
    camera = PinholeCamera(K, R, C, size=np.array([width, rows]))
    segments, family = [], []
    truths = []
    for index, degrees in enumerate((rotation, rotation + angle)):
        theta = np.deg2rad(degrees)
        direction = np.array([np.sin(theta), 0.0, np.cos(theta)])
        truths.append(K @ R @ direction)
        normal = np.array([direction[2], 0.0, -direction[0]])
        centre = np.array([0.0, 0.0, 10.0])
        for offset in rng.uniform(-6, 6, lines):
            base = centre + offset * normal
            ends = np.array([base - 8 * direction, base + 8 * direction])
            # keep the part between 2 and 30 units ahead of the camera
            ahead = ends[:, 2]
            if abs(ahead[1] - ahead[0]) < 1e-9:
                continue
            t = np.clip((np.array([2.0, 30.0]) - ahead[0]) / (ahead[1] - ahead[0]), 0, 1)
            clipped = ends[0] + np.sort(t)[:, None] * (ends[1] - ends[0])
            pixels = project_points(clipped, K, R, C)
            segments.append(pixels.ravel() + rng.normal(0, noise, 4))
            family.append(index)
    image = np.zeros((rows, width), np.float32)
    for x0, y0, x1, y1 in segments:
        rr, cc, value = line_aa(int(round(y0)), int(round(x0)), int(round(y1)), int(round(x1)))
        inside = (rr >= 0) & (rr < rows) & (cc >= 0) & (cc < width)
        image[rr[inside], cc[inside]] = np.maximum(image[rr[inside], cc[inside]], value[inside])
    points = np.array([v / np.linalg.norm(v) for v in truths])
    horizon = np.cross(points[0], points[1])
    return PlaneLines(
        image,
        np.array(segments),
        np.array(family, np.int64),
        points,
        horizon / np.hypot(horizon[0], horizon[1]),
        camera,
    )
