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

from ..shared.draw import colour_canvas
from ..shared.params import Count, Positive
from ._generalized_votes import (
    _best_over_poses,
    _claim_instances,
    _Matcher,
    _oriented_points,
    _unit_peak,
    build_r_table,
)
from ._peaks import local_maxima, quadratic_peak_2d

__all__ = [
    "GeneralizedHough",
    "draw_instances",
    "generalized_hough",
]


class GeneralizedHough(NamedTuple):
    locations: Points2D
    angles: Array
    scales: Array
    scores: Array
    count: Int  # type: ignore[assignment]  # the port is named count in pipelines; hides tuple.count
    accumulator: FloatImage


@node("hough.generalized", version=2)
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
    threshold: Annotated[float, Field(gt=0, le=1)] = 0.4,
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
    scale :math:`s` tried. Votes are spread by a Gaussian of height one and
    divided by the peak a perfect copy of the model gets from the same votes
    and spreading (the accumulator is 1 at a copy's reference point). Its
    local maxima over position, best over rotation and scale, refined to a
    fraction of a pixel by a quadratic, are the candidates.

    A candidate's score is the fraction of the model found there: model point
    :math:`p` is found when a scene edge point lies within
    :math:`\tau = \max(1.5, 2\,\sigma_v)` pixels of where it should be,
    :math:`c - s R_\alpha r`, with a gradient orientation within two bins
    (:math:`4\pi/`\ ``bins``) of :math:`p`'s turned by :math:`\alpha`; that is,
    the fraction of model points whose vote lands within :math:`\tau` of
    :math:`c`. It lies in [0, 1] for every ``vote_sigma`` (1 for a copy), which
    the peak of spread votes does not: the votes of a point's neighbours along
    an edge land beside its own and add up (a copy's peak was 3 at
    ``vote_sigma=1``). Candidates are taken best first, each scored again on
    the scene points that instances kept before it left unclaimed, and kept
    when that score is at least ``threshold`` and it lies ``min_distance``
    from every kept one; a kept instance claims the scene points it matched,
    so a copy shifted along the ridge of its own votes, which finds some of
    the same points again, is not a second instance.

    The default ``threshold`` 0.4 separates, on held-out scenes (arrows on
    photographed textures among polygons, ``arrow_scene`` in
    tests/plugins/test_held_out_hough_template.py, 24 scenes), clutter (at
    most 0.25) from arrows with 37 % of their outline hidden (0.48 to 0.63;
    whole arrows turned 10° score 0.87 to 1).

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
        Spread of each vote in pixels (0: none); a model point is found within
        ``max(1.5, 2 · vote_sigma)`` pixels.
    threshold : float
        Smallest score (fraction of the model's points found).
    min_distance : float
        Least distance between two instances, in pixels.
    max_instances : int
        Most instances returned, strongest first.

    Returns
    -------
    locations : (N, 2) float64, the reference point of each instance
    angles : (N,) float64, rotation in degrees
    scales : (N,) float64
    scores : (N,) float64, the fraction of the model found, in [0, 1]
    count : int
    accumulator : (H, W) float32, the spread votes over rotations and scales (best),
        relative to a perfect copy's peak

    References
    ----------
    .. [1] D. H. Ballard, "Generalizing the Hough transform to detect arbitrary
       shapes", Pattern Recognition 13(2), 1981.
    """
    if model_edges.shape != model_image.shape or edges.shape != image.shape:
        raise ValueError(
            "edges and image (and model_edges and model_image) must have the same size, got "
            f"{edges.shape}, {image.shape}, {model_edges.shape}, {model_image.shape}"
        )
    model_points, model_angles = _oriented_points(model_edges, model_image, sigma)
    if len(model_points) == 0:
        raise ValueError("model_edges has no edge point with a gradient: the model is empty")
    reference, table, starts = build_r_table(model_points, model_angles, bins)
    points, angles = _oriented_points(edges, image, sigma)
    height, width = edges.shape
    unit = _unit_peak(model_points, model_angles, table, starts, bins, vote_sigma)
    best, best_rotation, best_scale = _best_over_poses(
        points, angles, table, starts, bins, rotations, scales, (height, width), vote_sigma, unit
    )
    peaks = local_maxima(best, 2 * int(math.ceil(min_distance / 2)) + 1, 0.0)
    peaks = peaks[
        (peaks[:, 0] > 0)
        & (peaks[:, 0] < height - 1)
        & (peaks[:, 1] > 0)
        & (peaks[:, 1] < width - 1)
    ]
    y, x = peaks[:, 0], peaks[:, 1]
    offsets = quadratic_peak_2d(best, y, x) if len(peaks) else np.zeros((0, 2))
    locations = np.column_stack([x + offsets[:, 1], y + offsets[:, 0]]).astype(np.float64)
    turn = np.radians(np.asarray(rotations, dtype=np.float64))[best_rotation[y, x]]
    size = np.asarray(scales, dtype=np.float64)[best_scale[y, x]]
    tolerance = max(1.5, 2.0 * vote_sigma)
    matcher = _Matcher(
        reference - model_points, model_angles, points, angles, tolerance, 4 * math.pi / bins
    )
    fractions = matcher.fractions(locations, turn, size)
    kept, scores = _claim_instances(
        matcher, locations, turn, size, fractions, threshold, min_distance, max_instances
    )
    return GeneralizedHough(
        locations[kept].reshape(-1, 2),
        np.degrees(turn[kept]),
        size[kept],
        scores,
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
