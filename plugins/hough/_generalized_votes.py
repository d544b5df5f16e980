"""The generalised Hough transform's votes (Ballard 1981; see :mod:`._generalized`): the
R-table of a model's edge points, the votes of a scene's edge points at each rotation and
scale, spread and compared in units of a perfect copy's peak, and the instances claimed
by the fraction of the model's points they explain."""

from __future__ import annotations

import math

import numpy as np

from ..edges import gradient_images

__all__ = [
    "build_r_table",
]


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


def _unit_peak(
    model_points: np.ndarray,
    model_angles: np.ndarray,
    table: np.ndarray,
    starts: np.ndarray,
    bins: int,
    vote_sigma: float,
) -> float:
    """A perfect copy's peak, through the same votes and spreading: the accumulator's unit."""
    margin = int(math.ceil(3 * vote_sigma)) + 2
    shift = np.floor(model_points.min(axis=0)) - margin
    extent = np.ceil(model_points.max(axis=0) - shift).astype(int) + margin + 1
    copy = _vote_plane(
        model_points - shift, model_angles, table, starts, bins, 0.0, 1.0, (extent[1], extent[0])
    )
    return float(_spread(copy, vote_sigma).max())


def _best_over_poses(
    points: np.ndarray,
    angles: np.ndarray,
    table: np.ndarray,
    starts: np.ndarray,
    bins: int,
    rotations: list[float],
    scales: list[float],
    shape: tuple[int, int],
    vote_sigma: float,
    unit: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pixel the best vote (in ``unit``) over rotations and scales, and which."""
    height, width = shape
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
    return best, best_rotation, best_scale


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
