"""Verification of a pose cluster (Lowe 2004, section 7.4): RANSAC on an affine map, matches
gathered top-down, RANSAC on a homography, refitted until the inlier set is stable; and
the location of every instance in a scene from its matches."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from graphvision import KeypointSet

from ..fitting import ransac
from ..geometry import apply_homography, estimate_homography, refine_homography
from ._instances import InstanceSet
from ._model_views import ConstellationParams, ModelViews, _corners
from ._polygons import _is_convex, polygon_area, quad_iou
from ._probability import _unique_positions, pose_probability
from ._votes import PoseVotes, pose_votes

__all__ = [
    "locate_instances",
    "verify_cluster",
]


def _affine(src: np.ndarray, dst: np.ndarray) -> np.ndarray | None:
    r"""Least-squares affine map :math:`dst = A\,[src;\ 1]` (Lowe's equation (5): the
    normal equations of the 6 parameters), as a 3×3 matrix, or None when the points are
    (nearly) collinear."""
    if len(src) < 3:
        return None
    centre = src.mean(axis=0)
    design = np.column_stack([src - centre, np.ones(len(src))])
    if len(src) == 3:
        if abs(np.linalg.det(design)) < 1.0:  # twice the triangle's area, in pixels
            return None
        solution = np.linalg.solve(design, dst)
    else:
        if np.linalg.eigvalsh((design[:, :2].T @ design[:, :2]) / len(src))[0] < 0.25:
            return None
        solution, *_ = np.linalg.lstsq(design, dst, rcond=None)
    affine = np.vstack([solution.T, [0.0, 0.0, 1.0]])
    return affine @ np.array([[1.0, 0.0, -centre[0]], [0.0, 1.0, -centre[1]], [0.0, 0.0, 1.0]])


def _residual(h: np.ndarray, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    error = np.linalg.norm(apply_homography(h, src) - dst, axis=1)
    return np.where(np.isfinite(error), error, np.inf)


def _consistent(
    h: np.ndarray,
    views: ModelViews,
    scene_keypoints: KeypointSet,
    pairs: np.ndarray,
    params: ConstellationParams,
    threshold: float,
) -> np.ndarray:
    r"""Matches that agree with ``h`` (a homography or an affine map): position within
    ``threshold`` px, orientation within
    ``orientation_tolerance`` degrees and scale within a factor ``scale_tolerance`` of
    what the local affine map predicts for the model keypoint, :math:`J = J_H(u) F`
    (:math:`J_H` the homography's Jacobian at the keypoint's model position :math:`u`,
    :math:`F` its view's map to the model): orientation :math:`\angle J (\cos\theta,
    \sin\theta)^T`, scale :math:`\sigma \sqrt{|\det J|}`."""
    model, scene = pairs[:, 1], pairs[:, 0]
    points = views.xy[model]
    w = points @ h[2, :2] + h[2, 2]
    mapped = apply_homography(h, points)
    jacobian = (h[None, :2, :2] - mapped[:, :, None] * h[None, 2:3, :2]) / w[:, None, None]
    jacobian = jacobian @ views.frame[model]
    close = np.linalg.norm(mapped - scene_keypoints.xy[scene], axis=1) < threshold
    theta = views.keypoints.orientation[model]
    direction = np.einsum("nij,nj->ni", jacobian, np.column_stack([np.cos(theta), np.sin(theta)]))
    predicted = np.arctan2(direction[:, 1], direction[:, 0])
    turn = np.angle(np.exp(1j * (scene_keypoints.orientation[scene] - predicted)))
    stretch = np.sqrt(np.abs(np.linalg.det(jacobian)))
    with np.errstate(divide="ignore", invalid="ignore"):
        size = np.log(scene_keypoints.scale[scene] / (views.keypoints.scale[model] * stretch))
        agree = (np.abs(np.degrees(turn)) < params.orientation_tolerance) & (
            np.abs(size) < math.log(params.scale_tolerance)
        )
    return close & agree & (w > 0)


def _valid_quad(h: np.ndarray, size: tuple[int, int], scene_shape: tuple[int, int]) -> bool:
    """The model maps in front of the camera (w > 0 at every corner), unmirrored, to a
    convex quadrilateral of at least 8 × 8 px whose centre is inside the scene."""
    corners = _corners(size)
    w = corners @ h[2, :2] + h[2, 2]
    if not (w > 0).all():
        return False
    quad = apply_homography(h, corners)
    if not np.isfinite(quad).all() or not _is_convex(quad):
        return False
    area = polygon_area(quad)
    if np.sign(area) != np.sign(polygon_area(corners)) or abs(area) < 64:
        return False
    centre = quad.mean(axis=0)
    return bool(0 <= centre[0] < scene_shape[1] and 0 <= centre[1] < scene_shape[0])


class Hypothesis(NamedTuple):
    homography: np.ndarray
    inliers: np.ndarray  # match indices
    probability: float


def _gather_by_affine(
    cluster: np.ndarray,
    views: ModelViews,
    scene_keypoints: KeypointSet,
    pairs: np.ndarray,
    params: ConstellationParams,
) -> np.ndarray | None:
    """Stages 1 and 2 of :func:`verify_cluster`: the matches (indices into ``pairs``)
    consistent with the cluster's affine pose, or None."""
    src_all = views.xy[pairs[:, 1]]
    dst_all = scene_keypoints.xy[pairs[:, 0]]
    src, dst = src_all[cluster], dst_all[cluster]
    ratio = scene_keypoints.scale[pairs[cluster, 0]] / views.keypoints.scale[pairs[cluster, 1]]
    loose = 0.5 * params.location_bin * max(views.size) * float(np.median(ratio))
    found = ransac(
        len(cluster),
        3,
        lambda s: _affine(src[s], dst[s]),
        lambda a: _residual(a, src, dst),
        loose,
        refit=lambda i: _affine(src[i], dst[i]),
        max_iterations=100,
        seed=params.seed,
    )
    if found.model is None or found.inliers.sum() < 3:
        return None
    affine = found.model
    for _ in range(2):
        if np.linalg.det(affine[:2, :2]) <= 0:
            return None  # a mirror image: not a view of the model
        members = np.flatnonzero(_consistent(affine, views, scene_keypoints, pairs, params, loose))
        if len(members) < max(params.min_inliers, 5):
            return None
        refit = _affine(src_all[members], dst_all[members])
        if refit is None:
            return None
        affine = refit
    return members


def verify_cluster(
    cluster: np.ndarray,
    views: ModelViews,
    scene_keypoints: KeypointSet,
    pairs: np.ndarray,
    scene_shape: tuple[int, int],
    params: ConstellationParams,
) -> Hypothesis | None:
    r"""Verify one Hough cluster (match indices ``cluster``) by fitting its pose.

    1. RANSAC on an affine map (samples of 3) from the cluster's model positions to its
       scene positions, inliers within half a location bin (Lowe: half the error range
       of the Hough bins);
    2. top-down: every match (not only the cluster's) within that distance of the affine
       prediction, and agreeing with it in orientation and scale (:func:`_consistent`),
       joins; least squares again, twice (a mirroring map is refused);
    3. RANSAC on a homography (normalised DLT on samples of 4) over the gathered
       matches, inliers within ``threshold`` px;
    4. top-down again: all matches consistent with the homography in position,
       orientation and scale (:func:`_consistent`), refitted by DLT until the set is
       stable (at most 5 rounds), then by Levenberg-Marquardt.

    Returns None when a stage keeps too few matches or the pose is implausible (behind
    the camera, mirrored, not convex); else the homography, its inliers and
    :func:`pose_probability`.
    """
    if len(cluster) < 3:
        return None
    src_all = views.xy[pairs[:, 1]]
    dst_all = scene_keypoints.xy[pairs[:, 0]]
    members = _gather_by_affine(cluster, views, scene_keypoints, pairs, params)
    if members is None:
        return None
    a, b = src_all[members], dst_all[members]
    fit = ransac(
        len(members),
        4,
        lambda s: estimate_homography(a[s], b[s]),
        lambda h: _residual(h, a, b),
        params.threshold,
        refit=lambda i: estimate_homography(a[i], b[i]),
        confidence=0.995,
        max_iterations=200,
        seed=params.seed,
    )
    if fit.model is None:
        return None
    h, inliers = fit.model, members[fit.inliers]
    for _ in range(5):
        agree = np.flatnonzero(
            _consistent(h, views, scene_keypoints, pairs, params, params.threshold)
        )
        if len(agree) < 5:
            return None
        refit = estimate_homography(src_all[agree], dst_all[agree])
        if refit is None:
            return None
        stable = np.array_equal(agree, inliers)
        h, inliers = refit, agree
        if stable:
            break
    h = refine_homography(h, src_all[inliers], dst_all[inliers])
    if not _valid_quad(h, views.size, scene_shape):
        return None
    probability = pose_probability(h, inliers, views, scene_keypoints, pairs, params)
    return Hypothesis(h, inliers, probability)


def locate_instances(
    views: ModelViews,
    scene_keypoints: KeypointSet,
    pairs: np.ndarray,
    scene_shape: tuple[int, int],
    params: ConstellationParams,
) -> tuple[InstanceSet, PoseVotes]:
    """Every instance of the model (see the module): the Hough table (:func:`pose_votes`),
    each bin of at least ``min_votes`` votes verified (:func:`verify_cluster`), largest
    first (at most ``max_clusters``; a bin whose matches mostly support an accepted
    instance already, or were all tried in a rejected bin, is skipped), accepted when
    :math:`P(m \\mid f) \\ge` ``min_probability`` with at least ``min_inliers`` distinct
    inliers; then non-maximum suppression: of two instances whose quadrilaterals overlap
    by more than ``nms_iou``, the one with more inliers stays."""
    votes = pose_votes(views, scene_keypoints, pairs, params)
    order = np.argsort(-votes.counts, kind="stable")
    order = order[votes.counts[order] >= params.min_votes][: params.max_clusters]
    claimed = np.zeros(len(pairs), bool)
    tried: set[tuple[int, ...]] = set()
    accepted: list[Hypothesis] = []
    for b in order:
        cluster = votes.members[votes.starts[b] : votes.starts[b + 1]]
        if claimed[cluster].mean() > 0.5:
            continue
        signature = tuple(np.sort(cluster).tolist())
        if signature in tried:
            continue
        tried.add(signature)
        hypothesis = verify_cluster(cluster, views, scene_keypoints, pairs, scene_shape, params)
        if hypothesis is None:
            continue
        distinct = _unique_positions(scene_keypoints.xy[pairs[hypothesis.inliers, 0]])
        if distinct < params.min_inliers or hypothesis.probability < params.min_probability:
            continue
        accepted.append(hypothesis)
        claimed[hypothesis.inliers] = True
    accepted.sort(key=lambda one: -len(one.inliers))
    corners = _corners(views.size)
    kept: list[tuple[Hypothesis, np.ndarray]] = []
    for hypothesis in accepted:
        quad = apply_homography(hypothesis.homography, corners)
        if all(quad_iou(quad, other) <= params.nms_iou for _, other in kept):
            kept.append((hypothesis, quad))
    if not kept:
        return InstanceSet.empty(), votes
    instances = InstanceSet(
        np.array([quad for _, quad in kept], np.float64),
        np.array([one.homography for one, _ in kept], np.float64),
        np.array([len(one.inliers) for one, _ in kept], np.int64),
        np.array([one.probability for one, _ in kept], np.float64),
        np.zeros(len(kept), np.int64),
    )
    return instances, votes
