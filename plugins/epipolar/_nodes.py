"""Two-view nodes: robust F, E, relative pose by cheirality, triangulation, errors."""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from graphvision import (
    Array,
    ArrayPort,
    Camera,
    Conformance,
    Float,
    Int,
    Keypoints,
    Matches,
    PinholeCamera,
    Points2D,
    Points3D,
    PortValueError,
    node,
)

from ..camera import normalise_pixels
from ..fitting._ransac import model_significance, refuse_chance
from ..geometry._homography import ransac_four_point
from ..shared.checks import check_reference_method
from ..shared.params import Iterations, Positive, Probability, Seed
from ._geometry import (
    essential_from_fundamental,
    poses_from_essential,
    ransac_eight_point,
    refine_fundamental,
    refine_pose,
    reprojection_residuals,
    sampson_distance,
    triangulate_linear,
    triangulate_nonlinear,
)

__all__ = [
    "EssentialPort",
    "FundamentalPort",
    "essential",
    "essential_from_points",
    "fundamental",
    "matched_points",
    "mean_abs_dy",
    "pose_error",
    "relative_pose",
    "reprojection_errors",
    "reprojection_rms",
    "robust_fundamental",
    "triangulate",
]


class FundamentalPort(ArrayPort):
    """A fundamental matrix: finite ``float64`` 3×3 of rank 2, ``x_b^T F x_a = 0``, unit norm."""

    ndims: ClassVar[tuple[int, ...]] = (2,)
    dtypes = (np.float64,)
    expected = "finite float64 3×3"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape != (3, 3) or not np.isfinite(value).all():
            raise PortValueError(
                f"expected {cls.type_name()} (finite float64 3×3), got {value.shape}"
            )
        return value


class EssentialPort(FundamentalPort):
    """An essential matrix :math:`E = [t]_\\times R` (singular values 1, 1, 0)."""


Fundamental = Annotated[NDArray[np.float64], FundamentalPort]
Essential = Annotated[NDArray[np.float64], EssentialPort]


def _pairs(a: np.ndarray, b: np.ndarray, least: int, what: str) -> None:
    if len(a) != len(b):
        raise ValueError(f"{what}: {len(a)} points in view a but {len(b)} in view b")
    if len(a) < least:
        raise ValueError(f"{what} needs at least {least} correspondences, got {len(a)}")


def _refuse_a_homography(a: np.ndarray, b: np.ndarray, threshold: float, seed: int) -> None:
    """Refuse correspondences that one homography explains: a plane, or a camera turning
    about its centre, leaves F undetermined (a family of solutions: H^{-T}[v]_x), so any F
    RANSAC returns is arbitrary (the test of DEGENSAC and model selection in SLAM)."""
    # Only a share of 90 % or more matters: then a 4-point sample is clean with probability
    # 0.9^4 = 0.66, and 25 samples miss every clean one with probability 0.34^25 < 1e-11.
    planar = ransac_four_point(a, b, 2.0 * threshold, max_iterations=25, seed=seed)
    share = float(planar.inliers.mean()) if planar.model is not None else 0.0
    if share >= 0.9:
        raise ValueError(
            f"{100 * share:.0f} % of the correspondences fit one homography: the scene is a "
            "plane or the camera only turned, so F is not determined (use "
            "geometry.homography_ransac)"
        )


class FundamentalFit(NamedTuple):
    F: Fundamental
    inlier_count: Int
    sampson_rms: Float
    inliers_a: Points2D
    inliers_b: Points2D
    log_nfa: Float


MaxNfa = Annotated[
    float | None,
    Field(gt=0, description="Largest number of false alarms accepted (null: every model)."),
]
"""The largest NFA of a model a robust fit returns (1: the a-contrario convention; None
reports the NFA and refuses nothing)."""


@node(
    "epipolar.fundamental",
    version=2,
    conformance=Conformance(
        "sampson",
        1.5,
        note=(
            "OpenCV's F is not refined by Levenberg-Marquardt: on the conformance scene "
            "(0.5 px noise) it fits the reference's inliers to 1.0 px RMS Sampson, the "
            "reference to 0.55 px; method: magsac (OpenCV's USAC_MAGSAC) has no reference "
            "implementation and is compared with the reference's RANSAC"
        ),
    ),
)
def fundamental(
    a: Points2D,
    b: Points2D,
    *,
    threshold: Positive = 1.0,
    confidence: Probability = 0.999,
    max_iterations: Iterations = 2000,
    max_nfa: MaxNfa = 1.0,
    seed: Seed = 0,
    method: Literal["ransac", "magsac"] = "ransac",
) -> FundamentalFit:
    r"""Robust F: RANSAC over 8-point samples scored by Sampson distance, refit on the inliers,
    refused when chance explains its inliers.

    Each sample gives F by the normalised 8-point algorithm with rank 2
    enforced; inliers are within ``threshold`` pixels (Sampson distance);
    the best model is refit on all its inliers and the inliers re-collected
    until stable (the generic :func:`~graphvision_plugins.fitting.ransac`);
    finally the Sampson distances of the inliers are minimised
    (Levenberg-Marquardt over F's 7 degrees of freedom, rank 2 throughout).

    Significance (a-contrario, :mod:`graphvision_plugins.fitting._ransac`): with
    α the probability that a correspondence of two independent points, uniform
    over each view's bounding box, is within ``threshold`` of the model, the
    number of false alarms of k inliers among n is

    .. math::

        \mathrm{NFA} = (n - 8)\binom{n}{8}\, P\bigl(B(n - 8, \alpha) \ge k - 8\bigr),

    how many models this well supported RANSAC would find in correspondences
    made at random. A model with NFA above ``max_nfa`` is refused.

    Parameters
    ----------
    a, b : Points2D
        Corresponding pixels in the two views, row by row.
    threshold : float
        Inlier Sampson distance, pixels.
    confidence : float
        Probability of drawing one outlier-free sample; sets the iterations.
    max_iterations : int
        Upper bound on the samples.
    max_nfa : float
        Largest number of false alarms accepted (1: at most one such model
        expected from chance; None accepts every model).
    seed : int
        Seed of the sampler (and of the draws that measure α).
    method : {"ransac", "magsac"}
        ``ransac``: the consensus above. ``magsac``: MAGSAC++ [3]_, implemented by the
        ``opencv`` backend alone (``cv2.USAC_MAGSAC``); the reference refuses it at
        validation, naming that backend.

    Returns
    -------
    F : (3, 3) float64, unit Frobenius norm
    inlier_count : int
    sampson_rms : float, pixels over the inliers
    inliers_a, inliers_b : the inlier correspondences
    log_nfa : float, log10 of the model's NFA (−20: one such model in 1e20 sets of
        random correspondences)

    Raises
    ------
    ValueError
        When chance explains the best model (NFA above ``max_nfa``), when fewer
        than 8 correspondences fit it, or when one homography explains them.

    References
    ----------
    .. [1] R. Hartley, A. Zisserman, *Multiple View Geometry*, 2nd ed., 2004, §11.
    .. [2] L. Moisan, B. Stival, "A probabilistic criterion to detect rigid point
       matches between two images and estimate the fundamental matrix", IJCV
       57(3), 2004.
    .. [3] D. Barath, J. Noskova, M. Ivashechkin, J. Matas, "MAGSAC++, a fast, reliable
       and accurate robust estimator", CVPR 2020.
    """
    check_reference_method(method)
    _pairs(a, b, 8, "the fundamental matrix")
    F, inliers, log_nfa = robust_fundamental(
        a, b, threshold, confidence, max_iterations, seed, max_nfa=max_nfa
    )
    rms = float(np.sqrt(np.mean(sampson_distance(F, a[inliers], b[inliers]) ** 2)))
    return FundamentalFit(F, int(inliers.sum()), rms, a[inliers], b[inliers], log_nfa)


def robust_fundamental(
    a: np.ndarray,
    b: np.ndarray,
    threshold: float,
    confidence: float = 0.999,
    max_iterations: int = 2000,
    seed: int = 0,
    homography_threshold: float | None = None,
    *,
    what: str = "the fundamental matrix",
    pixel_threshold: float | None = None,
    max_nfa: float | None = 1.0,
) -> tuple[np.ndarray, np.ndarray, float]:
    """F, its inlier mask and log10 NFA by :func:`fundamental`'s method (``a``, ``b`` in any
    units; ``homography_threshold`` defaults to twice ``threshold``). ValueError naming
    ``what`` and the threshold (``pixel_threshold`` when given: the user's value before a
    change of units) when fewer than 8 correspondences are inliers, or when the NFA is
    above ``max_nfa`` (None: never)."""
    found = ransac_eight_point(a, b, threshold, confidence, max_iterations, seed)
    if found.model is None:
        raise ValueError(
            "no fundamental matrix: every sample of 8 correspondences was degenerate "
            "(points on a line or a plane seen without noise)"
        )
    shown = threshold if pixel_threshold is None else pixel_threshold
    data = np.hstack([a, b])
    found.require_support(8, shown, what, data=data)
    model = found.model
    support, count = found.support(data)
    log_nfa, alpha = model_significance(
        lambda pa, pb: sampson_distance(model, pa, pb) < threshold,
        (a, b),
        count,
        8,
        support,
        max_nfa=max_nfa,
        seed=seed,
    )
    refuse_chance(log_nfa, max_nfa, what, support, count, alpha)
    inliers = found.inliers
    _refuse_a_homography(a[inliers], b[inliers], threshold, seed)
    return refine_fundamental(model, a[inliers], b[inliers]), inliers, log_nfa


class EssentialFit(NamedTuple):
    E: Essential
    inlier_count: Int
    inliers_a: Points2D
    inliers_b: Points2D
    log_nfa: Float


@node(
    "epipolar.essential_from_points",
    version=2,
    conformance=Conformance(
        "up_to_scale",
        0.05,
        note=(
            "OpenCV samples five points (Nistér) where the reference samples eight and "
            "refines by Sampson's distance; E is compared at unit norm up to sign: 0.025 "
            "apart on the conformance scene (0.5 px noise, 20 outliers in 150); method: "
            "magsac (OpenCV's USAC_MAGSAC) has no reference implementation and is compared "
            "with the reference's RANSAC"
        ),
    ),
)
def essential_from_points(
    a: Points2D,
    b: Points2D,
    camera_a: Camera,
    camera_b: Camera,
    *,
    threshold: Positive = 1.0,
    confidence: Probability = 0.999,
    max_iterations: Iterations = 2000,
    max_nfa: MaxNfa = 1.0,
    seed: Seed = 0,
    method: Literal["ransac", "magsac"] = "ransac",
) -> EssentialFit:
    r"""E directly from normalised points: :func:`fundamental`'s robust method on
    :math:`\hat x = K^{-1} x`, then singular values forced to (1, 1, 0).

    In normalised coordinates :math:`\hat x_b^T E \hat x_a = 0`, so the 8-point
    algorithm (with RANSAC, refit and Sampson refinement) gives E up to its
    internal constraint, imposed by :math:`E = U \operatorname{diag}(1, 1, 0) V^T`.
    The pixel threshold is turned into normalised units by the mean focal length.
    The model's significance is :func:`fundamental`'s (NFA, refused above
    ``max_nfa``), measured in normalised units.

    Parameters
    ----------
    a, b : Points2D
        Corresponding pixels.
    camera_a, camera_b : Camera
        Their calibrations (only K is used; undistort points first).
    threshold : float
        Inlier Sampson distance, pixels.
    confidence : float
        Probability of drawing one outlier-free sample.
    max_iterations : int
        Upper bound on the samples.
    max_nfa : float
        Largest number of false alarms accepted (None: every model).
    seed : int
        Seed of the sampler.
    method : {"ransac", "magsac"}
        ``ransac``: the consensus above. ``magsac``: MAGSAC++ [3]_ over Nistér's
        five-point samples, implemented by the ``opencv`` backend alone
        (``cv2.findEssentialMat(..., cv2.USAC_MAGSAC)``); the reference refuses it at
        validation, naming that backend.

    Returns
    -------
    E : Essential
    inlier_count : int
    inliers_a, inliers_b : Points2D
    log_nfa : float, log10 of the model's number of false alarms

    References
    ----------
    .. [1] R. Hartley, A. Zisserman, *Multiple View Geometry*, 2nd ed., 2004, §9.6.
    .. [2] L. Moisan, B. Stival, IJCV 57(3), 2004 (the significance).
    .. [3] D. Barath, J. Noskova, M. Ivashechkin, J. Matas, "MAGSAC++, a fast, reliable
       and accurate robust estimator", CVPR 2020.
    """
    check_reference_method(method)
    _pairs(a, b, 8, "the essential matrix from points")
    focal = float(np.mean([camera_a.K[0, 0], camera_a.K[1, 1], camera_b.K[0, 0], camera_b.K[1, 1]]))
    na, nb = normalise_pixels(a, camera_a.K), normalise_pixels(b, camera_b.K)
    E, inliers, log_nfa = robust_fundamental(
        na, nb, threshold / focal, confidence, max_iterations, seed,
        what="the essential matrix", pixel_threshold=threshold, max_nfa=max_nfa,
    )  # fmt: skip
    E = essential_from_fundamental(E, np.eye(3), np.eye(3))
    return EssentialFit(E, int(inliers.sum()), a[inliers], b[inliers], log_nfa)


@node("epipolar.essential", version=1)
def essential(F: Fundamental, camera_a: Camera, camera_b: Camera) -> Essential:
    r""":math:`E = K_b^T F K_a`, singular values forced to (1, 1, 0).

    Parameters
    ----------
    F : Fundamental
        The fundamental matrix of the pair.
    camera_a, camera_b : Camera
        Their calibrations (only K is used).
    """
    return essential_from_fundamental(F, camera_a.K, camera_b.K)


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
