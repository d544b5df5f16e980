"""Rectification: two homographies that make epipolar lines horizontal and aligned (notes:
"Stereo image rectification": reproject both image planes onto a common plane parallel to
the baseline)."""

from __future__ import annotations

from typing import Generic, NamedTuple

import numpy as np

from graphvision import (
    Camera,
    Conformance,
    Float,
    Homography,
    Image,
    ImageT,
    PinholeCamera,
    Points2D,
    node,
)

from ..camera._projection import cross_matrix
from ..epipolar._ports import Fundamental
from ..geometry import apply_homography, sample_homography

__all__ = [
    "Rectification",
    "RectifiedPair",
    "hartley_homographies",
    "rectification_dy",
    "rectify_calibrated",
    "rectify_pair",
    "rectify_uncalibrated",
]


class Rectification(NamedTuple):
    H_a: Homography
    H_b: Homography
    camera_a: Camera
    camera_b: Camera
    baseline: Float


class UncalibratedRectification(NamedTuple):
    H_a: Homography
    H_b: Homography


class RectifiedPair(NamedTuple, Generic[ImageT]):
    left: ImageT
    right: ImageT


def _recentre(H_a: np.ndarray, H_b: np.ndarray, width: int, height: int) -> np.ndarray:
    """A translation applied to both homographies so that the left image's centre stays
    at the centre (the same for both, so rows stay aligned and disparities keep their sign)."""
    centre = np.array([[(width - 1) / 2.0, (height - 1) / 2.0]])
    moved = apply_homography(H_a, centre)[0]
    shift = np.eye(3)
    shift[:2, 2] = centre[0] - moved
    return shift


_OPENCV_ROTATION = (
    "OpenCV (cv2.stereoRectify) turns each camera by half the relative rotation, then puts "
    "the baseline on x: its rectified x axis is the baseline too, rows align as exactly "
    "(|dy| of corresponding points below 1e-9 px), but its common orientation differs "
    "from Fusiello's (z: the left camera's axis made perpendicular to the baseline) by a "
    "rotation about the baseline of about half the angle between the two optical axes "
    "about it (never more than that angle), and its K is its own (alpha=-1), not the mean "
    "K with the left image's centre kept; compared by the rectified cameras' rotation"
)


@node(
    "stereo.rectify_calibrated",
    version=1,
    conformance=Conformance("rotation_error", 3.0, note=_OPENCV_ROTATION),
)
def rectify_calibrated(camera_a: Camera, camera_b: Camera) -> Rectification:
    r"""Rectify a calibrated pair (Fusiello, Trucco & Verri 2000): both cameras turned to a
    common orientation whose x axis is the baseline, with one calibration matrix.

    .. math::

        r_1 = \frac{\tilde C_b - \tilde C_a}{\lVert \tilde C_b - \tilde C_a \rVert},\quad
        r_2 = \frac{z_a \times r_1}{\lVert z_a \times r_1 \rVert},\quad r_3 = r_1 \times r_2,
        \qquad H_i = K_n R_n R_i^T K_i^{-1}

    with :math:`z_a` the left camera's optical axis and :math:`K_n` the mean of
    the two K (skew 0). A shared translation keeps the left image's centre in
    place. The rectified cameras :math:`K_n [R_n \mid -R_n \tilde C_i]` differ
    only by the baseline along x, so a scene point has the same row in both
    and disparity :math:`d = f b / Z`.

    Parameters
    ----------
    camera_a, camera_b : Camera
        The left and right cameras (b to the right of a along the baseline).

    Returns
    -------
    H_a, H_b : Homography
        Map each original image to its rectified image.
    camera_a, camera_b : Camera
        The rectified cameras (no distortion: undistort the images first).
    baseline : float
        :math:`\lVert \tilde C_b - \tilde C_a \rVert`, in the cameras' unit.

    References
    ----------
    .. [1] A. Fusiello, E. Trucco, A. Verri, "A compact algorithm for
       rectification of stereo pairs", Machine Vision and Applications 12, 2000.
    """
    baseline_vector = camera_b.C - camera_a.C
    baseline = float(np.linalg.norm(baseline_vector))
    if baseline < 1e-12:
        raise ValueError("the two cameras have the same centre: a zero baseline has no stereo")
    r1 = baseline_vector / baseline
    r2 = np.cross(camera_a.R[2], r1)
    if np.linalg.norm(r2) < 1e-9:
        raise ValueError(
            "the baseline lies along the left camera's optical axis (forward motion): "
            "the epipoles are inside the image and the pair cannot be rectified by homographies"
        )
    r2 /= np.linalg.norm(r2)
    rotation = np.vstack([r1, r2, np.cross(r1, r2)])
    K = (camera_a.K + camera_b.K) / 2.0
    K[0, 1] = 0.0
    H_a = K @ rotation @ camera_a.R.T @ np.linalg.inv(camera_a.K)
    H_b = K @ rotation @ camera_b.R.T @ np.linalg.inv(camera_b.K)
    width, height = (int(v) for v in camera_a.size) if camera_a.size.all() else (0, 0)
    shift = _recentre(H_a, H_b, width, height) if width else np.eye(3)
    K_new = shift @ K
    cameras = [
        PinholeCamera(K_new.copy(), rotation.copy(), cam.C.copy(), size=cam.size.copy())
        for cam in (camera_a, camera_b)
    ]
    return Rectification(shift @ H_a, shift @ H_b, cameras[0], cameras[1], baseline)


def hartley_homographies(
    F: np.ndarray, a: np.ndarray, b: np.ndarray, width: int, height: int
) -> tuple[np.ndarray, np.ndarray]:
    """Hartley's rectifying pair (H_a, H_b) from F (``x_bᵀ F x_a = 0``) and matches."""
    _, _, vt = np.linalg.svd(F.T)
    epipole = vt[-1]  # in image b: Fᵀ e_b = 0
    to_origin = np.array([[1.0, 0, -(width - 1) / 2], [0, 1.0, -(height - 1) / 2], [0, 0, 1.0]])
    e = to_origin @ epipole
    angle = -np.arctan2(e[1], e[0])
    if abs(angle) > np.pi / 2:  # turn the epipole onto the nearer half of the x axis
        angle -= np.pi * np.sign(angle)
    turn = np.array(
        [[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0, 0, 1.0]]
    )
    e = turn @ e
    to_infinity = np.eye(3)
    to_infinity[2, 0] = -e[2] / e[0]
    H_b = to_infinity @ turn @ to_origin
    unit = epipole / np.linalg.norm(epipole)
    M = cross_matrix(unit) @ F + np.outer(unit, np.ones(3))
    H_0 = H_b @ M
    mapped_a = apply_homography(H_0, a)
    mapped_b = apply_homography(H_b, b)
    design = np.column_stack([mapped_a, np.ones(len(a))])
    coefficients, *_ = np.linalg.lstsq(design, mapped_b[:, 0], rcond=None)
    affine = np.eye(3)
    affine[0] = coefficients
    return affine @ H_0, H_b


@node("stereo.rectify_uncalibrated", version=1)
def rectify_uncalibrated(
    F: Fundamental, a: Points2D, b: Points2D, image: Image
) -> UncalibratedRectification:
    r"""Rectify an uncalibrated pair from F and its matches (Hartley 1999).

    1. :math:`H_b = G R T` sends the right epipole :math:`e_b` (:math:`F^T e_b
       = 0`) to infinity along x: T moves the image centre to the origin, R
       turns :math:`e_b` onto the x axis, :math:`G` (identity but
       :math:`g_{31} = -1/f`) maps :math:`(f, 0, 1)` to :math:`(f, 0, 0)`.
    2. With :math:`F = [e_b]_\times M`, :math:`M = [e_b]_\times F + e_b v^T`,
       :math:`H_0 = H_b M` also sends the left epipole to infinity, and rows
       agree.
    3. :math:`H_a = H_A H_0` with :math:`H_A` the affine map of x (rows kept)
       minimising :math:`\sum_i (H_a x_{a,i} - H_b x_{b,i})_x^2`: the least
       horizontal distortion.

    A shared translation then keeps the left image's centre in place.

    Parameters
    ----------
    F : Fundamental
        The fundamental matrix, :math:`x_b^T F x_a = 0`.
    a, b : Points2D
        Matches (inliers of F), at least 8.
    image : Image
        The left image (gives the size).

    Returns
    -------
    H_a, H_b : Homography
        Rectifying homographies of the left and right images.

    References
    ----------
    .. [1] R. Hartley, "Theory and practice of projective rectification", IJCV 35, 1999.
    .. [2] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., §11.12.
    """
    if len(a) != len(b) or len(a) < 8:
        raise ValueError(f"rectification needs at least 8 matched pairs, got {len(a)} and {len(b)}")
    height, width = image.shape[:2]
    H_a, H_b = hartley_homographies(F, a, b, width, height)
    shift = _recentre(H_a, H_b, width, height)
    return UncalibratedRectification(shift @ H_a, shift @ H_b)


@node(
    "stereo.rectify_pair",
    version=1,
    conformance=Conformance(
        "max_abs", 1e-4, note="OpenCV's remap reads a float32 map (source positions to ~1e-5 px)"
    ),
)
def rectify_pair(
    left: ImageT, right: ImageT, H_a: Homography, H_b: Homography
) -> RectifiedPair[ImageT]:
    """Warp both images by their rectifying homographies (bilinear; pixels from outside black).

    Parameters
    ----------
    left, right : Image
        The original pair.
    H_a, H_b : Homography
        From :func:`rectify_calibrated` or :func:`rectify_uncalibrated`.

    Returns
    -------
    left, right : Image
        The rectified pair, each the size of its original (gray stays gray).
    """
    warped = [
        sample_homography(image, np.linalg.inv(H), image.shape[:2])[0]
        for image, H in ((left, H_a), (right, H_b))
    ]
    return RectifiedPair(warped[0], warped[1])


@node("stereo.rectification_dy", version=1)
def rectification_dy(a: Points2D, b: Points2D, H_a: Homography, H_b: Homography) -> Float:
    r"""Mean vertical distance of matches after rectification (0 for a perfect one).

    :math:`\frac{1}{N} \sum_i |(H_a x_{a,i})_y - (H_b x_{b,i})_y|`.

    Parameters
    ----------
    a, b : Points2D
        Matches in the original images.
    H_a, H_b : Homography
        The rectifying homographies.
    """
    if len(a) != len(b) or len(a) == 0:
        raise ValueError(f"expected matched, non-empty point sets, got {len(a)} and {len(b)}")
    dy = apply_homography(H_a, a)[:, 1] - apply_homography(H_b, b)[:, 1]
    return float(np.mean(np.abs(dy)))
