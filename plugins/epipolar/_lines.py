"""Epipolar lines and epipoles, and a drawing of both views with them."""

from __future__ import annotations

from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, ColorImage, Image, Points2D, node

from ..hough import Lines, draw_lines
from ._ports import Fundamental

__all__ = ["Epipoles", "draw_epipolar", "epipolar_lines", "epipoles", "lines_from_coefficients"]


def lines_from_coefficients(coefficients: np.ndarray) -> np.ndarray:
    r"""Lines :math:`a x + b y + c = 0` as ``(ρ, θ, 0)`` rows (:math:`x\cos\theta + y\sin\theta
    = \rho`, :math:`\theta \in [0, \pi)`), the form the Hough family draws."""
    a, b, c = coefficients.T
    norm = np.hypot(a, b)
    theta = np.arctan2(b, a)
    flip = theta < 0
    theta = np.where(flip, theta + np.pi, theta)
    rho = np.where(flip, c, -c) / norm
    theta = np.where(theta >= np.pi, theta - np.pi, theta)
    return np.column_stack([rho, theta, np.zeros(len(rho))])


@node("epipolar.epipolar_lines", version=1)
def epipolar_lines(F: Fundamental, points: Points2D, *, of_view: Literal["a", "b"] = "a") -> Lines:
    r"""The epipolar line in the other view of each point.

    :math:`l_b = F x_a` and :math:`l_a = F^T x_b`: with :math:`x_b^T F x_a = 0`,
    the match of :math:`x_a` lies on :math:`l_b`.

    Parameters
    ----------
    F : Fundamental
        The fundamental matrix.
    points : Points2D
        Pixels in view ``of_view``.
    of_view : {"a", "b"}
        The view the points are in; the lines are in the other view.

    Returns
    -------
    Lines
        ``(ρ, θ, 0)`` rows, one per point (see ``hough.draw_lines``).
    """
    return _lines_of(F, points, of_view)


def _lines_of(F: np.ndarray, points: np.ndarray, of_view: str) -> np.ndarray:
    homogeneous = np.column_stack([points, np.ones(len(points))])
    coefficients = homogeneous @ (F.T if of_view == "a" else F)
    if len(points) and (np.hypot(coefficients[:, 0], coefficients[:, 1]) < 1e-15).any():
        raise ValueError("a point is the epipole: its epipolar line is undefined")
    return lines_from_coefficients(coefficients)


class Epipoles(NamedTuple):
    a: Array
    b: Array


@node("epipolar.epipoles", version=1)
def epipoles(F: Fundamental) -> Epipoles:
    r"""The epipoles: where each view sees the other camera's centre and all its epipolar
    lines meet.

    :math:`F e_a = 0` and :math:`F^T e_b = 0`.

    Parameters
    ----------
    F : Fundamental
        The fundamental matrix (rank 2).

    Returns
    -------
    a, b : (3,) float64
        Homogeneous, unit norm, last coordinate ≥ 0; a last coordinate of 0 is
        an epipole at infinity (a rectified pair: along x).
    """
    values = []
    for matrix in (F, F.T):
        vector = np.linalg.svd(matrix)[2][-1]
        values.append(vector if vector[2] >= 0 else -vector)
    return Epipoles(values[0], values[1])


@node("epipolar.draw_epipolar", version=1)
def draw_epipolar(
    image_a: Image,
    image_b: Image,
    F: Fundamental,
    a: Points2D,
    b: Points2D,
    *,
    count: Annotated[int, Field(ge=1, le=200)] = 12,
) -> ColorImage:
    """Both views side by side: ``count`` matches as green crosses, each with its epipolar
    line (red) through the other view's point when F is right.

    Parameters
    ----------
    image_a, image_b : Image
        The two views (gray or colour; one height is not required).
    F : Fundamental
        :math:`x_b^T F x_a = 0`.
    a, b : Points2D
        Matches; ``count`` of them, spread evenly through the list, are drawn.
    count : int
        Matches drawn.
    """
    if len(a) != len(b):
        raise ValueError(f"{len(a)} points in view a but {len(b)} in view b")
    chosen = np.linspace(0, len(a) - 1, min(count, len(a))).round().astype(np.intp)
    pictures = []
    for image, own, other, view in ((image_a, a, b, "b"), (image_b, b, a, "a")):
        canvas = draw_lines(image, _lines_of(F, other[chosen], view))  # checks the image
        for x, y in own[chosen]:
            cols, rows = np.rint(x).astype(int), np.rint(y).astype(int)
            for d in range(-4, 5):
                for r, c in ((rows + d, cols), (rows, cols + d)):
                    if 0 <= r < canvas.shape[0] and 0 <= c < canvas.shape[1]:
                        canvas[r, c] = (0.1, 0.95, 0.1)
        pictures.append(canvas)
    height = max(p.shape[0] for p in pictures)
    padded = [np.pad(p, ((0, height - p.shape[0]), (0, 0), (0, 0))) for p in pictures]
    gap = np.ones((height, 4, 3), np.float32)
    return np.concatenate([padded[0], gap, padded[1]], axis=1).astype(np.float32)
