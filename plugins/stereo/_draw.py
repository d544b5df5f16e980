"""Pictures of what the stereo family finds: disparity and depth maps, point clouds."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import ColorImage, Points3D, node

from ..shared.checks import ordered
from ._colour_map import colour_map
from ._ports import Disparity

__all__ = ["colour_map", "draw_disparity", "draw_point_cloud"]


@node("stereo.draw_disparity", version=1, check=ordered(("low", "high"), strict=True))
def draw_disparity(
    disparity: Disparity, *, low: float | None = None, high: float | None = None
) -> ColorImage:
    """A disparity (or depth) map in colour: near (large disparity) red, far blue, invalid black.

    Parameters
    ----------
    disparity : Disparity
        The map (a Depth map draws too).
    low, high : float or None
        Values mapped to the ends of the colour scale (default: the 1st and
        99th percentiles), so that maps drawn with the same range compare.
    """
    return colour_map(disparity, low, high)


@node("stereo.draw_point_cloud", version=1)
def draw_point_cloud(
    points: Points3D,
    *,
    azimuth: float = 30.0,
    elevation: float = 20.0,
    size: Annotated[int, Field(ge=16, le=4096)] = 512,
) -> ColorImage:
    r"""A point cloud seen from the side: turned about its centre, projected
    orthographically, the nearest point drawn at each pixel, coloured by depth Z.

    The view turns the cloud by ``azimuth`` about the camera's y axis (down)
    and then by ``elevation`` about the x axis; camera coordinates are kept
    (x right, y down, z ahead), so azimuth 0 and elevation 0 is the camera's
    own view.

    Parameters
    ----------
    points : Points3D
        The cloud (camera coordinates).
    azimuth, elevation : float
        Angles of the view, degrees.
    size : int
        Side of the square picture, pixels.
    """
    canvas = np.ones((size, size, 3), np.float32)
    if len(points) == 0:
        return canvas
    a, e = np.radians(azimuth), np.radians(elevation)
    turn_y = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    turn_x = np.array([[1, 0, 0], [0, np.cos(e), -np.sin(e)], [0, np.sin(e), np.cos(e)]])
    centred = points - np.median(points, axis=0)
    seen = centred @ (turn_x @ turn_y).T
    low, high = np.percentile(seen[:, :2], [0.5, 99.5], axis=0)
    scale = (size - 8) / max(float((high - low).max()), 1e-12)
    cols, rows = np.round((seen[:, :2] - low) * scale + 4).astype(np.int64).T
    inside = (rows >= 0) & (rows < size) & (cols >= 0) & (cols < size)
    order = np.argsort(-seen[inside, 2])  # far first, so the nearest is written last
    colours = colour_map(-points[inside, 2])[order]  # near red, far blue, as disparity
    rows, cols = rows[inside][order], cols[inside][order]
    radius = 2 if len(rows) < 5_000 else 1 if len(rows) < 50_000 else 0  # sparse clouds: dots
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            canvas[np.clip(rows + dy, 0, size - 1), np.clip(cols + dx, 0, size - 1)] = colours
    return canvas
