"""Depth maps with known geometry, for depth-dependent image formation (defocus)."""

from __future__ import annotations

import numpy as np

from graphvision import FloatImage, Image, node

from ..shared.checks import ordered
from ..shared.params import Positive

__all__ = ["depth_plane"]


@node("synthetic.depth_plane", version=1, check=ordered(("near", "far")))
def depth_plane(
    image: Image,
    *,
    near: Positive = 1000.0,
    far: Positive = 8000.0,
) -> FloatImage:
    """The depth of a plane receding from the bottom row (``near``) to the top row (``far``).

    A plane seen by a pinhole camera has inverse depth linear in the image
    coordinates, so :math:`1/z` is interpolated linearly between the rows.

    Parameters
    ----------
    image : Image
        Gives the size H×W of the depth map.
    near : float
        Depth at the bottom row (mm).
    far : float
        Depth at the top row (mm).
    """
    rows, cols = image.shape[:2]
    t = np.linspace(0.0, 1.0, rows)[:, None]  # 0 at the top row
    inverse = (1 - t) / far + t / near
    return np.broadcast_to(1.0 / inverse, (rows, cols)).astype(np.float32)
