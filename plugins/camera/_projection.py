r"""Pure projection helpers: P from K, R, C̃; projection; decomposition; lens distortion.

Everything here is a plain numpy function (no node), so other families (two-view
geometry) can import it: ``from ..camera import project_points, undistort_points``.

The distortion model is the radial-tangential (Brown-Conrady) model in OpenCV's
coefficient order ``(k1, k2, p1, p2, k3)``, on normalised coordinates
:math:`(x, y) = K^{-1}` (pixel):

.. math::

    r^2 = x^2 + y^2, \quad
    x_d = x (1 + k_1 r^2 + k_2 r^4 + k_3 r^6) + 2 p_1 x y + p_2 (r^2 + 2 x^2), \\
    y_d = y (1 + k_1 r^2 + k_2 r^4 + k_3 r^6) + p_1 (r^2 + 2 y^2) + 2 p_2 x y.

References
----------
.. [1] Hartley & Zisserman, *Multiple View Geometry*, 2nd ed., 2004, §6.1 (P = K[R | −RC̃]),
   §6.2.4 (decomposition by RQ), §7.4 (radial distortion).
.. [2] D. C. Brown, "Decentering distortion of lenses", Photogrammetric Engineering 32(3), 1966.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "decompose_projection",
    "distort_normalised",
    "distort_pixels",
    "look_at",
    "normalise_pixels",
    "project_points",
    "projection_matrix",
    "rotation_from_vector",
    "undistort_normalised",
    "undistort_pixels",
    "vector_from_rotation",
]


def projection_matrix(K: np.ndarray, R: np.ndarray, C: np.ndarray) -> np.ndarray:
    r"""The 3×4 camera matrix :math:`P = K [R \mid -R \tilde C]`."""
    return K @ np.hstack([R, (-R @ C)[:, None]])


def cross_matrix(v: np.ndarray) -> np.ndarray:
    r""":math:`[v]_\times`, the matrix with :math:`[v]_\times w = v \times w`."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotation_from_vector(rvec: np.ndarray) -> np.ndarray:
    r"""Rodrigues' formula: :math:`R = I + \sin\theta [k]_\times + (1 - \cos\theta)[k]_\times^2`
    for the rotation by :math:`\theta = \lVert r \rVert` about :math:`k = r / \theta`
    (to first order, :math:`I + [r]_\times`, below :math:`\theta = 10^{-12}`)."""
    theta = float(np.linalg.norm(rvec))
    if theta < 1e-12:
        return np.eye(3) + cross_matrix(rvec)
    kx = cross_matrix(rvec / theta)
    return np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * kx @ kx


def vector_from_rotation(R: np.ndarray) -> np.ndarray:
    """The axis-angle vector of a rotation matrix (inverse of :func:`rotation_from_vector`)."""
    cos = np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)
    theta = float(np.arccos(cos))
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if theta < 1e-8:
        return axis / 2
    if np.pi - theta < 1e-6:  # sin θ ≈ 0: the axis from the symmetric part
        w, v = np.linalg.eigh((R + R.T) / 2)
        return theta * v[:, np.argmax(w)]
    return theta * axis / (2 * np.sin(theta))


def distort_normalised(xy: np.ndarray, distortion: np.ndarray) -> np.ndarray:
    """Apply the radial-tangential model (module docstring) to normalised ``N×2`` points."""
    k1, k2, p1, p2, k3 = distortion
    x, y = xy[:, 0], xy[:, 1]
    r2 = x * x + y * y
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.column_stack([xd, yd])


def _distortion_jacobian(xy: np.ndarray, distortion: np.ndarray) -> np.ndarray:
    """``N×2×2`` Jacobian of :func:`distort_normalised` with respect to (x, y)."""
    k1, k2, p1, p2, k3 = distortion
    x, y = xy[:, 0], xy[:, 1]
    r2 = x * x + y * y
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    d_radial = k1 + r2 * (2 * k2 + 3 * k3 * r2)  # d radial / d r², times 2x or 2y below
    jac = np.empty((len(xy), 2, 2))
    jac[:, 0, 0] = radial + 2 * x * x * d_radial + 2 * p1 * y + 6 * p2 * x
    jac[:, 0, 1] = 2 * x * y * d_radial + 2 * p1 * x + 2 * p2 * y
    jac[:, 1, 0] = 2 * x * y * d_radial + 2 * p1 * x + 2 * p2 * y
    jac[:, 1, 1] = radial + 2 * y * y * d_radial + 6 * p1 * y + 2 * p2 * x
    return jac


def undistort_normalised(
    xy: np.ndarray,
    distortion: np.ndarray,
    *,
    tolerance: float = 1e-12,
    max_iterations: int = 50,
) -> np.ndarray:
    r"""Invert :func:`distort_normalised` by Newton's method, point by point (vectorised).

    Starts from :math:`x_0 = x_d` and iterates
    :math:`x_{n+1} = x_n - J(x_n)^{-1} (d(x_n) - x_d)` until every residual is
    below ``tolerance`` (normalised units).

    Raises
    ------
    ValueError
        When some point has not converged after ``max_iterations``, or converged
        beyond the fold of the model (radial factor or Jacobian determinant
        ≤ 0: a strong barrel distortion maps no point inside the fold there).
    """
    target = np.asarray(xy, dtype=np.float64)
    if not np.any(distortion):
        return target.copy()
    estimate = target.copy()
    for _ in range(max_iterations):
        residual = distort_normalised(estimate, distortion) - target
        error = np.abs(residual).max(axis=1)
        active = error > tolerance
        if not active.any():
            break
        jac = _distortion_jacobian(estimate[active], distortion)
        estimate[active] -= np.linalg.solve(jac, residual[active][:, :, None])[:, :, 0]
    residual = np.abs(distort_normalised(estimate, distortion) - target).max(axis=1)
    # a root beyond the fold of the model is not the preimage: there the radial
    # factor turns negative (the point crosses the centre) or the Jacobian degenerates
    k1, k2, _, _, k3 = distortion
    r2 = (estimate**2).sum(axis=1)
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    folded = (radial <= 0) | (np.linalg.det(_distortion_jacobian(estimate, distortion)) <= 0)
    bad = ~(residual <= tolerance * 10) | folded
    if bad.any():
        worst = int(np.nanargmax(np.where(np.isfinite(residual), residual, np.inf)))
        raise ValueError(
            f"undistortion did not converge for {int(bad.sum())} of {len(target)} points "
            f"(e.g. normalised point {target[worst].round(4).tolist()}) after {max_iterations} "
            f"Newton iterations: the distortion {np.round(distortion, 4).tolist()} is not "
            "invertible there"
        )
    return estimate


def normalise_pixels(points: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Pixels to normalised coordinates: :math:`K^{-1} (u, v, 1)^T` (K upper triangular)."""
    fx, s, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2]
    y = (points[:, 1] - cy) / fy
    x = (points[:, 0] - cx - s * y) / fx
    return np.column_stack([x, y])


def _to_pixels(xy: np.ndarray, K: np.ndarray) -> np.ndarray:
    u = K[0, 0] * xy[:, 0] + K[0, 1] * xy[:, 1] + K[0, 2]
    v = K[1, 1] * xy[:, 1] + K[1, 2]
    return np.column_stack([u, v])


def distort_pixels(points: np.ndarray, K: np.ndarray, distortion: np.ndarray) -> np.ndarray:
    """Ideal (undistorted) pixels to the pixels a lens with ``distortion`` records."""
    return _to_pixels(distort_normalised(normalise_pixels(points, K), distortion), K)


def undistort_pixels(points: np.ndarray, K: np.ndarray, distortion: np.ndarray) -> np.ndarray:
    """Recorded (distorted) pixels to ideal pixels, by :func:`undistort_normalised`."""
    return _to_pixels(undistort_normalised(normalise_pixels(points, K), distortion), K)


def project_points(
    points: np.ndarray,
    K: np.ndarray,
    R: np.ndarray,
    C: np.ndarray,
    distortion: np.ndarray | None = None,
) -> np.ndarray:
    r"""Project world points ``N×3`` to pixels ``N×2``: :math:`x = K\, d(\pi(R(X - \tilde C)))`.

    :math:`\pi(X, Y, Z) = (X/Z, Y/Z)` and :math:`d` the lens distortion; points
    behind the camera (Z ≤ 0) give NaN.
    """
    cam = (np.asarray(points, dtype=np.float64) - C) @ R.T
    with np.errstate(divide="ignore", invalid="ignore"):
        xy = cam[:, :2] / np.where(cam[:, 2:] > 0, cam[:, 2:], np.nan)
    if distortion is not None and np.any(distortion):
        xy = distort_normalised(xy, distortion)
    return _to_pixels(xy, K)


def decompose_projection(P: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Split a finite camera :math:`P = [M \mid p_4]` into K, R and C̃.

    :math:`M = K R` by RQ decomposition; the signs of K's columns (and R's rows)
    are chosen so that K has a positive diagonal, and P is negated first when
    :math:`\det M < 0` so that R is a proper rotation. :math:`\tilde C = -M^{-1}
    p_4`, and K is scaled so :math:`K_{33} = 1`.

    Raises
    ------
    ValueError
        When M is singular (P is not a finite camera).
    """
    import scipy.linalg

    P = np.asarray(P, dtype=np.float64)
    M = P[:, :3]
    det = np.linalg.det(M)
    if not np.isfinite(det) or abs(det) < 1e-12 * max(np.abs(M).max(), 1e-300) ** 3:
        raise ValueError("the left 3×3 block M of P is singular: P is not a finite camera")
    if det < 0:
        P, M = -P, -M
    K, R = scipy.linalg.rq(M)
    signs = np.sign(np.diag(K))
    K, R = K * signs, signs[:, None] * R
    C = -np.linalg.solve(M, P[:, 3])
    return K / K[2, 2], R, C


def look_at(C: np.ndarray, target: np.ndarray, roll: float = 0.0) -> np.ndarray:
    r"""The rotation of a camera at ``C`` whose optical axis points at ``target``.

    Rows of R are the camera axes in world coordinates: z along the view
    direction, x as close to world +x as possible, :math:`y = z \times x`
    (image y down), then a rotation by ``roll`` radians about z.

    Raises
    ------
    ValueError
        When the target is the centre, or the view direction is world ±x.
    """
    z = np.asarray(target, dtype=np.float64) - C
    norm = np.linalg.norm(z)
    if norm == 0:
        raise ValueError("look_at: the target coincides with the camera centre")
    z = z / norm
    x = np.array([1.0, 0.0, 0.0]) - z[0] * z
    if np.linalg.norm(x) < 1e-9:
        raise ValueError("look_at: the view direction is parallel to world x")
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    c, s = np.cos(roll), np.sin(roll)
    return np.vstack([c * x + s * y, -s * x + c * y, z])
