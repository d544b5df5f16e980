"""The steps of Zhang's planar calibration (see :mod:`._calibrate`, which holds the node):
K in closed form from the views' homographies, each view's pose from K and its
homography, the projection of the board in every view, and the views that have a board."""

from __future__ import annotations

import numpy as np

from ._projection import distort_normalised

__all__ = [
    "zhang_intrinsics",
]


def _v(h: np.ndarray, i: int, j: int) -> np.ndarray:
    a, b = h[:, i], h[:, j]
    return np.array(
        [a[0] * b[0], a[0] * b[1] + a[1] * b[0], a[1] * b[1],
         a[2] * b[0] + a[0] * b[2], a[2] * b[1] + a[1] * b[2], a[2] * b[2]]
    )  # fmt: skip


def zhang_intrinsics(homographies: list[np.ndarray]) -> np.ndarray:
    """K in closed form from ≥ 3 plane-to-image homographies, zero skew (module docstring)."""
    rows = []
    for h in homographies:
        rows += [_v(h, 0, 1), _v(h, 0, 0) - _v(h, 1, 1)]
    rows.append(np.array([0, 1.0, 0, 0, 0, 0]))  # zero skew: B12 = 0
    _, _, vt = np.linalg.svd(np.array(rows))
    b11, b12, b22, b13, b23, b33 = vt[-1] if vt[-1][0] > 0 else -vt[-1]
    v0 = (b12 * b13 - b11 * b23) / (b11 * b22 - b12**2)
    lam = b33 - (b13**2 + v0 * (b12 * b13 - b11 * b23)) / b11
    if lam / b11 <= 0 or b11 * b22 - b12**2 <= 0:
        raise ValueError("the views do not determine K (B is not positive definite)")
    alpha = np.sqrt(lam / b11)
    beta = np.sqrt(lam * b11 / (b11 * b22 - b12**2))
    gamma = -b12 * alpha**2 * beta / lam
    u0 = gamma * v0 / beta - b13 * alpha**2 / lam
    return np.array([[alpha, gamma, u0], [0, beta, v0], [0, 0, 1.0]])


def _pose_from_homography(K: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R, t of a plane view: :math:`[r_1\\, r_2\\, t] = \\lambda K^{-1} H`, R orthonormalised."""
    m = np.linalg.solve(K, h)
    lam = 1.0 / np.linalg.norm(m[:, 0])
    if m[2, 2] * lam < 0:  # the board must be in front of the camera
        lam = -lam
    r1, r2, t = lam * m[:, 0], lam * m[:, 1], lam * m[:, 2]
    u, _, vt = np.linalg.svd(np.column_stack([r1, r2, np.cross(r1, r2)]))
    R = u @ vt
    if np.linalg.det(R) < 0:
        R = u @ np.diag([1, 1, -1.0]) @ vt
    return R, t


def _rotations(rvecs: np.ndarray) -> np.ndarray:
    """Rodrigues' formula for ``V×3`` axis-angle vectors at once: ``V×3×3``."""
    theta = np.linalg.norm(rvecs, axis=1)
    safe = np.where(theta > 1e-12, theta, 1.0)
    k = rvecs / safe[:, None]
    kx = np.zeros((len(rvecs), 3, 3))
    kx[:, 0, 1], kx[:, 0, 2], kx[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    kx[:, 1, 0], kx[:, 2, 0], kx[:, 2, 1] = k[:, 2], -k[:, 1], k[:, 0]
    sin = np.where(theta > 1e-12, np.sin(theta), theta)[:, None, None]
    cos = np.where(theta > 1e-12, 1 - np.cos(theta), 0.0)[:, None, None]
    return np.eye(3) + sin * kx + cos * kx @ kx


def _project_views(
    points: np.ndarray, K: np.ndarray, dist: np.ndarray, rvecs: np.ndarray, tvecs: np.ndarray
) -> np.ndarray:
    """Project ``N×3`` points into V views (pose R(rvec), t): ``V×N×2`` pixels."""
    cam = np.einsum("vij,nj->vni", _rotations(rvecs), points) + tvecs[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        xy = cam[..., :2] / np.where(cam[..., 2:] > 0, cam[..., 2:], np.nan)
    xy = distort_normalised(xy.reshape(-1, 2), dist).reshape(xy.shape)
    u = K[0, 0] * xy[..., 0] + K[0, 1] * xy[..., 1] + K[0, 2]
    v = K[1, 1] * xy[..., 1] + K[1, 2]
    return np.stack([u, v], axis=-1)


def _usable_views(corners: np.ndarray, object_points: np.ndarray, min_views: int) -> np.ndarray:
    """The indices of the views with a board (no NaN corner), after checking the shapes,
    the plane Z = 0 and that at least ``min_views`` views have one (:func:`calibrate_board`)."""
    if corners.ndim != 3 or corners.shape[1:] != (len(object_points), 2):
        raise ValueError(
            f"corners must be N×{len(object_points)}×2 (one row per object point), "
            f"got shape {corners.shape}"
        )
    if np.abs(object_points[:, 2]).max() > 1e-9:
        raise ValueError("object_points must lie on the board plane Z = 0")
    usable = np.isfinite(corners).all(axis=(1, 2))
    missing = np.flatnonzero(~usable).tolist()
    if usable.sum() < min_views:
        reason = f"; no board found in views {missing}" if missing else ""
        raise ValueError(
            f"only {int(usable.sum())} of {len(corners)} views have a board, need "
            f"{min_views}{reason}"
        )
    return np.flatnonzero(usable)
