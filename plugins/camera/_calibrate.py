r"""Calibration: normalised DLT from 3-D–2-D correspondences, and Zhang's planar method.

**DLT.** Each correspondence :math:`X_i \leftrightarrow x_i = (x, y, w)` gives two
rows of :math:`A p = 0` (p the 12 entries of P, row by row):

.. math::

    \begin{pmatrix} 0^T & -w X_i^T & y X_i^T \\ w X_i^T & 0^T & -x X_i^T \end{pmatrix} p = 0,

solved by SVD after Hartley's normalisation of both point sets, then refined
by minimising the reprojection error over K (5), R (3) and C̃ (3).

**Zhang.** A view of the plane Z = 0 is a homography :math:`H = \lambda K [r_1\, r_2\, t]`;
:math:`r_1 \perp r_2` and :math:`|r_1| = |r_2|` give two linear constraints on
:math:`B = K^{-T} K^{-1}`: :math:`h_1^T B h_2 = 0`, :math:`h_1^T B h_1 = h_2^T B h_2`.
B from ≥ 3 views (SVD), K from B in closed form, each view's R, t from
:math:`K^{-1} H`; then all parameters with radial distortion refined jointly.

References
----------
.. [1] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., 2004, §7.1 (algorithm 7.1).
.. [2] Z. Zhang, "A flexible new technique for camera calibration", IEEE TPAMI 22(11), 2000.
"""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import (
    Array,
    Camera,
    Conformance,
    Float,
    GraphvisionError,
    PinholeCamera,
    Points2D,
    Points3D,
    node,
)

from ..geometry import estimate_homography, normalising_transform
from ._projection import (
    decompose_projection,
    project_points,
    rotation_from_vector,
    vector_from_rotation,
)
from ._zhang import _pose_from_homography, _project_views, _usable_views, zhang_intrinsics

__all__ = [
    "CalibrationError",
    "calibrate_board",
    "calibrate_dlt",
    "dlt_projection",
    "focal_error",
]


class CalibrationError(GraphvisionError, ValueError):
    """The correspondences give no usable camera; the message names the cause (points
    behind the estimated camera, a system without a unique solution, a singular M)."""


def _normalising_transform_3d(points: np.ndarray) -> np.ndarray:
    centre = points.mean(axis=0)
    spread = np.sqrt(((points - centre) ** 2).sum(axis=1).mean())
    scale = np.sqrt(3.0) / spread
    U = np.diag([scale, scale, scale, 1.0])
    U[:3, 3] = -scale * centre
    return U


def check_non_coplanar(points: np.ndarray) -> None:
    """Raise ValueError when the 3-D points lie on a plane (or a line)."""
    centred = points - points.mean(axis=0)
    singular = np.linalg.svd(centred, compute_uv=False)
    if singular[2] <= 1e-6 * singular[0]:
        raise ValueError(
            "the 3-D points are coplanar: a plane only fixes the homography of that plane, "
            "P stays undetermined (a 3-parameter family fits exactly); use points in at least "
            "two planes, or planar calibration (camera.calibrate_board)"
        )


def dlt_projection(world: np.ndarray, image: np.ndarray) -> np.ndarray:
    """Normalised DLT (module docstring): P with :math:`\\|P\\|_F = 1` from ≥ 6 correspondences.

    Raises CalibrationError when the system's null space has more than one dimension
    (the smallest two singular values within 1e-10 of each other, relative to the
    largest): the correspondences then fit a family of cameras, not one.
    """
    T = normalising_transform(image)
    U = _normalising_transform_3d(world)
    X = np.column_stack([world, np.ones(len(world))]) @ U.T
    x = image @ T[:2, :2].T + T[:2, 2]
    rows = np.zeros((2 * len(X), 12))
    rows[0::2, 4:8] = -X
    rows[0::2, 8:] = x[:, 1:2] * X
    rows[1::2, 0:4] = X
    rows[1::2, 8:] = -x[:, 0:1] * X
    _, singular, vt = np.linalg.svd(rows, full_matrices=rows.shape[0] < rows.shape[1])
    if len(singular) == 12 and singular[-2] <= 1e-10 * singular[0]:
        raise CalibrationError(
            "the correspondences do not determine P: the DLT system has more than one "
            "solution (a degenerate configuration: points on a plane and on a line through "
            "the camera centre, or on a twisted cubic through it); add points in general "
            "position"
        )
    P = np.linalg.inv(T) @ vt[-1].reshape(3, 4) @ U
    return P / np.linalg.norm(P)


def _check_camera(
    world: np.ndarray, K: np.ndarray, R: np.ndarray, C: np.ndarray, stage: str
) -> None:
    """CalibrationError naming ``stage`` when K, R, C̃ are not finite or when a point lies
    behind the camera (depth :math:`r_3 \\cdot (X - \\tilde C) \\le 0`, where it has no image)."""
    if not (np.isfinite(K).all() and np.isfinite(R).all() and np.isfinite(C).all()):
        raise CalibrationError(f"the {stage} camera is not finite (K, R or C has inf or NaN)")
    depth = (world - C) @ R[2]
    behind = depth <= 0
    if behind.any():
        first = np.flatnonzero(behind)[:5].tolist()
        raise CalibrationError(
            f"{int(behind.sum())} of {len(world)} points lie behind the {stage} camera "
            f"(points {first}): a camera that sees every point does not fit these "
            "correspondences, too few or too noisy to determine its 11 parameters; use more "
            "points, spread over more depth, or check the correspondences"
        )


class DltCalibration(NamedTuple):
    camera: Camera
    reprojection_rms: Float


def _rms(residual: np.ndarray) -> float:
    return float(np.sqrt((residual.reshape(-1, 2) ** 2).sum(axis=1).mean()))


@node("camera.calibrate_dlt", version=1)
def calibrate_dlt(
    world: Points3D,
    image: Points2D,
    *,
    refine: bool = True,
) -> DltCalibration:
    """Camera (K, R, C̃) from ≥ 6 non-coplanar 3-D points and their images (module docstring).

    Normalised DLT, RQ decomposition, then (with ``refine``) Levenberg-Marquardt
    on the reprojection error over the 11 parameters (fx, fy, skew, cx, cy,
    rotation vector, centre). Distortion is not modelled (zero).

    Parameters
    ----------
    world : Points3D
        Points of the calibration object, N×3, not all on one plane.
    image : Points2D
        Their measured pixel positions, N×2, in the same order.
    refine : bool
        Minimise the geometric (reprojection) error after the algebraic DLT.

    Returns
    -------
    camera : the calibrated camera
    reprojection_rms : RMS distance between measured and reprojected points, pixels

    Raises
    ------
    ValueError
        With fewer than 6 correspondences, unequal counts, or coplanar points.
    CalibrationError
        (a graphvision error and a ValueError) when the estimate is degenerate,
        naming the cause: points behind the DLT's (or the refined) camera, which
        happens with few noisy points (6 points with 0.5–1 px of noise: about 1
        scene in 70), a DLT system without a unique solution, or a singular M.
    """
    if len(world) != len(image):
        raise ValueError(f"world has {len(world)} points but image has {len(image)}")
    if len(world) < 6:
        raise ValueError(f"the DLT needs at least 6 correspondences, got {len(world)}")
    check_non_coplanar(world)
    from scipy.optimize import least_squares

    try:
        K, R, C = decompose_projection(dlt_projection(world, image))
    except CalibrationError:
        raise
    except ValueError as error:  # M singular: the estimate is a camera at infinity
        raise CalibrationError(f"the DLT estimate is degenerate: {error}") from None
    _check_camera(world, K, R, C, "DLT")
    params = np.concatenate(
        [[K[0, 0], K[1, 1], K[0, 1], K[0, 2], K[1, 2]], vector_from_rotation(R), C]
    )

    def unpack(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        K = np.array([[p[0], p[2], p[3]], [0, p[1], p[4]], [0, 0, 1.0]])
        return K, rotation_from_vector(p[5:8]), p[8:11]

    def residual(p: np.ndarray) -> np.ndarray:
        return (project_points(world, *unpack(p)) - image).ravel()

    if refine:
        # a step that puts a point behind the camera costs 1e6 px there, so the
        # minimiser backs off instead of meeting NaN
        params = least_squares(
            lambda p: np.nan_to_num(residual(p), nan=1e6), params, method="lm", x_scale="jac"
        ).x
        _check_camera(world, *unpack(params), "refined")
    K, R, C = unpack(params)
    return DltCalibration(PinholeCamera(K, R, C), _rms(residual(params)))


class BoardCalibration(NamedTuple):
    camera: Camera
    reprojection_rms: Float
    views_used: Array


@node(
    "camera.calibrate_board",
    version=1,
    conformance=Conformance(
        "max_abs",
        2e-3,
        note=(
            "OpenCV minimises the same reprojection error over the same model (zero skew, "
            "k1.. beyond radial fixed at 0) from its own start, the principal point at the "
            "centre of the corners' bounding box; on 6 views with 0.1 px noise every value "
            "agrees within 2e-3 (K within 2e-4 px) with radial ≤ 2; with k3 free both reach "
            "the same RMS but k3 is poorly determined (0.05 apart; not in the cases)"
        ),
    ),
)
def calibrate_board(
    corners: Array,
    object_points: Points3D,
    *,
    radial: Annotated[int, Field(ge=0, le=3)] = 2,
    tangential: bool = False,
    min_views: Annotated[int, Field(ge=3)] = 3,
) -> BoardCalibration:
    """Zhang's planar calibration from several views of a board (module docstring).

    Per view the board-to-image homography (normalised DLT), K in closed
    form (zero skew), each view's pose; then Levenberg-Marquardt over fx, fy,
    cx, cy, ``radial`` coefficients k1.., optional p1, p2 and every pose,
    on the reprojection error of all corners.

    Parameters
    ----------
    corners : Array
        Detected corners N×M×2 (``camera.board_corners``); a view with NaN
        (board not found) is reported and skipped.
    object_points : Points3D
        The M corners on the board, Z = 0, in the same order.
    radial : int
        Number of radial coefficients estimated (0 to 3: k1, k2, k3).
    tangential : bool
        Also estimate the tangential coefficients p1, p2.
    min_views : int
        Fewest usable views accepted (at least 3).

    Returns
    -------
    camera : K and distortion, posed as the first usable view
    reprojection_rms : RMS reprojection error over all corners, pixels
    views_used : indices of the views used

    Raises
    ------
    ValueError
        When the shapes disagree, the points are not on Z = 0, or fewer than
        ``min_views`` views have a board (naming the views without one).
    """
    views = _usable_views(corners, object_points, min_views)
    from scipy.optimize import least_squares

    image_points = corners[views]
    plane = object_points[:, :2]
    homographies = []
    T = normalising_transform(image_points.reshape(-1, 2))
    for pts in image_points:
        h = estimate_homography(plane, pts)
        if h is None:
            raise ValueError("a view's corners are degenerate (collinear)")
        homographies.append(h)
    K = np.linalg.inv(T) @ zhang_intrinsics([T @ h for h in homographies])
    K /= K[2, 2]
    poses = [_pose_from_homography(K, h) for h in homographies]
    n_dist = radial + (2 if tangential else 0)
    n_views = len(views)

    def unpack(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        K = np.array([[p[0], 0, p[2]], [0, p[1], p[3]], [0, 0, 1.0]])
        dist = np.zeros(5)
        radial_slots = [0, 1, 4][:radial]
        dist[radial_slots] = p[4 : 4 + radial]
        if tangential:
            dist[2:4] = p[4 + radial : 6 + radial]
        return K, dist

    def residual(p: np.ndarray) -> np.ndarray:
        K, dist = unpack(p)
        poses = p[4 + n_dist :].reshape(n_views, 6)
        projected = _project_views(object_points, K, dist, poses[:, :3], poses[:, 3:])
        return np.nan_to_num(projected - image_points, nan=1e6).ravel()

    start = [K[0, 0], K[1, 1], K[0, 2], K[1, 2], *np.zeros(n_dist)]
    for R, t in poses:
        start += [*vector_from_rotation(R), *t]
    fit = least_squares(residual, np.array(start), x_scale="jac", method="lm")
    K, dist = unpack(fit.x)
    R0 = rotation_from_vector(fit.x[4 + n_dist : 7 + n_dist])
    t0 = fit.x[7 + n_dist : 10 + n_dist]
    camera = PinholeCamera(K, R0, -R0.T @ t0, dist, np.zeros(2, np.int64))
    return BoardCalibration(camera, _rms(residual(fit.x)), views.astype(np.int64))


@node("camera.focal_error", version=1)
def focal_error(estimated: Camera, truth: Camera) -> Float:
    """Largest relative error of fx and fy against the truth, in percent.

    Parameters
    ----------
    estimated : Camera
        The calibrated camera.
    truth : Camera
        The camera the data came from.
    """
    f_est = np.array([estimated.K[0, 0], estimated.K[1, 1]])
    f_true = np.array([truth.K[0, 0], truth.K[1, 1]])
    return float(100 * np.abs(f_est / f_true - 1).max())
