"""Two-view nodes that estimate the epipolar geometry from matched points: a robust
fundamental matrix F (RANSAC on the normalised eight-point algorithm, refused when a
homography explains the matches as well) and an essential matrix E (from points with
known cameras, or from F)."""

from __future__ import annotations

from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Camera, Conformance, Float, Int, Points2D, node

from ..camera import normalise_pixels
from ..fitting._ransac import model_significance, refuse_chance
from ..geometry._homography import ransac_four_point
from ..shared.checks import check_reference_method
from ..shared.params import Iterations, Positive, Probability, Seed
from ._checks import _pairs
from ._geometry import (
    essential_from_fundamental,
    ransac_eight_point,
    refine_fundamental,
    sampson_distance,
)
from ._ports import Essential, Fundamental

__all__ = [
    "essential",
    "essential_from_points",
    "fundamental",
    "robust_fundamental",
]


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
