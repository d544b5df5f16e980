"""Two-view nodes: relative pose by cheirality, triangulation, errors (robust F and E are
in ``_fundamental``)."""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np

from graphvision import (
    Array,
    Camera,
    Conformance,
    Float,
    Keypoints,
    Matches,
    PinholeCamera,
    Points2D,
    Points3D,
    node,
)

from ..shared.params import Positive
from ._checks import _pairs
from ._geometry import (
    poses_from_essential,
    refine_pose,
    reprojection_residuals,
    sampson_distance,
    triangulate_linear,
    triangulate_nonlinear,
)
from ._ports import Essential

__all__ = [
    "matched_points",
    "mean_abs_dy",
    "pose_error",
    "relative_pose",
    "reprojection_errors",
    "reprojection_rms",
    "triangulate",
]


class MatchedPoints(NamedTuple):
    a: Points2D
    b: Points2D


@node("epipolar.matched_points", version=1)
def matched_points(
    keypoints_a: Keypoints, keypoints_b: Keypoints, matches: Matches
) -> MatchedPoints:
    """The positions of matched keypoints, row by row: the correspondences two-view nodes take.

    Parameters
    ----------
    keypoints_a, keypoints_b : Keypoints
        Keypoints of the two images.
    matches : Matches
        Pairs (index in ``keypoints_a``, index in ``keypoints_b``).
    """
    return MatchedPoints(
        keypoints_a.xy[matches.pairs[:, 0]].copy(), keypoints_b.xy[matches.pairs[:, 1]].copy()
    )


@node("epipolar.mean_abs_dy", version=1)
def mean_abs_dy(a: Points2D, b: Points2D) -> Float:
    """Mean |y_a − y_b| of correspondences, pixels: 0 for true matches of a rectified pair.

    Parameters
    ----------
    a, b : Points2D
        Corresponding pixels.
    """
    _pairs(a, b, 1, "mean |dy|")
    return float(np.mean(np.abs(a[:, 1] - b[:, 1])))


class RelativePose(NamedTuple):
    reference: Camera
    moved: Camera


@node(
    "epipolar.relative_pose",
    version=1,
    conformance=Conformance(
        "rotation_error",
        1.0,
        note="OpenCV does not refine the pose over the pairs within inlier_threshold",
    ),
)
def relative_pose(
    E: Essential,
    a: Points2D,
    b: Points2D,
    camera_a: Camera,
    camera_b: Camera,
    *,
    inlier_threshold: Positive = 1.5,
) -> RelativePose:
    r"""The pose of view b relative to view a (at :math:`[I \mid 0]`), baseline 1, by cheirality.

    Of the four decompositions of E, the one that puts the most triangulated
    correspondences in front of both cameras is kept; it is then refined by
    minimising the Sampson distances of the correspondences within
    ``inlier_threshold`` pixels over the pose's 5 degrees of freedom.

    Parameters
    ----------
    E : Essential
        The essential matrix.
    a, b : Points2D
        Corresponding pixels (inliers of F, ideally).
    camera_a, camera_b : Camera
        Calibrations (K) of the views.
    inlier_threshold : float
        Sampson distance (pixels) of the correspondences used to refine.

    Returns
    -------
    reference : camera a at the origin (K of a, R = I, C = 0)
    moved : camera b (K of b, R, C = −Rᵀt with |t| = 1)

    Raises
    ------
    ValueError
        When no decomposition puts any point in front of both cameras.
    """
    _pairs(a, b, 5, "the relative pose")
    Pa = camera_a.K @ np.hstack([np.eye(3), np.zeros((3, 1))])
    best, best_front = None, 0
    for R, t in poses_from_essential(E):
        Pb = camera_b.K @ np.hstack([R, t[:, None]])
        points = triangulate_linear(Pa, Pb, a, b)
        depth_a = points[:, 2]
        depth_b = (points @ R.T + t)[:, 2]
        front = int(np.sum((depth_a > 0) & (depth_b > 0)))
        if front > best_front:
            best, best_front = (R, t), front
    if best is None:
        raise ValueError("no pose puts the points in front of both cameras (E is wrong for them)")
    R, t = best
    F = np.linalg.inv(camera_b.K).T @ E @ np.linalg.inv(camera_a.K)
    close = sampson_distance(F / np.linalg.norm(F), a, b) < inlier_threshold
    if close.sum() >= 5:
        R, t = refine_pose(R, t, camera_a.K, camera_b.K, a[close], b[close])
    reference = PinholeCamera(camera_a.K.copy(), size=camera_a.size.copy())
    moved = PinholeCamera(camera_b.K.copy(), R, -R.T @ t, size=camera_b.size.copy())
    return RelativePose(reference, moved)


@node(
    "epipolar.triangulate",
    version=2,
    conformance=Conformance(
        "max_abs",
        0.01,
        note=(
            "OpenCV's linear DLT is not Hartley-normalised: on the conformance scene (points "
            "6 m away, 0.5 px noise) its points are up to 3 mm from the reference's; "
            "nonlinear refines both to the same points"
        ),
    ),
)
def triangulate(
    a: Points2D,
    b: Points2D,
    camera_a: Camera,
    camera_b: Camera,
    *,
    method: Literal["nonlinear", "linear"] = "nonlinear",
) -> Points3D:
    r"""3-D points from two views: linear (DLT), then by default refined to the least
    reprojection error.

    The linear method takes the null vector of :math:`x \times P X = 0` in
    both views (an algebraic error); ``nonlinear`` then minimises the
    geometric error :math:`\sum_v \lVert \pi(P_v X) - x_v \rVert^2` per point
    by Levenberg-Marquardt, the maximum-likelihood estimate under Gaussian
    pixel noise.

    Parameters
    ----------
    a, b : Points2D
        Corresponding pixels.
    camera_a, camera_b : Camera
        The two cameras (P = K[R | −RC̃]).
    method : {"nonlinear", "linear"}
        Refine the DLT's points, or keep them.

    Returns
    -------
    Points3D
        One point per correspondence; a pair whose rays are parallel (a point
        at infinity) is refused.
    """
    _pairs(a, b, 1, "triangulation")
    if np.linalg.norm(camera_a.C - camera_b.C) < 1e-12:
        raise ValueError(
            "the two cameras have the same centre: a zero baseline triangulates nothing"
        )
    points = triangulate_linear(camera_a.P, camera_b.P, a, b)
    if not np.isfinite(points).all():
        bad = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
        raise ValueError(
            f"correspondence {bad} triangulates to a point at infinity (parallel rays: "
            "a zero baseline or a mismatch)"
        )
    if method == "nonlinear":
        points = triangulate_nonlinear(camera_a.P, camera_b.P, a, b, points)
    return points


@node("epipolar.reprojection_errors", version=1)
def reprojection_errors(
    points: Points3D, a: Points2D, b: Points2D, camera_a: Camera, camera_b: Camera
) -> Array:
    r"""Reprojection error of each point, in pixels.

    :math:`\sqrt{(e_a^2 + e_b^2) / 2}` with :math:`e_v` its distance to the
    observed pixel in view v.

    Parameters
    ----------
    points : Points3D
        Triangulated points.
    a, b : Points2D
        The observed pixels.
    camera_a, camera_b : Camera
        The cameras that observed them.
    """
    _pairs(a, b, 0, "reprojection")
    residual = reprojection_residuals((camera_a.P, camera_b.P), (a, b), points)
    errors: np.ndarray = np.sqrt(np.sum(residual**2, axis=1) / 2)
    return errors


@node("epipolar.reprojection_rms", version=1)
def reprojection_rms(
    points: Points3D, a: Points2D, b: Points2D, camera_a: Camera, camera_b: Camera
) -> Float:
    """Root mean square distance, pixels, between the points' projections and a, b.

    Parameters
    ----------
    points : Points3D
        Triangulated points.
    a, b : Points2D
        The observed pixels.
    camera_a, camera_b : Camera
        The cameras that observed them.
    """
    errors = []
    for camera, seen in ((camera_a, a), (camera_b, b)):
        homogeneous = np.column_stack([points, np.ones(len(points))]) @ camera.P.T
        projected = homogeneous[:, :2] / homogeneous[:, 2:]
        errors.append(np.sum((projected - seen) ** 2, axis=1))
    return float(np.sqrt(np.mean(np.concatenate(errors))))


class PoseError(NamedTuple):
    rotation_error_deg: Float
    translation_error_deg: Float


@node("epipolar.pose_error", version=1)
def pose_error(moved: Camera, truth_a: Camera, truth_b: Camera) -> PoseError:
    r"""Angles between an estimated relative pose and the true one, in degrees.

    The truth: :math:`R = R_b R_a^T`, :math:`t = R_b (\tilde C_a - \tilde C_b)`;
    the rotation error is the angle of :math:`\hat R R^T`, the translation
    error the angle between :math:`\hat t` and :math:`t` (scale is unknown).

    Parameters
    ----------
    moved : Camera
        Estimated camera b relative to a (``epipolar.relative_pose``).
    truth_a, truth_b : Camera
        The true cameras; at the same centre (a zero baseline: no translation direction
        to compare with) they are refused.
    """
    if np.linalg.norm(truth_a.C - truth_b.C) < 1e-12:
        raise ValueError(
            "truth_a and truth_b have the same centre: a zero baseline has no translation "
            "direction to compare with (and two views from one centre determine no pose)"
        )
    R_true = truth_b.R @ truth_a.R.T
    t_true = truth_b.R @ (truth_a.C - truth_b.C)
    cos_r = np.clip((np.trace(moved.R @ R_true.T) - 1) / 2, -1.0, 1.0)
    t_est = moved.t
    cos_t = np.clip(t_est @ t_true / (np.linalg.norm(t_est) * np.linalg.norm(t_true)), -1.0, 1.0)
    return PoseError(float(np.degrees(np.arccos(cos_r))), float(np.degrees(np.arccos(cos_t))))
