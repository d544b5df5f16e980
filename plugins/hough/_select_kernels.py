"""numba kernel of the greedy selection of lines (imported on first use: numba loads slowly):
each candidate refitted by total least squares to its free supporting points, kept when
they still cover enough cells and it is far enough from every line kept."""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit
from ._support_kernels import _gather

__all__ = [
    "select_lines",
]


@njit(cache=True, nogil=True)
def _refit(x, y, on, t):
    """The total-least-squares line ``(ρ, θ, True)`` of the points ``on`` (θ on the branch
    of ``t``), or ``(0, t, False)`` for fewer than 2 points (:func:`select_lines`)."""
    n = 0
    mx = 0.0
    my = 0.0
    for i in range(x.size):
        if on[i]:
            n += 1
            mx += x[i]
            my += y[i]
    if n < 2:
        return 0.0, t, False
    mx /= n
    my /= n
    sxx = 0.0
    sxy = 0.0
    syy = 0.0
    for i in range(x.size):
        if on[i]:
            dx, dy = x[i] - mx, y[i] - my
            sxx += dx * dx
            sxy += dx * dy
            syy += dy * dy
    normal = 0.5 * np.arctan2(2.0 * sxy, sxx - syy) + 0.5 * np.pi  # least spread
    nx, ny = np.cos(normal), np.sin(normal)
    if nx * np.cos(t) + ny * np.sin(t) < 0:  # stay on the candidate's branch of θ
        nx, ny = -nx, -ny
    t = np.arctan2(ny, nx)
    r = mx * nx + my * ny
    return r, t, True


@njit(cache=True, nogil=True)
def _near_a_kept_line(out, count, r, t, theta_step, rho_step, min_distance):
    """Whether line ``(r, t)`` is within ``min_distance`` bins of one of the ``count``
    lines kept in ``out`` (:func:`select_lines`)."""
    for j in range(count):
        d_theta = abs(out[j, 1] - t)
        other = out[j, 0]
        if d_theta > 0.5 * np.pi:
            d_theta, other = np.pi - d_theta, -other
        if np.hypot(d_theta / theta_step, (r - other) / rho_step) < min_distance:
            return True
    return False


@njit(cache=True, nogil=True)
def _refine(
    x, y, orientation, check, free, r, t, covered, tolerance, window, cells, stamp, on, index
):
    """Twice: the line refitted to its points ``on`` (:func:`_refit`) and its points gathered
    again (:func:`_gather`); returns ``(ρ, θ, covered cells, stamp)`` (:func:`select_lines`)."""
    for _ in range(2):  # a peak's θ is coarse for a short segment: fit its points
        fitted_r, fitted_t, fitted = _refit(x, y, on, t)
        if not fitted:
            break
        r, t = fitted_r, fitted_t
        stamp += 1
        covered = _gather(
            x, y, orientation, check, free, r, t, tolerance, window, cells, stamp, on, True, index
        )
    return r, t, covered, stamp


@njit(cache=True, nogil=True)
def _keep(out, count, r, t, covered, on, free, theta_step, rho_step, min_distance):
    """Line ``(r, t)``, θ put in [0, π), appended to ``out`` and its points ``on`` claimed,
    unless it lies within ``min_distance`` bins of a line kept; the new count of lines
    (:func:`select_lines`)."""
    if abs(t) < 1e-12 or abs(t - np.pi) < 1e-12:  # rounding of an axis-parallel fit
        r, t = (r, 0.0) if abs(t) < 1e-12 else (-r, 0.0)
    if t < 0 or t >= np.pi:  # the same line with θ in [0, π)
        r, t = -r, t % np.pi
    if _near_a_kept_line(out, count, r, t, theta_step, rho_step, min_distance):
        return count
    for i in range(on.size):
        if on[i]:
            free[i] = False
    out[count, 0] = r
    out[count, 1] = t
    out[count, 2] = covered
    return count + 1


@njit(cache=True, nogil=True)
def select_lines(
    x,
    y,
    orientation,
    check,
    rho,
    theta,
    order,
    floor,
    tolerance,
    window,
    extent,
    max_lines,
    min_distance,
    theta_step,
    rho_step,
    index,
):
    """Greedy selection of lines ``(ρ, θ, covered length)`` from candidates ``order``: each
    candidate is refitted twice by total least squares to its free supporting points, kept
    when they still cover ``floor`` cells and it is ``min_distance`` bins from every line
    kept, and then claims those points."""
    cells = np.zeros(2 * int(np.ceil(extent)) + 4, dtype=np.int64)
    stamp = 0
    free = np.ones(x.size, dtype=np.bool_)
    on = np.zeros(x.size, dtype=np.bool_)
    out = np.zeros((min(max_lines, order.size), 3))
    count = 0
    for k in order:
        if count == max_lines:
            break
        r, t = rho[k], theta[k]
        stamp += 1
        covered = _gather(
            x, y, orientation, check, free, r, t, tolerance, window, cells, stamp, on, True, index
        )
        if covered < floor:
            continue
        r, t, covered, stamp = _refine(
            x,
            y,
            orientation,
            check,
            free,
            r,
            t,
            covered,
            tolerance,
            window,
            cells,
            stamp,
            on,
            index,
        )
        if covered < floor:
            continue
        count = _keep(out, count, r, t, covered, on, free, theta_step, rho_step, min_distance)
    return out[:count]
