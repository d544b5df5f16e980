"""The generalised Hough transform: an R-table of displacements indexed by gradient orientation."""

from __future__ import annotations

import math
from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import (
    Array,
    BinaryImage,
    ColorImage,
    FloatImage,
    GrayImage,
    Image,
    Int,
    Points2D,
    node,
)

from .._draw import colour_canvas
from .._params import Count, Positive
from ..edges import gradient_images
from ._peaks import local_maxima, quadratic_peak_2d, suppress_close

__all__ = ["GeneralizedHough", "build_r_table", "draw_instances", "generalized_hough"]


def _oriented_points(
    edges: np.ndarray, image: np.ndarray, sigma: float
) -> tuple[np.ndarray, np.ndarray]:
    """Edge points ``(x, y)`` with a non-zero gradient and their orientation in [0, 2π)."""
    rows, cols = np.nonzero(edges)
    dx, dy = gradient_images(image, "gaussian", sigma)
    gx, gy = dx[rows, cols].astype(np.float64), dy[rows, cols].astype(np.float64)
    moving = np.hypot(gx, gy) > 0
    points = np.column_stack([cols, rows]).astype(np.float64)[moving]
    return points, np.mod(np.arctan2(gy[moving], gx[moving]), 2 * math.pi)


def build_r_table(
    points: np.ndarray, angles: np.ndarray, bins: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """R-table: displacements ``r = c - p`` to the reference point ``c`` (the centroid of the
    model's edge points), sorted by orientation bin, with each bin's start offset.

    Returns ``(reference, displacements (M, 2) sorted by bin, starts (bins + 1,))``.
    """
    reference = points.mean(axis=0)
    index = np.floor(angles / (2 * math.pi) * bins).astype(np.intp) % bins
    order = np.argsort(index, kind="stable")
    starts = np.searchsorted(index[order], np.arange(bins + 1))
    return reference, (reference - points)[order], starts


class GeneralizedHough(NamedTuple):
    locations: Points2D
    angles: Array
    scales: Array
    scores: Array
    count: Int  # type: ignore[assignment]  # the port is named count in pipelines; hides tuple.count
    accumulator: FloatImage


@node("hough.generalized", version=1)
def generalized_hough(
    edges: BinaryImage,
    image: GrayImage,
    model_edges: BinaryImage,
    model_image: GrayImage,
    *,
    bins: Annotated[int, Field(ge=4, le=720)] = 64,
    rotations: Annotated[list[float], Field(min_length=1)] = [0.0],  # noqa: B006
    scales: Annotated[list[Positive], Field(min_length=1)] = [1.0],  # noqa: B006
    sigma: Annotated[float, Field(gt=0, le=50)] = 1.0,
    vote_sigma: Annotated[float, Field(ge=0, le=20)] = 1.0,
    threshold: Annotated[float, Field(gt=0, le=1)] = 0.3,
    min_distance: Positive = 10.0,
    max_instances: Count = 10,
) -> GeneralizedHough:
    r"""Find an arbitrary shape by voting for its reference point (Ballard's GHT).

    Model learning: for each model edge point :math:`p` with gradient
    orientation :math:`\theta`, store the displacement :math:`r = c - p` to
    the reference point :math:`c` (the centroid of the edge points) in the
    R-table row of :math:`\theta`. Detection: each scene edge point :math:`q`
    of orientation :math:`\psi` looks up the row of :math:`\psi - \alpha` and
    votes at :math:`q + s\,R_\alpha r` for every rotation :math:`\alpha` and
    scale :math:`s` tried. Votes are spread by a Gaussian (height one) and
    divided by the number of model points, so a score is the fraction of the
    model found. Instances are local maxima over position, best over
    rotation and scale, of at least ``threshold``, ``min_distance`` apart,
    refined to a fraction of a pixel.

    Parameters
    ----------
    edges : (H, W) bool ndarray
        Edge points of the scene.
    image : (H, W) float32 ndarray
        The scene, for gradient orientations.
    model_edges : (h, w) bool ndarray
        Edge points of the shape.
    model_image : (h, w) float32 ndarray
        The model picture, for its gradient orientations.
    bins : int
        Orientation bins of the R-table over :math:`[0, 2\pi)`.
    rotations : list of float
        Rotations tried, in degrees (counter-clockwise on screen is negative).
    scales : list of float
        Scales tried.
    sigma : float
        Gaussian scale of the gradients.
    vote_sigma : float
        Spread of each vote in pixels (0: none).
    threshold : float
        Smallest score (fraction of the model's points that voted).
    min_distance : float
        Least distance between two instances, in pixels.
    max_instances : int
        Most instances returned, strongest first.

    Returns
    -------
    locations : (N, 2) float64, the reference point of each instance
    angles : (N,) float64, rotation in degrees
    scales : (N,) float64
    scores : (N,) float64
    count : int
    accumulator : (H, W) float32, the best score over rotations and scales

    References
    ----------
    .. [1] D. H. Ballard, "Generalizing the Hough transform to detect arbitrary
       shapes", Pattern Recognition 13(2), 1981.
    """
    from .._separable import smooth_gaussian

    if model_edges.shape != model_image.shape or edges.shape != image.shape:
        raise ValueError(
            "edges and image (and model_edges and model_image) must have the same size, got "
            f"{edges.shape}, {image.shape}, {model_edges.shape}, {model_image.shape}"
        )
    model_points, model_angles = _oriented_points(model_edges, model_image, sigma)
    if len(model_points) == 0:
        raise ValueError("model_edges has no edge point with a gradient: the model is empty")
    _, table, starts = build_r_table(model_points, model_angles, bins)
    points, angles = _oriented_points(edges, image, sigma)
    height, width = edges.shape
    best = np.zeros((height, width))
    best_rotation = np.zeros((height, width), dtype=np.intp)
    best_scale = np.zeros((height, width), dtype=np.intp)
    for a, rotation in enumerate(rotations):
        alpha = math.radians(rotation)
        turn = np.array([[math.cos(alpha), -math.sin(alpha)], [math.sin(alpha), math.cos(alpha)]])
        rows = np.floor(np.mod(angles - alpha, 2 * math.pi) / (2 * math.pi) * bins).astype(np.intp)
        rows %= bins
        for k, scale in enumerate(scales):
            votes = np.zeros(height * width)
            displacement = scale * table @ turn.T
            for row in range(bins):
                here = points[rows == row]
                entries = displacement[starts[row] : starts[row + 1]]
                if len(here) == 0 or len(entries) == 0:
                    continue
                target = np.rint(here[:, None, :] + entries[None, :, :]).astype(np.intp)
                x, y = target[..., 0].ravel(), target[..., 1].ravel()
                inside = (x >= 0) & (x < width) & (y >= 0) & (y < height)
                votes += np.bincount(y[inside] * width + x[inside], minlength=height * width)
            plane = votes.reshape(height, width)
            if vote_sigma > 0:
                plane = smooth_gaussian(plane, vote_sigma, "constant")
                plane *= 2 * math.pi * vote_sigma**2
            plane /= len(model_points)
            better = plane > best
            best = np.where(better, plane, best)
            best_rotation[better] = a
            best_scale[better] = k
    peaks = local_maxima(best, 2 * int(math.ceil(min_distance / 2)) + 1, 0.0)
    peaks = peaks[best[peaks[:, 0], peaks[:, 1]] >= threshold]
    peaks = peaks[
        (peaks[:, 0] > 0)
        & (peaks[:, 0] < height - 1)
        & (peaks[:, 1] > 0)
        & (peaks[:, 1] < width - 1)
    ]
    scores = best[peaks[:, 0], peaks[:, 1]]
    kept = peaks[suppress_close(peaks.astype(np.float64), scores, min_distance, max_instances)]
    y, x = kept[:, 0], kept[:, 1]
    offsets = quadratic_peak_2d(best, y, x) if len(kept) else np.zeros((0, 2))
    locations = np.column_stack([x + offsets[:, 1], y + offsets[:, 0]]).astype(np.float64)
    return GeneralizedHough(
        locations.reshape(-1, 2),
        np.asarray(rotations, dtype=np.float64)[best_rotation[y, x]],
        np.asarray(scales, dtype=np.float64)[best_scale[y, x]],
        best[y, x],
        len(kept),
        best.astype(np.float32),
    )


@node("hough.draw_instances", version=1)
def draw_instances(
    image: Image,
    locations: Points2D,
    model_edges: BinaryImage,
    model_image: GrayImage,
    angles: Array | None = None,
    scales: Array | None = None,
    *,
    sigma: Annotated[float, Field(gt=0, le=50)] = 1.0,
) -> ColorImage:
    """The model's edge points in green where ``hough.generalized`` found it, reference in red.

    Parameters
    ----------
    image : Image
        The scene (gray is drawn in colour).
    locations : Points2D
        Reference points found (``hough.generalized``'s locations).
    model_edges : BinaryImage
        The model's edge points, as given to ``hough.generalized``.
    model_image : GrayImage
        The model picture, as given to ``hough.generalized``.
    angles : Array, optional
        Rotation of each instance in degrees (0 when not connected).
    scales : Array, optional
        Scale of each instance (1 when not connected).
    sigma : float
        The gradient scale used by ``hough.generalized`` (it picks the same points).

    Returns
    -------
    drawing : (H, W, 3) float32 ndarray
    """
    canvas = colour_canvas(image)
    points, _ = _oriented_points(model_edges, model_image, sigma)
    offsets = points - points.mean(axis=0) if len(points) else points
    rows, cols = canvas.shape[:2]
    for index, (x, y) in enumerate(locations):
        alpha = math.radians(float(angles[index])) if angles is not None else 0.0
        scale = float(scales[index]) if scales is not None else 1.0
        turn = np.array([[math.cos(alpha), -math.sin(alpha)], [math.sin(alpha), math.cos(alpha)]])
        placed = np.rint(scale * offsets @ turn.T + (x, y)).astype(np.intp)
        inside = (
            (placed[:, 0] >= 0)
            & (placed[:, 0] < cols)
            & (placed[:, 1] >= 0)
            & (placed[:, 1] < rows)
        )
        canvas[placed[inside, 1], placed[inside, 0]] = (0.1, 0.95, 0.1)
        cx, cy = round(x), round(y)
        if 0 <= cy < rows and 0 <= cx < cols:
            canvas[cy, cx] = (0.95, 0.15, 0.1)
    return canvas.astype(np.float32)
