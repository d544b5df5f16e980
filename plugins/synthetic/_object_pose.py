"""The pose of a planar object seen by a camera (:func:`object_pose`: tilt about an axis,
roll, scale, perspective or affine) and the maps of points by it."""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "object_pose",
]


def _rotation_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rotation_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def object_pose(
    width: int,
    height: int,
    *,
    scale: float,
    tilt: float,
    axis: float,
    roll: float,
    distance: float | None,
) -> np.ndarray:
    r"""The homography taking model pixels to scene pixels, the model's centre to (0, 0).

    ``tilt``, ``axis`` and ``roll`` (radians) are :math:`\theta`, :math:`\phi` and
    :math:`\psi` of the module's pose; ``distance`` is :math:`D` in model diagonals
    (None: affine, the orthographic limit). Add the position with a translation.
    """
    rotation = _rotation_z(roll) @ _rotation_z(axis) @ _rotation_x(tilt) @ _rotation_z(-axis)
    centre = np.array([[1.0, 0.0, -(width - 1) / 2], [0.0, 1.0, -(height - 1) / 2], [0, 0, 1.0]])
    if distance is None:
        plane = np.array([[*rotation[0, :2], 0.0], [*rotation[1, :2], 0.0], [0.0, 0.0, 1.0]])
        h = np.diag([scale, scale, 1.0]) @ plane @ centre
    else:
        depth = distance * math.hypot(width, height)
        plane = np.column_stack([rotation[:, 0], rotation[:, 1], [0.0, 0.0, depth]])
        h = np.diag([scale * depth, scale * depth, 1.0]) @ plane @ centre
    return h / h[2, 2]


def _map(h: np.ndarray, points: np.ndarray) -> np.ndarray:
    mapped = points @ h[:2, :2].T + h[:2, 2]
    return mapped / (points @ h[2, :2] + h[2, 2])[:, None]


def _smallest_stretch(h: np.ndarray, points: np.ndarray) -> float:
    """The smallest singular value of the warp's Jacobian at ``points`` (model pixels)."""
    smallest = math.inf
    for x, y in points:
        w = h[2, 0] * x + h[2, 1] * y + h[2, 2]
        u = (h[0, 0] * x + h[0, 1] * y + h[0, 2]) / w
        v = (h[1, 0] * x + h[1, 1] * y + h[1, 2]) / w
        jacobian = np.array(
            [
                [(h[0, 0] - u * h[2, 0]) / w, (h[0, 1] - u * h[2, 1]) / w],
                [(h[1, 0] - v * h[2, 0]) / w, (h[1, 1] - v * h[2, 1]) / w],
            ]
        )
        smallest = min(smallest, float(np.linalg.svd(jacobian, compute_uv=False)[-1]))
    return smallest


def _translation(x: float, y: float) -> np.ndarray:
    return np.array([[1.0, 0.0, x], [0.0, 1.0, y], [0.0, 0.0, 1.0]])
