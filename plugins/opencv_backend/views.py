"""OpenCV implementations of camera and two-view ops: undistortion and the fundamental
matrix."""

from __future__ import annotations

import numpy as np

from graphvision import PinholeCamera, implements

from .convert import EXTRA, REQUIRES, cv, points_to_cv, significance

__all__ = ["cv_fundamental", "cv_relative_pose", "cv_triangulate", "cv_undistort_image"]


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


@implements("epipolar.fundamental", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_fundamental(
    a: np.ndarray,
    b: np.ndarray,
    *,
    threshold: float = 1.0,
    confidence: float = 0.999,
    max_iterations: int = 2000,
    max_nfa: float | None = 1.0,
    seed: int = 0,
) -> tuple[np.ndarray, int, float, np.ndarray, np.ndarray, float]:
    """``cv2.findFundamentalMat(FM_RANSAC)``, OpenCV's generator seeded with ``seed``,
    scaled to unit Frobenius norm. OpenCV thresholds the distance to the epipolar line
    and refits on the inliers without the reference's Levenberg-Marquardt step. The
    significance (``log_nfa``, ``max_nfa``) is the reference's test on OpenCV's inliers."""
    from ..epipolar._geometry import sampson_distance
    from ..epipolar._nodes import FundamentalFit

    cv2 = cv()
    if len(a) != len(b):
        raise ValueError(f"the fundamental matrix: {len(a)} points in view a but {len(b)} in b")
    if len(a) < 8:
        raise ValueError(f"the fundamental matrix needs at least 8 correspondences, got {len(a)}")
    cv2.setRNGSeed(seed)
    F, mask = cv2.findFundamentalMat(
        points_to_cv(a), points_to_cv(b), cv2.FM_RANSAC, threshold, confidence, max_iterations
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
