r"""Two-view geometry as plain functions: F by the normalised 8-point algorithm, E, pose,
triangulation, Sampson distances.

For corresponding pixels :math:`x_a \leftrightarrow x_b` (homogeneous) the
fundamental matrix satisfies :math:`x_b^T F x_a = 0`; with calibrations
:math:`K_a, K_b` the essential matrix is :math:`E = K_b^T F K_a =
[t]_\times R`, where camera b is :math:`[R \mid t]` when camera a is
:math:`[I \mid 0]`.

References
----------
.. [1] R. I. Hartley, "In defense of the eight-point algorithm", IEEE PAMI
   19(6), 1997.
.. [2] R. Hartley, A. Zisserman, *Multiple View Geometry*, 2nd ed., 2004,
   §9.6 (E), §11.1–11.4 (8-point, Sampson), §12.2 (linear triangulation), §12.3
   (minimising the reprojection error).
"""

from __future__ import annotations

import numpy as np

from ..camera._projection import rotation_from_vector
from ..fitting._ransac import RansacResult, _refit_to_convergence

__all__ = [
    "eight_point",
    "essential_from_fundamental",
    "poses_from_essential",
    "ransac_eight_point",
    "reprojection_residuals",
    "sampson_distance",
    "triangulate_linear",
    "triangulate_nonlinear",
]


def _normalising(points: np.ndarray) -> np.ndarray:
    """Similarity moving the centroid to 0 and the mean distance to √2 (Hartley)."""
    centre = points.mean(axis=0)
    scale = np.sqrt(2.0) / max(float(np.linalg.norm(points - centre, axis=1).mean()), 1e-12)
    return np.array([[scale, 0, -scale * centre[0]], [0, scale, -scale * centre[1]], [0, 0, 1.0]])


def eight_point(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    r"""F from at least 8 correspondences: normalise, solve :math:`A f = 0` by SVD,
    force rank 2 (zero the smallest singular value), undo the normalisation.

    Returns None when the points are degenerate: the null space of the 8 or more
    rows is not one-dimensional (fewer than 8 independent constraints, e.g. points
    on a line, or a noise-free plane whose null space is three-dimensional).
    """
    ta, tb = _normalising(a), _normalising(b)
    ha = np.column_stack([a, np.ones(len(a))]) @ ta.T
    hb = np.column_stack([b, np.ones(len(b))]) @ tb.T
    design = np.einsum("ni,nj->nij", hb, ha).reshape(len(a), 9)
    _, singular, vt = np.linalg.svd(design, full_matrices=len(design) < 9)  # no N × N U
    if singular[7] < 1e-9 * singular[0]:
        return None
    f = vt[-1].reshape(3, 3)
    u, s, vt2 = np.linalg.svd(f)
    f = u @ np.diag([s[0], s[1], 0.0]) @ vt2
    F = tb.T @ f @ ta
    norm = np.linalg.norm(F)
    return F / norm if norm > 0 else None


def _compiled_or_none(F: np.ndarray, solved: bool) -> np.ndarray | None:
    return F if solved else None


def ransac_eight_point(
    a: np.ndarray,
    b: np.ndarray,
    threshold: float,
    confidence: float,
    max_iterations: int,
    seed: int,
) -> RansacResult:
    """:func:`~graphvision_plugins.fitting.ransac` with :func:`eight_point` samples scored by
    :func:`sampson_distance` and refit by :func:`eight_point`: the same samples (seed for
    seed) and the same model (to rounding), its loop over samples and its refits compiled
    (:mod:`._kernels`)."""
    from ._kernels import eight_point_sample, ransac_fundamental  # numba: compiled on first use

    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    if len(a) < 8:
        return RansacResult(None, np.zeros(len(a), dtype=bool), 0)
    rng = np.random.default_rng(seed)
    model, inliers, drawn, any_model = ransac_fundamental(
        a, b, float(threshold), float(confidence), int(max_iterations), rng
    )
    if not any_model:
        return RansacResult(None, inliers, drawn)
    if inliers.sum() >= 8:
        model, inliers = _refit_to_convergence(
            model,
            inliers,
            lambda i: _compiled_or_none(*eight_point_sample(a, b, i)),
            lambda F: sampson_distance(F, a, b),
            threshold,
            8,
            10,
        )
    return RansacResult(model, inliers, drawn)


def refine_fundamental(F: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""F minimising the Sampson distances of ``a, b`` (Levenberg-Marquardt), rank 2 kept.

    F is parametrised by its SVD, :math:`F = U \operatorname{diag}(1, s, 0) V^T`
    with U, V updated by small rotations (7 parameters: F's degrees of
    freedom), so every iterate has rank 2. With 7 correspondences or fewer
    the Sampson error can be made zero and is no measure of fit: F is
    returned as given.
    """
    from scipy.optimize import least_squares

    from ._kernels import fundamental_jacobian, fundamental_residuals  # compiled: called ~60 times

    if len(a) <= 7:
        return F / np.linalg.norm(F)

    u0, s0, vt0 = np.linalg.svd(F)
    ratio = s0[1] / s0[0]

    def compose(x: np.ndarray) -> np.ndarray:
        u = rotation_from_vector(x[:3]) @ u0
        vt = vt0 @ rotation_from_vector(x[3:6]).T
        return u @ np.diag([1.0, x[6], 0.0]) @ vt

    a, b = np.ascontiguousarray(a, dtype=np.float64), np.ascontiguousarray(b, dtype=np.float64)

    def residuals(x: np.ndarray) -> np.ndarray:
        return fundamental_residuals(x, u0, vt0, a, b)

    def jacobian(x: np.ndarray) -> np.ndarray:
        return fundamental_jacobian(x, u0, vt0, a, b)  # SciPy's '2-point' differences

    x0 = np.concatenate([np.zeros(6), [ratio]])
    refined = compose(least_squares(residuals, x0, jac=jacobian, method="lm").x)
    return refined / np.linalg.norm(refined)


def refine_pose(
    R: np.ndarray, t: np.ndarray, Ka: np.ndarray, Kb: np.ndarray, a: np.ndarray, b: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    r"""(R, t) minimising the Sampson distances of ``a, b`` under
    :math:`F = K_b^{-T} [t]_\times R K_a^{-1}` over the pose's 5 degrees of
    freedom (a rotation increment and the direction of t), Levenberg-Marquardt.
    With 5 correspondences or fewer the pose is returned as given (nothing to
    average over)."""
    from scipy.optimize import least_squares

    from ._kernels import pose_jacobian, pose_residuals  # compiled: LM calls them ~60 times

    if len(a) <= 5:
        return R, t / np.linalg.norm(t)

    ka_inv, kb_inv = np.linalg.inv(Ka), np.linalg.inv(Kb)
    t = t / np.linalg.norm(t)
    helper = np.eye(3)[np.argmin(np.abs(t))]
    e1 = np.cross(t, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(t, e1)

    def pose(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        direction = t + x[3] * e1 + x[4] * e2
        return rotation_from_vector(x[:3]) @ R, direction / np.linalg.norm(direction)

    a, b = np.ascontiguousarray(a, dtype=np.float64), np.ascontiguousarray(b, dtype=np.float64)
    R = np.ascontiguousarray(R, dtype=np.float64)

    def residuals(x: np.ndarray) -> np.ndarray:
        return pose_residuals(x, R, t, e1, e2, ka_inv, kb_inv, a, b)

    def jacobian(x: np.ndarray) -> np.ndarray:
        return pose_jacobian(x, R, t, e1, e2, ka_inv, kb_inv, a, b)  # SciPy's '2-point'

    return pose(least_squares(residuals, np.zeros(5), jac=jacobian, method="lm").x)


def sampson_distance(F: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""First-order geometric error in pixels: :math:`\sqrt{(x_b^T F x_a)^2 /
    ((F x_a)_1^2 + (F x_a)_2^2 + (F^T x_b)_1^2 + (F^T x_b)_2^2)}`."""
    ha = np.column_stack([a, np.ones(len(a))])
    hb = np.column_stack([b, np.ones(len(b))])
    fa = ha @ F.T
    fb = hb @ F
    algebraic = np.einsum("ni,ni->n", hb, fa)
    denominator = fa[:, 0] ** 2 + fa[:, 1] ** 2 + fb[:, 0] ** 2 + fb[:, 1] ** 2
    return np.sqrt(algebraic**2 / np.maximum(denominator, 1e-300))


def essential_from_fundamental(F: np.ndarray, Ka: np.ndarray, Kb: np.ndarray) -> np.ndarray:
    """:math:`E = K_b^T F K_a` with its singular values forced to (1, 1, 0)."""
    u, _, vt = np.linalg.svd(Kb.T @ F @ Ka)
    return u @ np.diag([1.0, 1.0, 0.0]) @ vt


def poses_from_essential(E: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    r"""The four :math:`(R, t)` of :math:`E = U \operatorname{diag}(1,1,0) V^T`:
    :math:`R = U W V^T` or :math:`U W^T V^T`, :math:`t = \pm u_3`."""
    u, _, vt = np.linalg.svd(E)
    if np.linalg.det(u) < 0:
        u = -u
    if np.linalg.det(vt) < 0:
        vt = -vt
    w = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    rotations = [u @ w @ vt, u @ w.T @ vt]
    return [(R, s * u[:, 2]) for R in rotations for s in (1.0, -1.0)]


def triangulate_linear(Pa: np.ndarray, Pb: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""Points ``N×3`` by the DLT: the null vector of
    :math:`[x P^3 - P^1;\ y P^3 - P^2]` for both views (each row normalised), the right
    singular vector of the smallest singular value, by one-sided Jacobi rotations compiled
    per point (:func:`._kernels.triangulate_dlt`; a point at infinity gives inf or NaN)."""
    from ._kernels import triangulate_dlt  # numba compiles (or loads its cache) on first use

    return triangulate_dlt(
        np.ascontiguousarray(Pa, dtype=np.float64),
        np.ascontiguousarray(Pb, dtype=np.float64),
        np.ascontiguousarray(a, dtype=np.float64),
        np.ascontiguousarray(b, dtype=np.float64),
    )


def reprojection_residuals(
    cameras: tuple[np.ndarray, ...], observed: tuple[np.ndarray, ...], points: np.ndarray
) -> np.ndarray:
    """Residuals ``N×(2·views)``: projection of each point minus its observed pixel, per view."""
    homogeneous = np.column_stack([points, np.ones(len(points))])
    parts = []
    for P, seen in zip(cameras, observed, strict=True):
        projected = homogeneous @ P.T
        parts.append(projected[:, :2] / projected[:, 2:] - seen)
    return np.concatenate(parts, axis=1)


def triangulate_nonlinear(
    Pa: np.ndarray,
    Pb: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    start: np.ndarray,
    iterations: int = 20,
) -> np.ndarray:
    r"""Points minimising the reprojection error in both views, from ``start`` (the DLT).

    .. math:: \min_X \sum_{v \in \{a, b\}} \lVert \pi(P_v X) - x_v \rVert^2

    solved for all points at once by Levenberg-Marquardt (a damping per
    point: a step is kept only where it lowers that point's error). The
    Jacobian of :math:`u = p_1 \cdot X / p_3 \cdot X` is
    :math:`(p_{1,:3} - u\, p_{3,:3}) / (p_3 \cdot X)`.
    """
    cameras, observed = (Pa, Pb), (a, b)
    points = start.copy()
    residual = reprojection_residuals(cameras, observed, points)
    cost = np.sum(residual**2, axis=1)
    damping = np.full(len(points), 1e-3)
    for _ in range(iterations):
        homogeneous = np.column_stack([points, np.ones(len(points))])
        rows = []
        for P in cameras:
            projected = homogeneous @ P.T
            w = projected[:, 2:]
            for k in (0, 1):
                rows.append((P[k, :3] - (projected[:, k : k + 1] / w) * P[2, :3]) / w)
        jacobian = np.stack(rows, axis=1)  # N × 4 × 3
        normal = np.einsum("nri,nrj->nij", jacobian, jacobian)
        gradient = np.einsum("nri,nr->ni", jacobian, residual)
        scaled = (
            normal
            + damping[:, None, None]
            * np.eye(3)
            * np.trace(normal, axis1=1, axis2=2)[:, None, None]
            / 3
        )
        step = np.linalg.solve(scaled, -gradient[..., None])[..., 0]
        trial = points + step
        trial_residual = reprojection_residuals(cameras, observed, trial)
        trial_cost = np.sum(trial_residual**2, axis=1)
        better = np.isfinite(trial_cost) & (trial_cost < cost)
        points[better] = trial[better]
        residual[better] = trial_residual[better]
        cost[better] = trial_cost[better]
        damping = np.where(better, damping / 10, damping * 10)
        if not np.any(np.abs(step[better]) > 1e-12 * (1 + np.abs(points[better]))):
            break
    return points
