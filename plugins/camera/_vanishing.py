r"""Vanishing points and the horizon (seed: "Homography", vanishing points).

Parallel 3-D lines of direction d project to image lines meeting at the
vanishing point :math:`v \sim K R d`; the vanishing points of all directions in
a plane of normal n lie on its horizon :math:`l \sim K^{-T} R n`.

The vanishing point of a set of segments is the homogeneous point closest to
all their lines in the least-squares sense: with each line
:math:`l_i = p_i \times q_i` scaled to a unit normal (after Hartley's
normalisation of the end points), v is the right singular vector of the
smallest singular value of :math:`L = [l_1 \dots l_n]^T` (minimising
:math:`\sum_i (l_i^T v)^2` over :math:`\|v\| = 1`; a point at infinity is allowed).

References
----------
.. [1] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., 2004, §8.6 (vanishing
   points and lines), §8.6.1 (ML estimate from more than two lines).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from graphvision import Array, Camera, ColorImage, Float, Image, node

from ..geometry import normalising_transform
from ..shared.draw import colour_canvas, draw_segment
from ._model import check_intrinsics

__all__ = [
    "draw_vanishing",
    "horizon",
    "vanishing_error",
    "vanishing_point",
    "vanishing_points",
]


def vanishing_point(segments: np.ndarray) -> np.ndarray:
    """Least-squares intersection (module docstring) of ``N×4`` segments, homogeneous, unit norm."""
    ends = segments.reshape(-1, 2)
    T = normalising_transform(ends)
    p = np.column_stack([segments[:, :2], np.ones(len(segments))]) @ T.T
    q = np.column_stack([segments[:, 2:], np.ones(len(segments))]) @ T.T
    lines = np.cross(p, q)
    lines /= np.hypot(lines[:, 0], lines[:, 1])[:, None]
    _, _, vt = np.linalg.svd(lines, full_matrices=len(lines) < 3)
    v = np.linalg.solve(T, vt[-1])
    v /= np.linalg.norm(v)
    return v if v[2] >= 0 else -v


def _check_segments(segments: np.ndarray, family: np.ndarray) -> None:
    if segments.ndim != 2 or segments.shape[1] != 4:
        raise ValueError(f"segments must be N×4 (x0, y0, x1, y1), got shape {segments.shape}")
    if family.shape != (len(segments),):
        raise ValueError(
            f"family must have one label per segment ({len(segments)}), got {family.shape}"
        )
    if np.hypot(*(segments[:, 2:] - segments[:, :2]).T).min(initial=np.inf) == 0:
        raise ValueError("a segment has coincident end points: it defines no line")


@node("camera.vanishing_points", version=1)
def vanishing_points(segments: Array, family: Array) -> Array:
    """One vanishing point per family of segments: their lines' least-squares intersection.

    Parameters
    ----------
    segments : Array
        Image segments N×4 ``(x0, y0, x1, y1)``.
    family : Array
        Integer label per segment, 0 … F−1: segments images of parallel lines share one.

    Returns
    -------
    vanishing_points : (F, 3) homogeneous points, unit norm, w ≥ 0

    Raises
    ------
    ValueError
        When a family has fewer than 2 segments, or a segment is a point.
    """
    _check_segments(segments, family)
    points = []
    for label in range(int(family.max()) + 1):
        chosen = segments[family == label]
        if len(chosen) < 2:
            raise ValueError(f"family {label} has {len(chosen)} segment(s): need at least 2")
        points.append(vanishing_point(chosen))
    return np.array(points)


@node("camera.horizon", version=1)
def horizon(vanishing_points: Array) -> Array:
    r"""The horizon: the line :math:`l = v_1 \times v_2` through two vanishing points of a plane.

    Parameters
    ----------
    vanishing_points : Array
        Two (or more: the first two are used) homogeneous vanishing points, F×3.

    Returns
    -------
    horizon : (3,) line (a, b, c) with a² + b² = 1 (ax + by + c = 0)
    """
    if vanishing_points.ndim != 2 or vanishing_points.shape[1] != 3 or len(vanishing_points) < 2:
        raise ValueError(f"need at least two homogeneous points F×3, got {vanishing_points.shape}")
    line = np.cross(vanishing_points[0], vanishing_points[1])
    norm = np.hypot(line[0], line[1])
    if norm < 1e-12:
        raise ValueError("the two vanishing points coincide: they define no horizon")
    return line / norm


class VanishingError(NamedTuple):
    points_degrees: Float
    horizon_degrees: Float


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    cos = abs(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b))
    return float(np.degrees(np.arccos(np.clip(cos, 0.0, 1.0))))


@node("camera.vanishing_error", version=1)
def vanishing_error(
    estimated: Array, truth: Array, estimated_horizon: Array, true_horizon: Array, camera: Camera
) -> VanishingError:
    r"""Angular errors of vanishing points (as 3-D directions) and of a horizon (as a plane normal).

    A vanishing point v is the direction :math:`K^{-1} v` in camera coordinates; a
    horizon l is the plane normal :math:`K^T l`. Errors are the angles between
    estimated and true directions (sign-free), in degrees.

    Parameters
    ----------
    estimated, truth : Array
        Homogeneous vanishing points F×3, in the same order.
    estimated_horizon, true_horizon : Array
        Lines (3,).
    camera : Camera
        Its K relates image points to directions.

    Returns
    -------
    points_degrees : the largest error over the vanishing points
    horizon_degrees : the horizon's error
    """
    check_intrinsics(camera)
    if estimated.shape != truth.shape:
        raise ValueError(f"estimated {estimated.shape} and truth {truth.shape} differ in shape")
    Kinv = np.linalg.inv(camera.K)
    worst = max(_angle(Kinv @ a, Kinv @ b) for a, b in zip(estimated, truth, strict=True))
    return VanishingError(worst, _angle(camera.K.T @ estimated_horizon, camera.K.T @ true_horizon))


@node("camera.draw_vanishing", version=1)
def draw_vanishing(
    image: Image, segments: Array, family: Array, vanishing_points: Array, horizon: Array
) -> ColorImage:
    """Segments coloured by family, each extended towards its vanishing point, and the horizon.

    Parameters
    ----------
    image : Image
        The image the segments were found in.
    segments : Array
        Segments N×4.
    family : Array
        Family label per segment.
    vanishing_points : Array
        Homogeneous points F×3 (``camera.vanishing_points``).
    horizon : Array
        The horizon line (3,), drawn in yellow.
    """
    canvas = colour_canvas(image)
    colours = np.array([[0.95, 0.2, 0.1], [0.1, 0.6, 1.0], [0.2, 0.9, 0.2], [0.9, 0.2, 0.9]])
    h, w = canvas.shape[:2]
    for (x0, y0, x1, y1), label in zip(segments, family.astype(int), strict=True):
        colour = colours[label % len(colours)]
        v = vanishing_points[label]
        start = np.array([x0, y0])
        if abs(v[2]) > 1e-12:
            target = v[:2] / v[2]
            far = np.array([x1, y1])
            nearer = start if np.linalg.norm(start - target) < np.linalg.norm(far - target) else far
            reach = target - nearer
            length = np.linalg.norm(reach)
            limit = 2.0 * (w + h)
            end = nearer + reach * min(1.0, limit / length) if length > 0 else nearer
            draw_segment(canvas, nearer, end, 0.5 * colour + 0.25)
        draw_segment(canvas, start, np.array([x1, y1]), colour)
    a, b, c = horizon
    if abs(b) > 1e-12:
        draw_segment(canvas, np.array([0.0, -c / b]), np.array([w - 1.0, -(c + a * (w - 1)) / b]),
                 np.array([1.0, 0.85, 0.0]))  # fmt: skip
    elif abs(a) > 1e-12:
        draw_segment(canvas, np.array([-c / a, 0.0]), np.array([-c / a, h - 1.0]),
                 np.array([1.0, 0.85, 0.0]))  # fmt: skip
    return canvas.astype(np.float32)
