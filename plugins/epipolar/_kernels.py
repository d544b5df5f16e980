"""numba kernels of the fundamental matrix's RANSAC (imported on first use: numba loads
slowly).

The Python loop spent most of its time in NumPy's per-call overhead on 8 × 9 arrays
(normalise, build the design matrix, two SVDs, score 500 Sampson distances, a few
hundred times). :func:`ransac_fundamental` runs the whole loop compiled: sample (the
samples of ``Generator.choice``, :mod:`..fitting._kernels`), solve by the normalised
8-point algorithm, score by Sampson distance, keep the best, lower the sample count.
The arithmetic is :func:`._geometry.eight_point`'s and :func:`._geometry.sampson_distance`'s,
with the 8 × 9 null vector by Householder QR and rank 2 by Jacobi rotations instead of
LAPACK's SVD (a microsecond call each, where the SVDs took 30): the same inliers. Also here:
the DLT triangulation point by point, and Levenberg-Marquardt's residuals and Jacobians
for F and the pose.
"""

from __future__ import annotations

import math

import numpy as np

from ..fitting._kernels import draw_sample, iterations_needed
from ..shared.jit import njit

__all__ = ["ransac_fundamental"]


@njit(cache=True, nogil=True)
def _normalising(x, y):  # pragma: no cover - compiled
    """(scale, centre x, centre y) of Hartley's similarity (``_geometry._normalising``)."""
    n = x.shape[0]
    cx = x.sum() / n
    cy = y.sum() / n
    spread = 0.0
    for i in range(n):
        spread += math.sqrt((x[i] - cx) ** 2 + (y[i] - cy) ** 2)
    return math.sqrt(2.0) / max(spread / n, 1e-12), cx, cy


@njit(cache=True, nogil=True)
def _similarity(scale, cx, cy):  # pragma: no cover - compiled
    t = np.zeros((3, 3))
    t[0, 0] = scale
    t[1, 1] = scale
    t[0, 2] = -scale * cx
    t[1, 2] = -scale * cy
    t[2, 2] = 1.0
    return t


@njit(cache=True, nogil=True)
def _product(x, y):  # pragma: no cover - compiled
    """3 × 3 matrix product in a loop (``@`` calls BLAS: a microsecond each at this size)."""
    out = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            for k in range(3):
                out[i, j] += x[i, k] * y[k, j]
    return out


@njit(cache=True, nogil=True)
def eight_point_sample(a, b, sample):  # pragma: no cover - compiled
    """(F, True) from the correspondences ``sample`` of a, b; (zeros, False) if degenerate."""
    n = sample.shape[0]
    ax, ay, bx, by = a[sample, 0], a[sample, 1], b[sample, 0], b[sample, 1]
    sa, cax, cay = _normalising(ax, ay)
    sb, cbx, cby = _normalising(bx, by)
    design = np.empty((n, 9))
    for r in range(n):
        ha = (sa * ax[r] - sa * cax, sa * ay[r] - sa * cay, 1.0)
        hb = (sb * bx[r] - sb * cbx, sb * by[r] - sb * cby, 1.0)
        for i in range(3):
            for j in range(3):
                design[r, 3 * i + j] = hb[i] * ha[j]
    if n == 8:
        f, degenerate = null_vector_8x9(design)
    else:
        _, singular, vt = np.linalg.svd(design, full_matrices=False)
        degenerate = singular[7] < 1e-9 * singular[0]
        f = vt[8].copy()
    if degenerate:
        return np.zeros((3, 3)), False
    f = f.reshape(3, 3)
    rotated, V = f.copy(), np.empty((3, 3))
    _jacobi_columns(rotated, V)  # f V = U Σ: drop the smallest singular triple
    least = 0
    for c in range(1, 3):
        if (rotated[:, c] ** 2).sum() < (rotated[:, least] ** 2).sum():
            least = c
    rank2 = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            rank2[i, j] = f[i, j] - rotated[i, least] * V[j, least]
    F = _product(_product(_similarity(sb, cbx, cby).T, rank2), _similarity(sa, cax, cay))
    norm = math.sqrt((F * F).sum())
    if norm <= 0.0:
        return np.zeros((3, 3)), False
    return F / norm, True


@njit(cache=True, nogil=True)
def null_vector_8x9(design):  # pragma: no cover - compiled
    """(unit null vector of the 8 × 9 ``design``, whether its singular values have
    σ₈ < 10⁻⁹ σ₁): the 8-point algorithm's SVD and test, by Householder QR of designᵀ.

    With designᵀ = QR, the null vector is Q's last column and design's singular values
    are R's, so that with c = ‖R‖_F ‖R⁻¹‖_F, 1/c ≤ σ₈/σ₁ ≤ 8/c. Outside that band the
    test is settled; inside it (a nearly degenerate sample, rare) LAPACK's SVD decides.
    """
    m = design.T.copy()  # 9 × 8, becomes R above its diagonal
    vs = np.zeros((9, 8))
    betas = np.zeros(8)
    for k in range(8):
        norm = 0.0
        for r in range(k, 9):
            norm += m[r, k] * m[r, k]
        if norm == 0.0:
            continue  # a zero column of R: singular, settled below
        alpha = -math.copysign(math.sqrt(norm), m[k, k])
        length = 0.0
        for r in range(k, 9):
            vs[r, k] = m[r, k]
        vs[k, k] -= alpha
        for r in range(k, 9):
            length += vs[r, k] * vs[r, k]
        betas[k] = 2.0 / length
        for c in range(k, 8):
            dot = 0.0
            for r in range(k, 9):
                dot += vs[r, k] * m[r, c]
            dot *= betas[k]
            for r in range(k, 9):
                m[r, c] -= dot * vs[r, k]
    null = np.zeros(9)
    null[8] = 1.0
    for k in range(7, -1, -1):
        dot = 0.0
        for r in range(k, 9):
            dot += vs[r, k] * null[r]
        dot *= betas[k]
        for r in range(k, 9):
            null[r] -= dot * vs[r, k]
    inverse = np.zeros((8, 8))  # R⁻¹ by back substitution
    for j in range(8):
        for i in range(j, -1, -1):
            if m[i, i] == 0.0:
                return null, True
            total = 1.0 if i == j else 0.0
            for k in range(i + 1, j + 1):
                total -= m[i, k] * inverse[k, j]
            inverse[i, j] = total / m[i, i]
    size = 0.0
    for i in range(8):
        for j in range(i, 8):
            size += m[i, j] * m[i, j]
    inverse_size = 0.0
    for i in range(8):
        for j in range(i, 8):
            inverse_size += inverse[i, j] * inverse[i, j]
    spread = math.sqrt(size * inverse_size)  # c
    if 1.0 / spread > 1.01e-9:
        return null, False
    if 8.0 / spread < 0.99e-9:
        return null, True
    _, singular, vt = np.linalg.svd(design, full_matrices=True)
    return vt[8].copy(), singular[7] < 1e-9 * singular[0]


@njit(cache=True, nogil=True, inline="always")
def _sampson(F, xa, ya, xb, yb):  # pragma: no cover - compiled
    """The Sampson distance of one pair ``(xa, ya)`` ↔ ``(xb, yb)`` under ``F``."""
    fa0 = F[0, 0] * xa + F[0, 1] * ya + F[0, 2]
    fa1 = F[1, 0] * xa + F[1, 1] * ya + F[1, 2]
    fa2 = F[2, 0] * xa + F[2, 1] * ya + F[2, 2]
    fb0 = xb * F[0, 0] + yb * F[1, 0] + F[2, 0]
    fb1 = xb * F[0, 1] + yb * F[1, 1] + F[2, 1]
    algebraic = xb * fa0 + yb * fa1 + fa2
    denominator = max(fa0 * fa0 + fa1 * fa1 + fb0 * fb0 + fb1 * fb1, 1e-300)
    return math.sqrt(algebraic * algebraic / denominator)


@njit(cache=True, nogil=True)
def sampson_inliers(F, a, b, threshold, out):  # pragma: no cover - compiled
    """``out[i]`` = Sampson distance of pair i below ``threshold``; returns their count."""
    found = 0
    for i in range(a.shape[0]):
        inside = _sampson(F, a[i, 0], a[i, 1], b[i, 0], b[i, 1]) < threshold
        out[i] = inside
        found += inside
    return found


@njit(cache=True, nogil=True)
def ransac_fundamental(a, b, threshold, confidence, max_iterations, rng):  # pragma: no cover
    """(best F, its inlier mask, samples drawn, whether any sample gave a model): the loop of
    :func:`~graphvision_plugins.fitting.ransac` with 8-point samples and Sampson scores."""
    count = a.shape[0]
    best, best_inliers, best_count = np.zeros((3, 3)), np.zeros(count, np.bool_), -1
    inliers = np.zeros(count, np.bool_)
    sample = np.empty(8, np.int64)
    needed, drawn = max_iterations, 0
    while drawn < min(needed, max_iterations):
        drawn += 1
        draw_sample(rng, count, sample)
        F, ok = eight_point_sample(a, b, sample)
        if not ok:
            continue
        found = sampson_inliers(F, a, b, threshold, inliers)
        if found > best_count:
            best, best_count = F, found
            best_inliers[:] = inliers
            needed = iterations_needed(1.0 - found / count, 8, confidence)
    return best, best_inliers, drawn, best_count >= 0


@njit(cache=True, nogil=True, error_model="numpy")
def triangulate_dlt(Pa, Pb, a, b):  # pragma: no cover - compiled
    """:func:`._geometry.triangulate_linear` point by point: the right singular vector of the
    smallest singular value of the 4 × 4 DLT rows (each of unit norm), by one-sided Jacobi
    rotations (Hestenes), accurate to rounding as LAPACK's SVD; NumPy's batched SVD paid a
    LAPACK call per point."""
    count = a.shape[0]
    out = np.empty((count, 3))
    A = np.empty((4, 4))
    V = np.empty((4, 4))
    for n in range(count):
        for r in range(4):
            P = Pa if r < 2 else Pb
            coord = a[n, r] if r < 2 else b[n, r - 2]
            k = r % 2
            norm = 0.0
            for c in range(4):
                A[r, c] = coord * P[2, c] - P[k, c]
                norm += A[r, c] * A[r, c]
            norm = math.sqrt(norm)
            for c in range(4):
                A[r, c] /= norm
        _jacobi_columns(A, V)
        smallest, least = 0, math.inf
        for c in range(4):
            size = A[0, c] ** 2 + A[1, c] ** 2 + A[2, c] ** 2 + A[3, c] ** 2
            if size < least:
                smallest, least = c, size
        w = V[3, smallest]
        for c in range(3):
            out[n, c] = V[c, smallest] / w
    return out


@njit(cache=True, nogil=True)
def _jacobi_columns(A, V):  # pragma: no cover - compiled
    """Rotate the columns of ``A`` until they are orthogonal (A V = U Σ), V in ``V``."""
    m = A.shape[1]
    V[:] = 0.0
    for i in range(m):
        V[i, i] = 1.0
    for _ in range(60):
        rotated = False
        for i in range(m - 1):
            for j in range(i + 1, m):
                alpha = beta = gamma = 0.0
                for r in range(A.shape[0]):
                    alpha += A[r, i] * A[r, i]
                    beta += A[r, j] * A[r, j]
                    gamma += A[r, i] * A[r, j]
                if abs(gamma) <= 1e-15 * math.sqrt(alpha * beta) or gamma == 0.0:
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = math.copysign(1.0, zeta) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
                c = 1.0 / math.sqrt(1.0 + t * t)
                s = c * t
                for r in range(A.shape[0]):
                    x, y = A[r, i], A[r, j]
                    A[r, i], A[r, j] = c * x - s * y, s * x + c * y
                for r in range(m):
                    x, y = V[r, i], V[r, j]
                    V[r, i], V[r, j] = c * x - s * y, s * x + c * y
        if not rotated:
            break


@njit(cache=True, nogil=True)
def sampson_distances(F, a, b):  # pragma: no cover - compiled
    """:func:`._geometry.sampson_distance`, compiled (the residuals Levenberg-Marquardt
    evaluates some fifty times per refinement)."""
    out = np.empty(a.shape[0])
    for i in range(a.shape[0]):
        out[i] = _sampson(F, a[i, 0], a[i, 1], b[i, 0], b[i, 1])
    return out


@njit(cache=True, nogil=True)
def _cross(x, y, z):  # pragma: no cover - compiled
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


@njit(cache=True, nogil=True)
def _rotation(x, y, z):  # pragma: no cover - compiled
    """``camera._projection.rotation_from_vector`` (Rodrigues' formula), compiled."""
    theta = math.sqrt(x * x + y * y + z * z)
    if theta < 1e-12:
        return np.eye(3) + _cross(x, y, z)
    k = _cross(x / theta, y / theta, z / theta)
    return np.eye(3) + math.sin(theta) * k + (1.0 - math.cos(theta)) * (k @ k)


@njit(cache=True, nogil=True)
def fundamental_residuals(x, u0, vt0, a, b):  # pragma: no cover - compiled
    """Sampson distances under :math:`F = R(x_{0:3}) U_0 \\operatorname{diag}(1, x_6, 0)
    V_0^T R(x_{3:6})^T` (``_geometry.refine_fundamental``'s parametrisation)."""
    u = _rotation(x[0], x[1], x[2]) @ u0
    vt = vt0 @ _rotation(x[3], x[4], x[5]).T
    middle = np.zeros((3, 3))
    middle[0, 0] = 1.0
    middle[1, 1] = x[6]
    return sampson_distances(u @ middle @ vt, a, b)


@njit(cache=True, nogil=True)
def pose_residuals(x, R, t, e1, e2, ka_inv, kb_inv, a, b):  # pragma: no cover - compiled
    """Sampson distances under :math:`F = K_b^{-T} [t(x)]_\\times R(x_{0:3}) R K_a^{-1}`,
    :math:`t(x) \\propto t + x_3 e_1 + x_4 e_2` (``_geometry.refine_pose``'s parametrisation)."""
    direction = t + x[3] * e1 + x[4] * e2
    direction = direction / math.sqrt((direction * direction).sum())
    rotation = _rotation(x[0], x[1], x[2]) @ R
    cross = _cross(direction[0], direction[1], direction[2])
    return sampson_distances(kb_inv.T @ cross @ rotation @ ka_inv, a, b)


@njit(cache=True, nogil=True)
def _step(value):  # pragma: no cover - compiled
    """SciPy's forward-difference step for ``value`` (``approx_derivative``, '2-point')."""
    sign = 1.0 if value >= 0 else -1.0
    return math.sqrt(np.finfo(np.float64).eps) * sign * max(1.0, abs(value))


@njit(cache=True, nogil=True)
def fundamental_jacobian(x, u0, vt0, a, b):  # pragma: no cover - compiled
    """Forward differences of :func:`fundamental_residuals`, SciPy's ``'2-point'`` steps and
    arithmetic (the same Jacobian, without a Python call per column)."""
    f0 = fundamental_residuals(x, u0, vt0, a, b)
    out = np.empty((f0.shape[0], x.shape[0]))
    for i in range(x.shape[0]):
        moved = x.copy()
        moved[i] = x[i] + _step(x[i])
        out[:, i] = (fundamental_residuals(moved, u0, vt0, a, b) - f0) / (moved[i] - x[i])
    return out


@njit(cache=True, nogil=True)
def pose_jacobian(x, R, t, e1, e2, ka_inv, kb_inv, a, b):  # pragma: no cover - compiled
    """Forward differences of :func:`pose_residuals`, as :func:`fundamental_jacobian`."""
    f0 = pose_residuals(x, R, t, e1, e2, ka_inv, kb_inv, a, b)
    out = np.empty((f0.shape[0], x.shape[0]))
    for i in range(x.shape[0]):
        moved = x.copy()
        moved[i] = x[i] + _step(x[i])
        step = moved[i] - x[i]
        out[:, i] = (pose_residuals(moved, R, t, e1, e2, ka_inv, kb_inv, a, b) - f0) / step
    return out
