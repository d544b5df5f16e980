"""Homography estimation: normalised DLT, Levenberg-Marquardt refinement, RANSAC."""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Conformance, Float, FloatImage, Homography, Keypoints, Matches, node

from ..fitting._ransac import RansacResult, _refit_to_convergence, model_significance, refuse_chance
from ..shared.checks import check_reference_method
from ..shared.params import ImageSide, Iterations, Positive, Probability, Seed

__all__ = [
    "apply_homography",
    "corner_error",
    "estimate_homography",
    "homography_ransac",
    "normalising_transform",
    "ransac_four_point",
    "refine_homography",
    "transfer_error",
]


def apply_homography(h: np.ndarray, points: np.ndarray) -> np.ndarray:
    r"""Map ``(x, y)`` points through ``h`` (homogeneous coordinates, then divide by w).

    :math:`x' = (h_{11}x + h_{12}y + h_{13}) / (h_{31}x + h_{32}y + h_{33})`, likewise :math:`y'`.
    """
    mapped = points @ h[:2, :2].T + h[:2, 2]
    w = points @ h[2, :2] + h[2, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        return mapped / w[:, None]


def normalising_transform(points: np.ndarray) -> np.ndarray:
    r"""The similarity :math:`T` taking the points' mean to 0 and RMS distance to :math:`\sqrt 2`.

    (Zero mean and unit variance per coordinate: Hartley's preconditioning.)
    """
    centre = points.mean(axis=0)
    spread = np.sqrt(((points - centre) ** 2).sum(axis=1).mean())
    scale = np.sqrt(2.0) / spread if spread > 0 else 1.0
    return np.array([[scale, 0, -scale * centre[0]], [0, scale, -scale * centre[1]], [0, 0, 1.0]])


def estimate_homography(src: np.ndarray, dst: np.ndarray) -> np.ndarray | None:
    r"""Normalised DLT: the homography with :math:`dst \simeq H\, src` from ≥ 4 correspondences.

    1. precondition each point set: :math:`\tilde x = T x`, :math:`\tilde x' = T' x'`;
    2. stack two rows per correspondence,
       :math:`[-\tilde x^T, 0, x'\tilde x^T]` and :math:`[0, -\tilde x^T, y'\tilde x^T]`,
       and take :math:`\tilde h` as the right singular vector of the smallest
       singular value (:math:`\|\tilde h\| = 1`);
    3. undo the preconditioning: :math:`H = T'^{-1} \tilde H T`, scaled so :math:`h_{33} = 1`.

    Returns None for a degenerate configuration (three of four points
    collinear, all points coincident, or a rank-deficient system), never NaN.

    References
    ----------
    .. [1] R. Hartley, "In defense of the eight-point algorithm", IEEE TPAMI
       19(6), 1997; Hartley & Zisserman, *Multiple View Geometry*, 2nd ed.,
       2004, algorithm 4.2.
    """
    if len(src) < 4 or not (np.isfinite(src).all() and np.isfinite(dst).all()):
        return None
    t_src, t_dst = normalising_transform(src), normalising_transform(dst)
    a = apply_homography(t_src, src)
    b = apply_homography(t_dst, dst)
    if len(src) == 4 and (_collinear_triple(a) or _collinear_triple(b)):
        return None
    ones, zeros = np.ones(len(a)), np.zeros((len(a), 3))
    xs = np.column_stack([a, ones])
    rows = np.empty((2 * len(a), 9))
    rows[0::2] = np.hstack([-xs, zeros, b[:, :1] * xs])
    rows[1::2] = np.hstack([zeros, -xs, b[:, 1:] * xs])
    # the reduced SVD: the full one also builds U, 2N × 2N (1800² for 900 matches)
    _, singular, vt = np.linalg.svd(rows, full_matrices=rows.shape[0] < rows.shape[1])
    if singular[-2] < 1e-10 * singular[0]:
        return None  # the solution is not unique: degenerate points
    h = np.linalg.inv(t_dst) @ vt[-1].reshape(3, 3) @ t_src
    if abs(h[2, 2]) < 1e-12 or not np.isfinite(h).all():
        return None
    return h / h[2, 2]


def _collinear_triple(points: np.ndarray) -> bool:
    for i, j, k in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)):
        u, v = points[j] - points[i], points[k] - points[i]
        if abs(u[0] * v[1] - u[1] * v[0]) < 1e-6:
            return True
    return False


def transfer_error(h: np.ndarray, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Forward reprojection error ``|| H src - dst ||`` in pixels (inf behind the camera)."""
    error = np.linalg.norm(apply_homography(h, src) - dst, axis=1)
    return np.where(np.isfinite(error), error, np.inf)


def refine_homography(h: np.ndarray, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Levenberg-Marquardt on the reprojection error (8 parameters, ``h33 = 1``)."""
    from scipy.optimize import least_squares

    if len(src) < 5:
        return h

    def residual(p: np.ndarray) -> np.ndarray:
        return (apply_homography(np.append(p, 1.0).reshape(3, 3), src) - dst).ravel()

    fit = least_squares(residual, (h / h[2, 2]).ravel()[:8], method="lm", max_nfev=200)
    refined = np.append(fit.x, 1.0).reshape(3, 3)
    return refined if np.isfinite(refined).all() else h


def _compiled_or_none(h: np.ndarray, solved: bool) -> np.ndarray | None:
    return h if solved else None


def ransac_four_point(
    src: np.ndarray,
    dst: np.ndarray,
    threshold: float,
    *,
    refit: Callable[[np.ndarray], np.ndarray | None] | None = None,
    confidence: float = 0.99,
    max_iterations: int = 10_000,
    seed: int = 0,
) -> RansacResult:
    """:func:`~graphvision_plugins.fitting.ransac` with :func:`estimate_homography` on
    4-point samples scored by :func:`transfer_error` (refit by ``refit``, or by
    :func:`estimate_homography`'s DLT on the inliers, compiled): the same samples (seed
    for seed) and the same model (to rounding), its loop over samples compiled
    (:mod:`._kernels`)."""
    from ._kernels import dlt, ransac_homography  # numba compiles (or loads its cache) on first use

    src = np.ascontiguousarray(src, dtype=np.float64)
    dst = np.ascontiguousarray(dst, dtype=np.float64)
    if len(src) < 4:
        return RansacResult(None, np.zeros(len(src), dtype=bool), 0)
    rng = np.random.default_rng(seed)
    model, inliers, drawn, any_model = ransac_homography(
        src, dst, float(threshold), float(confidence), int(max_iterations), rng
    )
    if not any_model:
        return RansacResult(None, inliers, drawn)
    if inliers.sum() >= 4:
        model, inliers = _refit_to_convergence(
            model,
            inliers,
            refit or (lambda i: _compiled_or_none(*dlt(src[i], dst[i]))),
            lambda h: transfer_error(h, src, dst),
            threshold,
            4,
            10,
        )
    return RansacResult(model, inliers, drawn)


class HomographyFit(NamedTuple):
    homography: Homography
    inliers: Matches
    inlier_ratio: Float
    log_nfa: Float


@node(
    "geometry.homography_ransac",
    version=2,
    conformance=Conformance(
        "corner_error",
        0.5,
        radius=256.0,
        note=(
            "OpenCV thresholds the forward error and always refines the inliers' fit "
            "(refine is the reference's alone); method: magsac (OpenCV's USAC_MAGSAC) has "
            "no reference implementation and is compared with the reference's RANSAC"
        ),
    ),
)
def homography_ransac(
    src: Keypoints,
    dst: Keypoints,
    matches: Matches,
    *,
    threshold: Positive = 3.0,
    confidence: Probability = 0.995,
    max_iterations: Iterations = 5000,
    refine: bool = True,
    max_nfa: Annotated[float | None, Field(gt=0)] = 1.0,
    seed: Seed = 0,
    method: Literal["ransac", "magsac"] = "ransac",
) -> HomographyFit:
    r"""The homography mapping ``src`` keypoints onto their matches in ``dst``, robust to
    outliers, refused when chance explains its inliers.

    RANSAC (:func:`~graphvision_plugins.fitting.ransac`) over minimal samples
    of 4 matches solved by normalised DLT, inliers within ``threshold`` pixels
    of forward reprojection error, adaptive sample count for ``confidence``;
    then DLT on all inliers and, with ``refine``, Levenberg-Marquardt on their
    reprojection error.

    Significance (a-contrario): with α the probability that a match of two
    independent points, uniform over each image's keypoint bounding box, is
    within ``threshold`` of the model (about :math:`\pi t^2` over the area),
    k inlier matches among n have

    .. math::

        \mathrm{NFA} = (n - 4)\binom{n}{4}\, P\bigl(B(n - 4, \alpha) \ge k - 4\bigr)

    false alarms: how many models this well supported RANSAC would find among
    random matches. Above ``max_nfa`` the model is refused.

    Parameters
    ----------
    src, dst : Keypoints
        Keypoints of the first and of the second image.
    matches : Matches
        Pairs (index in ``src``, index in ``dst``).
    threshold : float
        Inlier threshold on the symmetric transfer error, in pixels.
    confidence : float
        Probability of drawing at least one outlier-free sample; sets the
        number of iterations adaptively.
    max_iterations : int
        Upper bound on the iterations.
    refine : bool
        Refine the inliers' fit by minimising the geometric error.
    max_nfa : float
        Largest number of false alarms accepted (1: the a-contrario convention;
        None accepts every model).
    seed : int
        Seed of the sample draws (and of the draws that measure α).
    method : {"ransac", "magsac"}
        ``ransac``: the consensus above. ``magsac``: MAGSAC++ (inliers scored by a
        likelihood marginalised over the noise σ up to ``threshold``, then iteratively
        reweighted least squares), implemented by the ``opencv`` backend alone
        (``cv2.USAC_MAGSAC``); the reference refuses it at validation, naming that
        backend.

    Returns
    -------
    homography : (3, 3) float64, ``dst ~ H src``
    inliers : the inlier matches
    inlier_ratio : float
    log_nfa : float, log10 of the model's number of false alarms

    Raises
    ------
    ValueError
        With fewer than 4 matches, when every sample is degenerate (for
        example all points collinear): no homography is defined; or when
        chance explains the best model (NFA above ``max_nfa``).

    References
    ----------
    .. [1] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., 2004, §4.7.
    .. [2] L. Moisan, P. Moulon, P. Monasse, "Automatic homographic registration of a
       pair of images, with a contrario elimination of outliers", IPOL 2, 2012.
    .. [3] D. Barath, J. Noskova, M. Ivashechkin, J. Matas, "MAGSAC++, a fast, reliable
       and accurate robust estimator", CVPR 2020.
    """
    check_reference_method(method)
    if len(matches) < 4:
        raise ValueError(f"need at least 4 matches to estimate a homography, got {len(matches)}")
    a = src.xy[matches.pairs[:, 0]]
    b = dst.xy[matches.pairs[:, 1]]

    def refit(indices: np.ndarray) -> np.ndarray | None:
        h = estimate_homography(a[indices], b[indices])
        return refine_homography(h, a[indices], b[indices]) if h is not None and refine else h

    result = ransac_four_point(
        a,
        b,
        threshold,
        refit=refit,
        confidence=confidence,
        max_iterations=max_iterations,
        seed=seed,
    )
    if result.model is None:
        raise ValueError(
            f"no homography: all {result.iterations} samples of 4 matches were "
            "degenerate (collinear or coincident points)"
        )
    data = np.hstack([a, b])
    result.require_support(4, threshold, "the homography", exact=True, data=data)
    model = result.model
    support, count = result.support(data)
    log_nfa, alpha = model_significance(
        lambda pa, pb: transfer_error(model, pa, pb) < threshold,
        (a, b),
        count,
        4,
        support,
        max_nfa=max_nfa,
        seed=seed,
    )
    refuse_chance(log_nfa, max_nfa, "the homography", support, count, alpha)
    inliers = result.inliers
    return HomographyFit(model, matches.take(inliers), float(inliers.mean()), log_nfa)


@node("geometry.corner_error", version=2)
def corner_error(
    estimated: Homography,
    truth: Homography,
    image: FloatImage | None = None,
    *,
    width: ImageSide | None = None,
    height: ImageSide | None = None,
) -> Float:
    """Mean distance in pixels between the image corners mapped by ``estimated`` and by ``truth``.

    The corners are (0, 0), (w-1, 0), (w-1, h-1), (0, h-1) of the image the
    homographies map *from*: the usual accuracy measure of a homography
    estimate (success when below 3 px). The size is the real one: connect
    that image to ``image`` (its shape gives w and h), or give ``width`` and
    ``height`` when no image is at hand; there is no default size, since a
    wrong one silently scales the error.

    Parameters
    ----------
    estimated, truth : Homography
        The estimate and the true homography.
    image : FloatImage, optional
        The image whose corners are mapped; its ``H×W`` is the size.
    width, height : int, optional
        The size in pixels, when ``image`` is not connected.

    Returns
    -------
    error : float, pixels (inf when a corner maps to infinity)

    Raises
    ------
    ValueError
        When neither the image nor both width and height are given, or when
        both are given and disagree.
    """
    width, height = _mapped_size(image, width, height)
    corners = np.array([[0, 0], [width - 1, 0], [width - 1, height - 1], [0, height - 1]], float)
    error = np.linalg.norm(
        apply_homography(estimated, corners) - apply_homography(truth, corners), axis=1
    )
    return float(error.mean()) if np.isfinite(error).all() else float("inf")


def _mapped_size(
    image: np.ndarray | None, width: int | None, height: int | None
) -> tuple[int, int]:
    """(width, height) from the image, from the parameters, or a ValueError saying what to give."""
    given = None if width is None and height is None else (width, height)
    if image is None:
        if given is None or None in given:
            raise ValueError(
                "corner error needs the size of the image the homographies map from: "
                "connect it to input 'image', or set both 'width' and 'height'"
            )
        return int(width), int(height)  # type: ignore[arg-type]  # both checked above
    shape = (int(image.shape[1]), int(image.shape[0]))
    if given is not None and given != shape:
        raise ValueError(
            f"width×height {width}×{height} disagrees with the connected image "
            f"({shape[0]}×{shape[1]}); give one or the other"
        )
    return shape
