"""An image seen by the same camera turned about its centre: a known homography K R K⁻¹."""

from __future__ import annotations

from typing import Generic, NamedTuple

import numpy as np

from graphvision import Camera, Homography, ImageT, node

from ..camera import rotation_from_vector
from ..geometry import sample_homography

__all__ = ["turned_view"]


class TurnedView(NamedTuple, Generic[ImageT]):
    image: ImageT
    homography: Homography


@node("synthetic.turned_view", version=1)
def turned_view(
    image: ImageT,
    camera: Camera,
    *,
    yaw: float = 2.0,
    pitch: float = 1.0,
    roll: float = 1.5,
) -> TurnedView[ImageT]:
    r"""What ``camera`` would see after turning about its centre: :math:`H = K R K^{-1}`.

    A rotation about the centre moves no point relative to another (no
    parallax), so the new view is the old one mapped by the homography; it
    un-rectifies a rectified pair, for instance. :math:`R` turns by ``yaw``
    about the camera's y axis, then ``pitch`` about x, then ``roll`` about z.

    Parameters
    ----------
    image : Image
        The view before turning.
    camera : Camera
        Gives K (its distortion is ignored).
    yaw, pitch, roll : float
        Angles of the turn, degrees.

    Returns
    -------
    image : Image
        The turned view, the input's size (black where nothing was seen).
    homography : Homography
        Maps pixels of the input to the turned view.
    """
    yaw_r, pitch_r, roll_r = np.radians([yaw, pitch, roll])
    R = (
        rotation_from_vector(np.array([0.0, 0.0, roll_r]))
        @ rotation_from_vector(np.array([pitch_r, 0.0, 0.0]))
        @ rotation_from_vector(np.array([0.0, yaw_r, 0.0]))
    )
    H = camera.K @ R @ np.linalg.inv(camera.K)
    H /= H[2, 2]
    turned, _ = sample_homography(image, np.linalg.inv(H), image.shape[:2])
    return TurnedView(turned.astype(np.float32), H)
