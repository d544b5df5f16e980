r"""A generic RANSAC: minimal solver + residual + sample size + refit; and the
significance of its model, a-contrario.

**Significance.** RANSAC keeps the model with the most inliers, and some model always
has a few: 15 of 400 correspondences drawn at random fit the best of 2000 fundamental
matrices within 1 px. The a-contrario test (Moisan & Stival 2004) asks how many
models that good chance alone would give. Under the background model, the data are
independent and uniform over their domain (each view's points over the bounding box
of that view's points, since the nodes do not see the image), so a datum fits a given
model with a probability α, the *chance inlier rate*; of the n − s data outside a
minimal sample, the number that fit is binomial. With :math:`N_\mathrm{tests} =
(n - s)\binom{n}{s}` (every minimal sample, with every inlier count k), the number of
false alarms of a model with k inliers is

.. math::

    \mathrm{NFA}(k) = (n - s)\binom{n}{s}
        \sum_{j = k - s}^{n - s} \binom{n - s}{j} \alpha^j (1 - \alpha)^{n - s - j},

the expected number of models at least this well supported in data without any
model. NFA ≤ 1 is meaningful; NFA > 1 is what chance produces (Moisan & Stival bound
the tail by :math:`\binom{n - s}{k - s}\alpha^{k - s}`; the sum is exact). α is
measured for the model's own residual and threshold by drawing pairs of points
uniformly over the domains (:func:`chance_inlier_rate`, a scrambled Sobol sequence:
seeded, and of smaller error than independent draws).

References
----------
.. [1] M. A. Fischler, R. C. Bolles, "Random sample consensus", Comm. ACM 24(6), 1981.
.. [2] L. Moisan, B. Stival, "A probabilistic criterion to detect rigid point matches
   between two images and estimate the fundamental matrix", IJCV 57(3), 2004.
.. [3] L. Moisan, P. Moulon, P. Monasse, "Automatic homographic registration of a pair
   of images, with a contrario elimination of outliers", IPOL 2, 2012.
"""

from __future__ import annotations

import copy
import functools
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "RansacResult",
    "chance_inlier_rate",
    "log10_binomial_tail",
    "log10_nfa",
    "model_significance",
    "ransac",
    "ransac_iterations",
    "refuse_chance",
]

CHANCE_HITS = 400
"""Fitting draws that end the measure of a chance inlier rate α (about 5 % of error)."""
MAX_CHANCE_DRAWS = 2**21
"""Most draws for α (a 3 px disc in a 1000 × 700 view fits one in 10,000)."""
SETTLED = 20.0
"""Orders of magnitude below ``max_nfa`` at which α's upper bound settles a model."""


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

    def support(self, data: np.ndarray | None = None) -> tuple[int, int]:
        """(inliers, data) counted once per distinct row of ``data`` when given (a
        detector's keypoint repeated with several orientations is one datum)."""
        count = len(self.inliers)
        found = int(self.inliers.sum()) if self.model is not None else 0
        if data is not None:
            rows = np.asarray(data)
            count = len(np.unique(rows, axis=0))
            if found:
                found = len(np.unique(rows[self.inliers], axis=0))
        return found, count

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
            found = self.support(data)[0]
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


def log10_binomial_tail(trials: int, successes: int, p: float) -> float:
    r"""log10 of :math:`P(X \ge \text{successes})` for :math:`X \sim B(\text{trials}, p)`,
    summed in log space (no underflow for tails of 1e-1000).

    >>> round(log10_binomial_tail(10, 10, 0.5), 4)  # 2^-10
    -3.0103
    """
    from scipy.special import gammaln, logsumexp

    if successes <= 0 or p >= 1.0:
        return 0.0
    if successes > trials or p <= 0.0:
        return -math.inf
    k = np.arange(successes, trials + 1, dtype=np.float64)
    log_pmf = (
        gammaln(trials + 1.0)
        - gammaln(k + 1.0)
        - gammaln(trials - k + 1.0)
        + k * math.log(p)
        + (trials - k) * math.log1p(-p)
    )
    return float(logsumexp(log_pmf)) / math.log(10.0)


def log10_nfa(count: int, sample_size: int, inliers: int, alpha: float) -> float:
    r"""log10 of the number of false alarms of a model with ``inliers`` of ``count`` data
    fitting it, each datum fitting by chance with probability ``alpha`` (module
    docstring): :math:`\log_{10}\bigl((n - s)\binom{n}{s}\bigr)` plus the log of the
    binomial tail of the :math:`k - s` inliers beyond a minimal sample.

    >>> round(log10_nfa(20, 2, 20, 0.5), 2)  # log10(18 · 190 · 2^-18)
    -1.88
    """
    from scipy.special import gammaln

    extra = max(count - sample_size, 1)
    log_tests = math.log10(extra) + float(
        gammaln(count + 1.0) - gammaln(sample_size + 1.0) - gammaln(extra + 1.0)
    ) / math.log(10.0)
    return log_tests + log10_binomial_tail(count - sample_size, inliers - sample_size, alpha)


@functools.lru_cache(maxsize=16)
def _scrambled_sobol(dimensions: int, seed: int) -> Any:
    """A scrambled Sobol engine, never drawn from (callers draw from a copy): building one
    reads the direction numbers and scrambles them, some 30 ms, most of a fundamental
    matrix's significance test; a copy costs half a millisecond and draws the same points."""
    from scipy.stats import qmc

    return qmc.Sobol(dimensions, scramble=True, seed=seed)


def _chance_counts(
    fits: Callable[..., np.ndarray], views: tuple[np.ndarray, ...], seed: int
) -> Iterator[tuple[int, int]]:
    """(fitting, drawn) after each batch of pairs drawn uniformly over the views' bounding
    boxes (a scrambled Sobol sequence seeded by ``seed``): 2^14 draws, then doubling."""
    sobol = copy.deepcopy(_scrambled_sobol(2 * len(views), seed))  # the engine's first draws
    low = [points.min(axis=0) for points in views]
    span = [np.maximum(points.max(axis=0) - points.min(axis=0), 1e-12) for points in views]
    fitting, drawn, batch = 0, 0, 2**14
    while True:
        unit = sobol.random(batch)
        drawn_points = [low[v] + unit[:, 2 * v : 2 * v + 2] * span[v] for v in range(len(views))]
        fitting += int(np.count_nonzero(fits(*drawn_points)))
        drawn += batch
        yield fitting, drawn
        batch = drawn  # Sobol points come in powers of two


def chance_inlier_rate(
    fits: Callable[..., np.ndarray],
    views: tuple[np.ndarray, ...],
    *,
    hits: int = CHANCE_HITS,
    max_draws: int = MAX_CHANCE_DRAWS,
    seed: int = 0,
) -> float:
    """α: the probability that a datum of the background model fits (module docstring).

    ``fits(*points)`` takes one ``M×2`` array per view, each drawn uniformly over the
    bounding box of that view's points (a scrambled Sobol sequence seeded by
    ``seed``), and says which rows fit the model (residual below the threshold). The
    draws double from 2^14 until ``hits`` of them fit (a relative error of about
    1/√hits) or ``max_draws`` are drawn. Returns (fitting + 1) / (draws + 1), never 0.
    """
    for fitting, drawn in _chance_counts(fits, views, seed):
        if fitting >= hits or drawn >= max_draws:
            return (fitting + 1) / (drawn + 1)
    raise AssertionError("unreachable: the draws never end")  # pragma: no cover


def _upper_rate(fitting: int, drawn: int) -> float:
    """About a 97.5 % upper bound of a rate from a Poisson count: (h + 2√(h+1) + 2) / n."""
    return (fitting + 2.0 * math.sqrt(fitting + 1.0) + 2.0) / drawn


def model_significance(
    fits: Callable[..., np.ndarray],
    views: tuple[np.ndarray, ...],
    count: int,
    sample_size: int,
    inliers: int,
    *,
    max_nfa: float | None = 1.0,
    seed: int = 0,
) -> tuple[float, float]:
    """(log10 NFA, α) of a model with ``inliers`` of ``count`` data fitting it.

    α is measured as :func:`chance_inlier_rate` does, but the draws stop as soon as
    even α's upper bound (:func:`_upper_rate`) makes the model significant by
    :data:`SETTLED` orders of magnitude beyond ``max_nfa``: a model that hundreds of
    inliers support is settled by the first 2^14 draws, where measuring its tiny α
    to 5 % took up to 2^21. Such a model is reported with that bound (an upper bound
    of its NFA); any other with α measured as :func:`chance_inlier_rate` measures it.
    """
    line = min(0.0, math.log10(max_nfa) if max_nfa is not None else 0.0) - SETTLED
    for fitting, drawn in _chance_counts(fits, views, seed):
        upper = _upper_rate(fitting, drawn)
        bound = log10_nfa(count, sample_size, inliers, min(upper, 1.0))
        if bound <= line:
            return bound, upper
        if fitting >= CHANCE_HITS or drawn >= MAX_CHANCE_DRAWS:
            alpha = (fitting + 1) / (drawn + 1)
            return log10_nfa(count, sample_size, inliers, alpha), alpha
    raise AssertionError("unreachable: the draws never end")  # pragma: no cover


def refuse_chance(
    log_nfa: float, max_nfa: float | None, what: str, inliers: int, count: int, alpha: float
) -> None:
    """ValueError naming ``what`` when chance explains the model: NFA above ``max_nfa``
    (None: accept every model)."""
    if max_nfa is not None and log_nfa > math.log10(max_nfa):
        raise ValueError(
            f"{what}: {inliers} of {count} points fit the best model, as many as chance "
            f"gives: NFA = 10^{log_nfa:.1f} > max_nfa={max_nfa:g} (a point drawn at random "
            f"fits a model with probability {alpha:.2g}); the data has no such model, or "
            "raise max_nfa"
        )
