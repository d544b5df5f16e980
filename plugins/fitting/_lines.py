"""Line fitting: least squares, weighted, total (constrained), Gauss-Newton, RANSAC."""

from __future__ import annotations

from typing import Annotated, Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from graphvision import Array, ArrayPort, Float, Points2D, PortValueError, node

from ..shared.params import Iterations, Positive, Probability, Seed
from ._ransac import ransac

__all__ = [
    "Line2D",
    "Line2DPort",
    "fit_line_lstsq",
    "fit_line_ransac",
    "fit_line_total",
    "fit_line_weighted",
    "fit_line_weighted_node",
    "line_distance",
    "line_residuals",
    "refine_line",
]


class Line2DPort(ArrayPort):
    """A line ``a x + b y + c = 0`` as ``float64 (3,)`` with ``a² + b² = 1``."""

    ndims = (1,)
    dtypes = (np.float64,)
    expected = "float64 (a, b, c) with a² + b² = 1"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if (
            value.shape != (3,)
            or not np.isfinite(value).all()
            or not np.isclose(value[0] ** 2 + value[1] ** 2, 1.0)
        ):
            raise PortValueError(f"expected Line2D ({cls.expected}), got {value!r}")
        return value


Line2D = Annotated[NDArray[np.float64], Line2DPort]
"""The annotation of a line (see :class:`Line2DPort`)."""


def _check_points(points: np.ndarray, needed: int = 2) -> None:
    if len(points) < needed:
        raise ValueError(f"need at least {needed} points to fit a line, got {len(points)}")


def _normal_form(slope: float, intercept: float) -> np.ndarray:
    """``y = p1 x + p2`` as a unit-normal line ``(a, b, c)``."""
    line = np.array([slope, -1.0, intercept])
    return line / np.hypot(slope, 1.0)


def line_residuals(line: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Perpendicular distances of ``points`` to the unit-normal ``line``."""
    return np.abs(points @ line[:2] + line[2])


@node("fitting.line_lstsq", version=1)
def fit_line_lstsq(points: Points2D) -> Line2D:
    r"""Least squares line :math:`y = p_1 x + p_2`, minimising vertical errors.

    .. math:: E(p) = \sum_i (x_i p_1 + p_2 - y_i)^2, \qquad p = A^\dagger b,
              \quad A = [x\; 1],\ b = y

    Vertical errors make it unusable for near-vertical lines (use
    ``fitting.line_total``), and one outlier can pull it anywhere.

    Parameters
    ----------
    points : Points2D
        At least two points (x, y).

    Returns
    -------
    line : (3,) float64, ``a x + b y + c = 0`` with ``a² + b² = 1``
    """
    _check_points(points)
    design = np.column_stack([points[:, 0], np.ones(len(points))])
    (slope, intercept), *_ = np.linalg.lstsq(design, points[:, 1], rcond=None)
    return _normal_form(slope, intercept)


def fit_line_weighted(points: np.ndarray, weights: np.ndarray) -> np.ndarray:
    r"""Weighted least squares :math:`p = (A^T W A)^{-1} A^T W b` of ``y = p_1 x + p_2``."""
    _check_points(points)
    design = np.column_stack([points[:, 0], np.ones(len(points))])
    weighted = design * weights[:, None]
    slope, intercept = np.linalg.solve(design.T @ weighted, weighted.T @ points[:, 1])
    return _normal_form(slope, intercept)


@node("fitting.line_weighted", version=1)
def fit_line_weighted_node(points: Points2D, weights: Array) -> Line2D:
    r"""Weighted least squares line: :math:`E(p) = \sum_i w_i \varepsilon_i^2`.

    .. math:: p = (A^T W A)^{-1} A^T W b

    Parameters
    ----------
    points : (N, 2) float64
    weights : (N,) array of non-negative weights

    Returns
    -------
    line : (3,) float64
    """
    weights = np.asarray(weights, dtype=np.float64).ravel()
    if weights.shape != (len(points),) or (weights < 0).any():
        raise ValueError(
            f"weights must be {len(points)} non-negative numbers, got shape {weights.shape}"
        )
    return fit_line_weighted(points, weights)


@node("fitting.line_total", version=1)
def fit_line_total(points: Points2D) -> Line2D:
    r"""Total (constrained) least squares: minimise perpendicular distances.

    With centred points :math:`A = [x - \bar x,\; y - \bar y]`, the normal
    :math:`(a, b)` minimising :math:`\|A n\|^2` subject to :math:`\|n\| = 1`
    is the eigenvector of :math:`A^T A` of the smallest eigenvalue: the last
    right singular vector of :math:`A` (SVD). Then :math:`c = -(a \bar x + b \bar y)`.

    Parameters
    ----------
    points : Points2D
        At least two points (x, y).

    Returns
    -------
    line : (3,) float64

    Raises
    ------
    ValueError
        For fewer than two distinct points (no line is defined).
    """
    _check_points(points)
    centre = points.mean(axis=0)
    _, singular, vt = np.linalg.svd(points - centre, full_matrices=False)
    if singular[0] == 0:
        raise ValueError("all points coincide: no line is defined")
    normal = vt[-1]
    return np.array([normal[0], normal[1], -normal @ centre])


def refine_line(line: np.ndarray, points: np.ndarray, *, iterations: int = 10) -> np.ndarray:
    r"""Gauss-Newton on perpendicular distances, with the line as :math:`(\theta, \rho)`.

    The residual of point :math:`i` is :math:`r_i = x_i\cos\theta + y_i\sin\theta - \rho`;
    each step solves :math:`(J^T J)\,\delta = -J^T r`.
    """
    theta = np.arctan2(line[1], line[0])
    rho = -line[2]
    for _ in range(iterations):
        cos, sin = np.cos(theta), np.sin(theta)
        residual = points[:, 0] * cos + points[:, 1] * sin - rho
        jacobian = np.column_stack(
            [-points[:, 0] * sin + points[:, 1] * cos, -np.ones(len(points))]
        )
        step, *_ = np.linalg.lstsq(jacobian, -residual, rcond=None)
        theta, rho = theta + step[0], rho + step[1]
        if np.abs(step).max() < 1e-12:
            break
    return np.array([np.cos(theta), np.sin(theta), -rho])


class RobustLine(NamedTuple):
    line: Line2D
    inliers: Array


@node("fitting.line_ransac", version=1)
def fit_line_ransac(
    points: Points2D,
    *,
    threshold: Positive = 2.0,
    confidence: Probability = 0.99,
    max_iterations: Iterations = 1000,
    seed: Seed = 0,
) -> RobustLine:
    """RANSAC line: lines through two random points, scored by inliers within ``threshold``.

    The best line is refit to all its inliers by total least squares and
    refined with Gauss-Newton (see :func:`~graphvision_plugins.fitting.ransac`).

    Parameters
    ----------
    points : Points2D
        The points, inliers and outliers.
    threshold : float
        Inlier distance from a line, in the points' units.
    confidence : float
        Probability of drawing at least one outlier-free sample; sets the
        number of iterations adaptively.
    max_iterations : int
        Upper bound on the iterations.
    seed : int
        Seed of the sample draws.

    Returns
    -------
    line : (3,) float64
    inliers : (N,) bool, the inlier mask

    Raises
    ------
    ValueError
        When no two distinct points exist.
    """
    _check_points(points)

    def solve(sample: np.ndarray) -> np.ndarray | None:
        p, q = points[sample]
        direction = q - p
        length = np.hypot(*direction)
        if length == 0:
            return None
        normal = np.array([-direction[1], direction[0]]) / length
        return np.array([normal[0], normal[1], -normal @ p])

    def refit(indices: np.ndarray) -> np.ndarray:
        return refine_line(fit_line_total(points[indices]), points[indices])

    result = ransac(
        len(points),
        2,
        solve,
        lambda m: line_residuals(m, points),
        threshold,
        refit=refit,
        confidence=confidence,
        max_iterations=max_iterations,
        seed=seed,
    )
    if result.model is None:
        raise ValueError("all points coincide: no line is defined")
    result.require_support(2, threshold, "the line", exact=True, data=points)
    return RobustLine(result.model, result.inliers)


@node("fitting.line_distance", version=1)
def line_distance(line: Line2D, truth: Line2D, *, extent: Positive = 100.0) -> Float:
    """How far ``line`` is from ``truth``: the mean distance from ``line`` of 11 points
    spread over ``extent`` pixels of ``truth``, centred where ``truth`` passes closest
    to (50, 50), the centre of the sampled square.

    Parameters
    ----------
    line : Line2D
        The estimated line.
    truth : Line2D
        The true line.
    extent : float
        The points compared lie along ``truth`` within ``[-extent, extent]`` in x.

    Returns
    -------
    distance : float, pixels
    """
    normal = truth[:2]
    foot = np.array([50.0, 50.0]) - (normal @ [50.0, 50.0] + truth[2]) * normal
    direction = np.array([-normal[1], normal[0]])
    samples = foot + np.linspace(-extent / 2, extent / 2, 11)[:, None] * direction
    return float(line_residuals(line, samples).mean())
