"""OpenCV implementations of camera and two-view ops: undistortion and the fundamental
matrix."""

from __future__ import annotations

import numpy as np

from graphvision import PinholeCamera, implements

from .convert import EXTRA, REQUIRES, board_from_cv, cv, points_to_cv, significance, to_u8

__all__ = [
    "cv_board_corners",
    "cv_calibrate_board",
    "cv_essential_from_points",
    "cv_fundamental",
    "cv_relative_pose",
    "cv_triangulate",
    "cv_undistort_image",
]


@implements("camera.undistort_image", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_undistort_image(image: np.ndarray, camera: PinholeCamera) -> np.ndarray:
    """``cv2.initUndistortRectifyMap(K, d, None, K)`` and ``cv2.remap`` (bilinear, black
    outside). OpenCV's bilinear weights are fixed-point (1/32 pixel), the reference's
    exact: a difference of at most the image's gradient over 64."""
    from ..camera._model import check_intrinsics

    cv2 = cv()
    check_intrinsics(camera)
    rows, cols = image.shape[:2]
    K = np.asarray(camera.K, dtype=np.float64)
    dist = np.asarray(camera.distortion, dtype=np.float64)
    map_x, map_y = cv2.initUndistortRectifyMap(K, dist, None, K, (cols, rows), cv2.CV_32FC1)
    out = cv2.remap(
        np.ascontiguousarray(image, dtype=np.float32),
        map_x,
        map_y,
        cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=0.0,
    )
    return np.clip(out, 0.0, 1.0)


@implements(
    "epipolar.fundamental",
    backend="opencv",
    requires=REQUIRES,
    extra=EXTRA,
    exclusive={"method": ("magsac",)},
)
def cv_fundamental(
    a: np.ndarray,
    b: np.ndarray,
    *,
    threshold: float = 1.0,
    confidence: float = 0.999,
    max_iterations: int = 2000,
    max_nfa: float | None = 1.0,
    seed: int = 0,
    method: str = "ransac",
) -> tuple[np.ndarray, int, float, np.ndarray, np.ndarray, float]:
    """``cv2.findFundamentalMat(FM_RANSAC)``, OpenCV's generator seeded with ``seed``
    (``method: magsac``: ``USAC_MAGSAC``, MAGSAC++, its own generator), scaled to unit
    Frobenius norm. OpenCV thresholds the distance to the epipolar line
    and refits on the inliers without the reference's Levenberg-Marquardt step. The
    significance (``log_nfa``, ``max_nfa``) is the reference's test on OpenCV's inliers."""
    from ..epipolar._fundamental import FundamentalFit
    from ..epipolar._geometry import sampson_distance

    cv2 = cv()
    if len(a) != len(b):
        raise ValueError(f"the fundamental matrix: {len(a)} points in view a but {len(b)} in b")
    if len(a) < 8:
        raise ValueError(f"the fundamental matrix needs at least 8 correspondences, got {len(a)}")
    cv2.setRNGSeed(seed)
    flag = cv2.USAC_MAGSAC if method == "magsac" else cv2.FM_RANSAC
    F, mask = cv2.findFundamentalMat(
        points_to_cv(a), points_to_cv(b), flag, threshold, confidence, max_iterations
    )
    if F is None or F.shape != (3, 3):
        raise ValueError("no fundamental matrix: OpenCV found no consensus of 8 or more pairs")
    F = F / np.linalg.norm(F)
    inliers = mask.ravel().astype(bool)
    rms = float(np.sqrt(np.mean(sampson_distance(F, a[inliers], b[inliers]) ** 2)))

    def fits(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return sampson_distance(F, x, y) < threshold

    what = "the fundamental matrix"
    log_nfa = significance(inliers, a, b, fits, 8, max_nfa, what, seed)
    return FundamentalFit(F, int(inliers.sum()), rms, a[inliers], b[inliers], log_nfa)


@implements("epipolar.triangulate", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_triangulate(
    a: np.ndarray,
    b: np.ndarray,
    camera_a: PinholeCamera,
    camera_b: PinholeCamera,
    *,
    method: str = "nonlinear",
) -> np.ndarray:
    """``cv2.triangulatePoints`` (the linear DLT); ``nonlinear`` then refines the points
    by the reference's Levenberg-Marquardt, which OpenCV has no counterpart of."""
    from ..epipolar._geometry import triangulate_nonlinear

    cv2 = cv()
    if len(a) != len(b):
        raise ValueError(f"triangulation: {len(a)} points in view a but {len(b)} in view b")
    if len(a) < 1:
        raise ValueError("triangulation needs at least 1 correspondences, got 0")
    if np.linalg.norm(camera_a.C - camera_b.C) < 1e-12:
        raise ValueError(
            "the two cameras have the same centre: a zero baseline triangulates nothing"
        )
    homogeneous = cv2.triangulatePoints(
        camera_a.P.astype(np.float64), camera_b.P.astype(np.float64),
        a.T.astype(np.float64), b.T.astype(np.float64),
    )  # fmt: skip
    with np.errstate(divide="ignore", invalid="ignore"):
        points = (homogeneous[:3] / homogeneous[3]).T
    if not np.isfinite(points).all():
        bad = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
        raise ValueError(
            f"correspondence {bad} triangulates to a point at infinity (parallel rays: "
            "a zero baseline or a mismatch)"
        )
    if method == "nonlinear":
        points = triangulate_nonlinear(camera_a.P, camera_b.P, a, b, points)
    return points


@implements("epipolar.relative_pose", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_relative_pose(
    E: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    camera_a: PinholeCamera,
    camera_b: PinholeCamera,
    *,
    inlier_threshold: float = 1.5,
) -> tuple[PinholeCamera, PinholeCamera]:
    """``cv2.recoverPose`` (cheirality of the four decompositions) on the points
    normalised by each camera's K (OpenCV's takes one K); OpenCV does not refine the
    pose, which the reference does on the pairs within ``inlier_threshold`` pixels."""
    from ..epipolar._nodes import RelativePose

    cv2 = cv()
    if len(a) != len(b) or len(a) < 5:
        raise ValueError(f"the relative pose needs at least 5 pairs, got {len(a)} and {len(b)}")
    na = cv2.undistortPoints(points_to_cv(a).astype(np.float64), camera_a.K, None)
    nb = cv2.undistortPoints(points_to_cv(b).astype(np.float64), camera_b.K, None)
    front, R, t, _ = cv2.recoverPose(np.asarray(E, dtype=np.float64), na, nb, np.eye(3))
    if front == 0:
        raise ValueError("no pose puts the points in front of both cameras (E is wrong for them)")
    t = t.ravel() / np.linalg.norm(t)
    reference = PinholeCamera(camera_a.K.copy(), size=camera_a.size.copy())
    moved = PinholeCamera(camera_b.K.copy(), R, -R.T @ t, size=camera_b.size.copy())
    return RelativePose(reference, moved)


def _cv_board(image: np.ndarray, columns: int, rows: int, max_window: int) -> np.ndarray:
    """One view's corners in graphvision's order, NaN when OpenCV finds no board."""
    cv2 = cv()
    u8 = to_u8(image)
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, points = cv2.findChessboardCorners(u8, (columns, rows), flags=flags)
    if not found:
        return np.full((rows * columns, 2), np.nan)
    xy = points.reshape(-1, 2).astype(np.float64)
    spacing = np.linalg.norm(xy[:, None] - xy[None], axis=2) + np.eye(len(xy)) * 1e9
    half = int(np.clip(0.45 * spacing.min(), 3, max_window))
    stop = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-3)
    refined = cv2.cornerSubPix(u8, points, (half, half), (-1, -1), stop)
    return board_from_cv(refined, columns, rows, image)


@implements("camera.board_corners", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_board_corners(
    views: np.ndarray,
    *,
    columns: int = 9,
    rows: int = 6,
    sigma: float | None = None,
    max_window: int = 15,
) -> object:
    """``cv2.findChessboardCorners`` (adaptive threshold, normalised 8-bit image) and
    ``cv2.cornerSubPix`` with one half window for the board, 0.45 of the least corner
    spacing (at least 3, at most ``max_window``); the corners put in the reference's
    order (:func:`.convert.board_from_cv`). ``sigma`` is the reference's alone."""
    import warnings

    from ..camera._corners import BoardCorners

    stack = views[None] if views.ndim == 2 else views
    if stack.ndim != 3:
        raise ValueError(f"views must be H×W or N×H×W gray images, got shape {views.shape}")
    corners = np.stack([_cv_board(image, columns, rows, max_window) for image in stack])
    found = np.isfinite(corners).all(axis=(1, 2))
    missing = np.flatnonzero(~found).tolist()
    if missing:
        warnings.warn(
            f"no board of {columns}×{rows} inner corners found in {len(missing)} of "
            f"{len(stack)} views: {missing} (their corners are NaN)",
            stacklevel=2,
        )
    return BoardCorners(corners, found)


@implements(
    "epipolar.essential_from_points",
    backend="opencv",
    requires=REQUIRES,
    extra=EXTRA,
    exclusive={"method": ("magsac",)},
)
def cv_essential_from_points(
    a: np.ndarray,
    b: np.ndarray,
    camera_a: PinholeCamera,
    camera_b: PinholeCamera,
    *,
    threshold: float = 1.0,
    confidence: float = 0.999,
    max_iterations: int = 2000,
    max_nfa: float | None = 1.0,
    seed: int = 0,
    method: str = "ransac",
) -> object:
    """``cv2.findEssentialMat(RANSAC)`` (Nistér's five points) on the points normalised
    by each camera's K, the pixel threshold divided by the mean focal length as the
    reference divides it, OpenCV's generator seeded with ``seed`` (``method: magsac``:
    ``USAC_MAGSAC``, MAGSAC++, its own generator); the first of its solutions, singular
    values forced to (1, 1, 0). The significance is the reference's test on OpenCV's
    inliers."""
    from ..camera import normalise_pixels
    from ..epipolar._checks import _pairs
    from ..epipolar._fundamental import EssentialFit
    from ..epipolar._geometry import essential_from_fundamental, sampson_distance

    cv2 = cv()
    _pairs(a, b, 8, "the essential matrix from points")
    focal = float(np.mean([camera_a.K[0, 0], camera_a.K[1, 1], camera_b.K[0, 0], camera_b.K[1, 1]]))
    na, nb = normalise_pixels(a, camera_a.K), normalise_pixels(b, camera_b.K)
    cv2.setRNGSeed(seed)
    flag = cv2.USAC_MAGSAC if method == "magsac" else cv2.RANSAC
    E, mask = cv2.findEssentialMat(
        na.astype(np.float64), nb.astype(np.float64), np.eye(3), flag,
        confidence, threshold / focal, maxIters=max_iterations,
    )  # fmt: skip
    if E is None or E.shape[0] < 3:
        raise ValueError("no essential matrix: OpenCV found no consensus of 5 or more pairs")
    E = essential_from_fundamental(E[:3], np.eye(3), np.eye(3))
    inliers = mask.ravel().astype(bool)

    def fits(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return sampson_distance(E, x, y) < threshold / focal

    what = "the essential matrix"
    log_nfa = significance(inliers, na, nb, fits, 8, max_nfa, what, seed)
    return EssentialFit(E, int(inliers.sum()), a[inliers], b[inliers], log_nfa)


def _calibration_flags(radial: int, tangential: bool) -> int:
    """OpenCV's flags for ``radial`` coefficients k1.. and optional p1, p2 (zero skew is
    OpenCV's model)."""
    cv2 = cv()
    flags = 0 if tangential else cv2.CALIB_ZERO_TANGENT_DIST
    for k, name in enumerate(("CALIB_FIX_K1", "CALIB_FIX_K2", "CALIB_FIX_K3")):
        if k >= radial:
            flags |= getattr(cv2, name)
    return int(flags)


@implements("camera.calibrate_board", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_calibrate_board(
    corners: np.ndarray,
    object_points: np.ndarray,
    *,
    radial: int = 2,
    tangential: bool = False,
    min_views: int = 3,
) -> object:
    """``cv2.calibrateCamera`` on the views with a board, k1.. beyond ``radial`` fixed at
    0 (and p1, p2 without ``tangential``). OpenCV starts its principal point at the
    centre of the image size it is given: here the centre of the corners' bounding box
    (the op has no image size). The camera is posed as the first usable view."""
    from ..camera._calibrate import BoardCalibration

    cv2 = cv()
    if corners.ndim != 3 or corners.shape[1:] != (len(object_points), 2):
        raise ValueError(
            f"corners must be N×{len(object_points)}×2 (one row per object point), "
            f"got shape {corners.shape}"
        )
    if np.abs(object_points[:, 2]).max() > 1e-9:
        raise ValueError("object_points must lie on the board plane Z = 0")
    usable = np.isfinite(corners).all(axis=(1, 2))
    if usable.sum() < min_views:
        missing = np.flatnonzero(~usable).tolist()
        reason = f"; no board found in views {missing}" if missing else ""
        raise ValueError(
            f"only {int(usable.sum())} of {len(corners)} views have a board, need "
            f"{min_views}{reason}"
        )
    views = np.flatnonzero(usable)
    image_points = [points_to_cv(corners[v]) for v in views]
    board = [np.ascontiguousarray(object_points, dtype=np.float32)] * len(views)
    xy = corners[views].reshape(-1, 2)
    size = (int(np.ceil(xy[:, 0].min() + xy[:, 0].max())) + 1,
            int(np.ceil(xy[:, 1].min() + xy[:, 1].max())) + 1)  # fmt: skip
    stop = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    flags = _calibration_flags(radial, tangential)
    rms, K, dist, rvecs, tvecs = cv2.calibrateCamera(
        board, image_points, size, None, None, flags=flags, criteria=stop
    )
    distortion = np.zeros(5)
    distortion[: min(5, dist.size)] = dist.ravel()[:5]
    R0, _ = cv2.Rodrigues(rvecs[0])
    C0 = -R0.T @ tvecs[0].ravel()
    camera = PinholeCamera(K, R0, C0, distortion, np.zeros(2, np.int64))
    return BoardCalibration(camera, float(rms), views.astype(np.int64))
