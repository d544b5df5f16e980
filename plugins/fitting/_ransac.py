"""A generic RANSAC: minimal solver + residual + sample size + refit."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["RansacResult", "ransac", "ransac_iterations"]


def ransac_iterations(outlier_ratio: float, sample_size: int, confidence: float) -> int:
    r"""Samples needed to draw one all-inlier sample with probability ``confidence``.

    .. math:: N = \frac{\log(1 - p)}{\log\left(1 - (1 - e)^s\right)}

    >>> ransac_iterations(0.5, 4, 0.99)
    72
    """
    good = (1.0 - outlier_ratio) ** sample_size
    if good >= 1.0:
        return 1
    miss = math.log1p(-good)  # log(1 - good) without rounding 1 - 1e-18 to 1
    if miss == 0.0:
        return 10**9
    return math.ceil(math.log(1.0 - confidence) / miss)


@dataclass(frozen=True)
class RansacResult:
    """The refit model (None when no sample gave one), its inlier mask and the samples drawn."""

    model: Any
    inliers: np.ndarray
    iterations: int

    def require_support(
        self,
        sample_size: int,
        threshold: float,
        what: str,
        *,
        exact: bool = False,
        data: np.ndarray | None = None,
    ) -> None:
        """ValueError naming ``threshold`` when the model has fewer inliers than a minimal
        sample of ``sample_size`` (after the refit, which may lose its sample's points),
        or, for a model that passes ``exact``-ly through its sample (a line through two
        points, a homography through four), no inlier beyond that sample: it is then
        fitted to noise or to nothing, and every figure computed from its inliers (an
        RMS, a pose, an inlier ratio) would be meaningless. With the ``data`` rows, inliers
        at the same place count once (a detector's keypoints repeated with several
        orientations support a model no more than one)."""
        found = int(self.inliers.sum()) if self.model is not None else 0
        if found and data is not None:
            found = len(np.unique(np.asarray(data)[self.inliers], axis=0))
        if found < sample_size + exact:
            reason = (
                f"fewer than the {sample_size} of a minimal sample"
                if found < sample_size
                else f"none beyond the {sample_size} of the sample it passes through"
            )
            raise ValueError(
                f"{what}: only {found} of {len(self.inliers)} points lie within "
                f"threshold={threshold:g} of the best model, {reason}: raise the threshold, "
                "or the data has no such model"
            )


def ransac(
    count: int,
    sample_size: int,
    solve: Callable[[np.ndarray], Any],
    residuals: Callable[[Any], np.ndarray],
    threshold: float,
    *,
    refit: Callable[[np.ndarray], Any] | None = None,
    confidence: float = 0.99,
    max_iterations: int = 10_000,
    max_refits: int = 10,
    seed: int = 0,
) -> RansacResult:
    r"""RANSAC over ``count`` data items.

    1. draw a minimal sample of ``sample_size`` distinct items;
    2. ``solve(indices)`` fits a model to it (None for a degenerate sample);
    3. items whose ``residuals(model)`` are below ``threshold`` (e.g. 2σ for
       Gaussian noise of deviation σ) are its inliers; keep the model with
       the most inliers;
    4. after each improvement, lower the number of samples to
       :func:`ransac_iterations` for the observed outlier ratio (``confidence`` p);
    5. ``refit(inlier_indices)`` the best model on all its inliers (least
       squares), take the inliers of the refit model, and repeat until the
       inlier set stops changing (at most ``max_refits`` times): the notes'
       "improve RANSAC by applying least squares to the inliers". The refit
       is kept even when it has fewer inliers than the minimal-sample model
       (its inliers are the ones that fit best, not the most that a sample
       through two noisy points happened to cross); the minimal-sample model
       is kept only when a refit is degenerate (None, or fewer inliers than
       a sample).

    Parameters
    ----------
    count, sample_size : int
    solve, residuals, refit : callables
    threshold : float
    confidence : float
    max_iterations : int
    max_refits : int
        Bound on the refit–re-collect rounds (they usually converge in 2–3).
    seed : int
        Seed of the sampler: the result is a pure function of the inputs.

    Returns
    -------
    RansacResult

    References
    ----------
    .. [1] M. A. Fischler, R. C. Bolles, "Random sample consensus", Comm. ACM
       24(6), 1981.
    """
    rng = np.random.default_rng(seed)
    best_model, best_inliers, best_count = None, np.zeros(count, dtype=bool), -1
    needed, drawn = max_iterations, 0
    if count < sample_size:
        return RansacResult(None, best_inliers, 0)
    while drawn < min(needed, max_iterations):
        drawn += 1
        sample = rng.choice(count, size=sample_size, replace=False)
        model = solve(sample)
        if model is None:
            continue
        inliers = residuals(model) < threshold
        found = int(inliers.sum())
        if found > best_count:
            best_model, best_inliers, best_count = model, inliers, found
            needed = ransac_iterations(1.0 - found / count, sample_size, confidence)
    if best_model is not None and refit is not None and best_count >= sample_size:
        best_model, best_inliers = _refit_to_convergence(
            best_model, best_inliers, refit, residuals, threshold, sample_size, max_refits
        )
    return RansacResult(best_model, best_inliers, drawn)


def _refit_to_convergence(
    model: Any,
    inliers: np.ndarray,
    refit: Callable[[np.ndarray], Any],
    residuals: Callable[[Any], np.ndarray],
    threshold: float,
    sample_size: int,
    max_refits: int,
) -> tuple[Any, np.ndarray]:
    """Least squares on the inliers, new inliers, again, until the inlier set is stable."""
    for _ in range(max_refits):
        refined = refit(np.flatnonzero(inliers))
        if refined is None:
            break  # degenerate refit: keep the last good model
        refined_inliers = residuals(refined) < threshold
        if refined_inliers.sum() < sample_size:
            break
        stable = np.array_equal(refined_inliers, inliers)
        model, inliers = refined, refined_inliers
        if stable:
            break
    return model, inliers
