"""OpenCV implementations of calibrated stereo rectification (``cv2.stereoRectify``) and
of warping a pair by its rectifying homographies (``cv2.initUndistortRectifyMap`` and
``cv2.remap``)."""

from __future__ import annotations

import numpy as np

from graphvision import Camera, Homography, PinholeCamera, implements

from .convert import EXTRA, REQUIRES, cv

__all__ = ["cv_rectify_calibrated", "cv_rectify_pair"]


@implements("stereo.rectify_calibrated", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_rectify_calibrated(camera_a: Camera, camera_b: Camera) -> object:
    """``cv2.stereoRectify`` (``CALIB_ZERO_DISPARITY``, ``alpha=-1``) of the pair's
    relative pose ``R = R_b R_aᵀ``, ``T = R_b (C_a − C_b)``, no distortion (the
    reference's convention: undistort first). ``H_i = P_i[:, :3] R_i K_i⁻¹``; the
    rectified cameras are ``P_i[:, :3] [R_i R_{world→i} | …]`` at the original centres.

    OpenCV first turns each camera by half the relative rotation, then both by the
    smallest rotation that puts the baseline on x, so its common orientation differs
    from Fusiello's (whose z is the left camera's axis made perpendicular to the
    baseline) by a rotation about the baseline; its focal length and principal point
    are its own (``alpha=-1``), not the mean K and the kept centre."""
    from ..stereo._rectify import Rectification

    cv2 = cv()
    baseline = float(np.linalg.norm(camera_b.C - camera_a.C))
    if baseline < 1e-12:
        raise ValueError("the two cameras have the same centre: a zero baseline has no stereo")
    if np.linalg.norm(np.cross(camera_a.R[2], (camera_b.C - camera_a.C) / baseline)) < 1e-9:
        raise ValueError(
            "the baseline lies along the left camera's optical axis (forward motion): "
            "the epipoles are inside the image and the pair cannot be rectified by homographies"
        )
    relative = camera_b.R @ camera_a.R.T
    shift = camera_b.R @ (camera_a.C - camera_b.C)
    size = camera_a.size if camera_a.size.all() else np.rint(2 * camera_a.K[:2, 2] + 1)
    width, height = (int(v) for v in size)
    zero = np.zeros(5)
    R1, R2, P1, P2, *_ = cv2.stereoRectify(
        camera_a.K.astype(np.float64), zero, camera_b.K.astype(np.float64), zero,
        (width, height), relative, shift.reshape(3, 1), flags=cv2.CALIB_ZERO_DISPARITY, alpha=-1,
    )  # fmt: skip
    K = P1[:, :3].copy()
    H_a = K @ R1 @ np.linalg.inv(camera_a.K)
    H_b = P2[:, :3] @ R2 @ np.linalg.inv(camera_b.K)
    rotation = R1 @ camera_a.R  # the common world-to-rectified rotation (R2 R_b is equal)
    cameras = [
        PinholeCamera(K.copy(), rotation.copy(), cam.C.copy(), size=cam.size.copy())
        for cam in (camera_a, camera_b)
    ]
    return Rectification(H_a, H_b, cameras[0], cameras[1], baseline)


@implements("stereo.rectify_pair", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_rectify_pair(
    left: np.ndarray, right: np.ndarray, H_a: Homography, H_b: Homography
) -> object:
    """``cv2.initUndistortRectifyMap(I, no distortion, H, I)`` (the map of the
    homography ``H``) then ``cv2.remap`` (bilinear, black outside), each image kept at
    its own size. Pixels whose source lies outside the image's pixel area
    (``[-0.5, W - 0.5] × [-0.5, H - 0.5]``) are black, as the reference's; the map is
    float32 (source positions to about 1e-5 px)."""
    from ..stereo._rectify import RectifiedPair

    cv2 = cv()
    warped = []
    for image, H in ((left, H_a), (right, H_b)):
        rows, cols = image.shape[:2]
        identity = np.eye(3)
        map_x, map_y = cv2.initUndistortRectifyMap(
            identity, None, np.asarray(H, np.float64), identity, (cols, rows), cv2.CV_32FC1
        )
        data = np.ascontiguousarray(image, dtype=np.float32)
        out = cv2.remap(data, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        inside = (map_x >= -0.5) & (map_x <= cols - 0.5) & (map_y >= -0.5) & (map_y <= rows - 0.5)
        out[~(inside & np.isfinite(map_x) & np.isfinite(map_y))] = 0.0
        warped.append(np.clip(out, 0.0, 1.0).astype(np.float32))
    return RectifiedPair(warped[0], warped[1])
