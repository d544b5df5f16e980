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

from ..edges import gradient_images
from ..shared.draw import colour_canvas
from ..shared.params import Count, Positive
from ._peaks import local_maxima, quadratic_peak_2d

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
    # a perfect copy's peak, through the same votes and spreading: the accumulator's unit
    margin = int(math.ceil(3 * vote_sigma)) + 2
    shift = np.floor(model_points.min(axis=0)) - margin
    extent = np.ceil(model_points.max(axis=0) - shift).astype(int) + margin + 1
    copy = _vote_plane(
        model_points - shift, model_angles, table, starts, bins, 0.0, 1.0, (extent[1], extent[0])
    )
    unit = float(_spread(copy, vote_sigma).max())
    best = np.zeros((height, width))
    best_rotation = np.zeros((height, width), dtype=np.intp)
    best_scale = np.zeros((height, width), dtype=np.intp)
    for a, rotation in enumerate(rotations):
        for k, scale in enumerate(scales):
            votes = _vote_plane(
                points, angles, table, starts, bins, math.radians(rotation), scale, (height, width)
            )
            plane = _spread(votes, vote_sigma) / unit
            better = plane > best
            best = np.where(better, plane, best)
            best_rotation[better] = a
            best_scale[better] = k
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


def _vote_plane(
    points: np.ndarray,
    angles: np.ndarray,
    table: np.ndarray,
    starts: np.ndarray,
    bins: int,
    alpha: float,
    scale: float,
    shape: tuple[int, int],
) -> np.ndarray:
    """Votes (one per point and R-table entry of its orientation bin, turned by ``alpha``) at
    ``q + scale · R_alpha r``, rounded to the nearest pixel, as an ``shape`` array."""
    height, width = shape
    turn = np.array([[math.cos(alpha), -math.sin(alpha)], [math.sin(alpha), math.cos(alpha)]])
    rows = np.floor(np.mod(angles - alpha, 2 * math.pi) / (2 * math.pi) * bins).astype(np.intp)
    rows %= bins
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
    return votes.reshape(height, width)


def _spread(votes: np.ndarray, vote_sigma: float) -> np.ndarray:
    """Each vote spread as a Gaussian of height one (unchanged when ``vote_sigma`` is 0)."""
    from ..shared.separable import smooth_gaussian

    if vote_sigma <= 0:
        return votes
    return smooth_gaussian(votes, vote_sigma, "constant") * (2 * math.pi * vote_sigma**2)


class _Matcher:
    """Which model points an instance finds: a scene edge point within ``tolerance`` pixels
    of where the point should be, :math:`c - s R r`, with a gradient orientation within
    ``angle_tolerance`` of its (turned) orientation; equivalently, the model points whose
    vote lands within ``tolerance`` of the reference point :math:`c`."""

    def __init__(
        self,
        displacements: np.ndarray,
        model_angles: np.ndarray,
        points: np.ndarray,
        angles: np.ndarray,
        tolerance: float,
        angle_tolerance: float,
    ) -> None:
        from scipy.spatial import cKDTree

        self.displacements, self.model_angles = displacements, model_angles
        self.points, self.angles = points, angles
        self.tolerance, self.angle_tolerance = tolerance, angle_tolerance
        self.tree = cKDTree(points) if len(points) else None
        self.free = np.ones(len(points), dtype=bool)

    def matches(
        self, locations: np.ndarray, turns: np.ndarray, sizes: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Pairs ``(model point index over all instances, scene point)`` that match."""
        if self.tree is None or len(locations) == 0:
            return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        cos, sin = np.cos(turns)[:, None], np.sin(turns)[:, None]
        dx, dy = self.displacements[None, :, 0], self.displacements[None, :, 1]
        expected = np.stack(
            [
                locations[:, 0:1] - sizes[:, None] * (cos * dx - sin * dy),
                locations[:, 1:2] - sizes[:, None] * (sin * dx + cos * dy),
            ],
            axis=-1,
        ).reshape(-1, 2)
        from scipy.spatial import cKDTree

        pairs = cKDTree(expected).sparse_distance_matrix(
            self.tree, self.tolerance, output_type="ndarray"
        )
        owner, scene = pairs["i"].astype(np.intp), pairs["j"].astype(np.intp)
        wanted = (self.model_angles[None, :] + turns[:, None]).ravel()[owner]
        gap = np.abs(np.mod(self.angles[scene] - wanted + math.pi, 2 * math.pi) - math.pi)
        good = (gap <= self.angle_tolerance) & self.free[scene]
        return owner[good], scene[good]

    def fractions(self, locations: np.ndarray, turns: np.ndarray, sizes: np.ndarray) -> np.ndarray:
        """The fraction of the model's points each instance finds among the free scene points."""
        owner, _ = self.matches(locations, turns, sizes)
        found = np.zeros(len(locations) * len(self.displacements), dtype=bool)
        found[owner] = True
        return found.reshape(len(locations), len(self.displacements)).mean(axis=1)


def _claim_instances(
    matcher: _Matcher,
    locations: np.ndarray,
    turns: np.ndarray,
    sizes: np.ndarray,
    fractions: np.ndarray,
    threshold: float,
    min_distance: float,
    limit: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Indices and scores of the instances kept, best first. Candidates are taken in order of
    the fraction found, each scored again on the scene points the instances before it left
    free, and kept when that is at least ``threshold`` and it lies ``min_distance`` from every
    kept one; a kept instance claims the points it matched (so a shifted copy of the same
    instance, on a ridge of its votes, finds them gone)."""
    kept: list[int] = []
    scores: list[float] = []
    for k in np.argsort(-fractions, kind="stable"):
        if fractions[k] < threshold or len(kept) == limit:
            break
        owner, scene = matcher.matches(locations[k : k + 1], turns[k : k + 1], sizes[k : k + 1])
        score = len(np.unique(owner)) / len(matcher.displacements)
        if score < threshold or any(
            np.hypot(*(locations[k] - locations[j])) < min_distance for j in kept
        ):
            continue
        matcher.free[scene] = False
        kept.append(int(k))
        scores.append(score)
    order = np.argsort(-np.array(scores), kind="stable")
    return np.array(kept, dtype=np.intp)[order], np.array(scores, dtype=np.float64)[order]


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
