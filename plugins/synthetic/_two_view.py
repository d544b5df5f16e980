"""Two calibrated views of a random 3-D point cloud, with seeded pixel noise and the truth."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Camera, PinholeCamera, Points2D, Points3D, node

from ..camera import look_at, project_points
from ..shared.params import Positive, Seed

__all__ = ["two_view_scene"]


class TwoViewScene(NamedTuple):
    a: Points2D
    b: Points2D
    camera_a: Camera
    camera_b: Camera
    points: Points3D


@node("synthetic.two_view_scene", version=1)
def two_view_scene(
    *,
    count: Annotated[int, Field(ge=8, le=100_000)] = 200,
    noise: Annotated[float, Field(ge=0)] = 0.5,
    baseline: Positive = 1.0,
    seed: Seed = 0,
) -> TwoViewScene:
    """Points in a 4 m box 6 m ahead, seen by two 640×480 cameras (K = 800/800/320/240).

    Camera a sits at the origin looking at the box; camera b is ``baseline``
    metres to its right, raised a little and turned towards the box. Both
    projections get Gaussian noise of ``noise`` pixels (seeded); only points
    inside both images are kept.

    Parameters
    ----------
    count : int
        Points drawn (fewer are returned if some fall outside an image).
    noise : float
        σ of the pixel noise.
    baseline : float
        Distance between the camera centres, metres.
    seed : int
        Seed of the points, the pose jitter and the noise.

    Returns
    -------
    a, b : the noisy pixels in each view, row by row in correspondence
    camera_a, camera_b : the true cameras
    points : the true 3-D points
    """
    rng = np.random.default_rng(seed)
    K = np.array([[800.0, 0, 320], [0, 800.0, 240], [0, 0, 1]])
    target = np.array([0.0, 0.0, 6.0])
    points = target + rng.uniform(-2, 2, (count, 3))
    centre_b = np.array([baseline, rng.uniform(-0.1, 0.1) * baseline, rng.uniform(-0.2, 0.2)])
    size = np.array([640, 480], np.int64)
    camera_a = PinholeCamera(K.copy(), look_at(np.zeros(3), target), np.zeros(3), size=size)
    aim = target + rng.uniform(-0.3, 0.3, 3)
    camera_b = PinholeCamera(
        K.copy(), look_at(centre_b, aim, rng.uniform(-0.05, 0.05)), centre_b, size=size.copy()
    )
    a = project_points(points, K, camera_a.R, camera_a.C)
    b = project_points(points, K, camera_b.R, camera_b.C)
    inside = np.all(np.isfinite(a) & np.isfinite(b), axis=1)
    inside &= (a[:, 0] >= 0) & (a[:, 0] < 640) & (a[:, 1] >= 0) & (a[:, 1] < 480)
    inside &= (b[:, 0] >= 0) & (b[:, 0] < 640) & (b[:, 1] >= 0) & (b[:, 1] < 480)
    a = a[inside] + rng.normal(0, noise, (int(inside.sum()), 2))
    b = b[inside] + rng.normal(0, noise, (int(inside.sum()), 2))
    return TwoViewScene(a, b, camera_a, camera_b, points[inside])
