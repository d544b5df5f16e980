"""Global thresholds chosen from the gray-level histogram."""

from __future__ import annotations

from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, BinaryImage, Conformance, Float, GrayImage, LabelImage, node

from ..shared.checks import ordered
from ..shared.params import Fraction

__all__ = ["ght", "histogram", "manual", "multi_otsu", "otsu", "split_scores"]

Bins = Annotated[int, Field(ge=2, le=65536, description="Number of histogram bins.")]
Foreground = Literal["bright", "dark"]


class Thresholded(NamedTuple):
    mask: BinaryImage
    threshold: Float


class Classes(NamedTuple):
    labels: LabelImage
    thresholds: Array


def histogram(image: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """Counts and bin centres over the image's range ``[min, max]``.

    Raises
    ------
    ValueError
        For a constant image: no threshold separates two classes.
    """
    low, high = float(image.min()), float(image.max())
    if low == high:
        raise ValueError(f"image is constant (every pixel is {low:g}): no threshold exists")
    counts, edges = np.histogram(image, bins=bins, range=(low, high))
    return counts.astype(np.float64), (edges[:-1] + edges[1:]) / 2


def _cumulative(counts: np.ndarray, centres: np.ndarray):
    """Class weights, sums and sums of squares below (0) and above (1) each split.

    Split ``i`` puts bins ``0..i`` in class 0; there are ``bins - 1`` splits.
    """
    n0 = np.cumsum(counts)[:-1]
    s0 = np.cumsum(counts * centres)[:-1]
    q0 = np.cumsum(counts * centres**2)[:-1]
    n1, s1, q1 = counts.sum() - n0, (counts * centres).sum() - s0, (counts * centres**2).sum() - q0
    return n0, s0, q0, n1, s1, q1


def split_scores(
    counts: np.ndarray,
    centres: np.ndarray,
    *,
    nu: float = 0.0,
    tau: float = 0.0,
    kappa: float = 0.0,
    omega: float = 0.5,
) -> np.ndarray:
    r"""GHT's score of every split of the histogram (Barron 2020, eq. 13).

    With :math:`w_c` the pixel count, :math:`d_c` the sum of squared
    deviations from the mean of class :math:`c`, :math:`p_c = w_c / N`:

    .. math::
        v_c = \frac{p_c \nu \tau^2 + d_c}{p_c \nu + w_c}, \qquad
        f = \sum_{c \in \{0,1\}} -\frac{d_c}{v_c} - w_c \log v_c
            + 2 (w_c + \kappa \omega_c) \log w_c

    with :math:`\omega_0 = \omega`, :math:`\omega_1 = 1 - \omega`: the
    expected complete log-likelihood of two Gaussians with a scaled inverse
    chi-squared prior (ν, τ) on each variance and a beta prior (κ, ω) on the
    mixture weight.
    """
    tiny = 1e-30
    n0, s0, q0, n1, s1, q1 = _cumulative(counts, centres)
    w0, w1 = np.maximum(n0, tiny), np.maximum(n1, tiny)
    total = counts.sum()
    d0 = np.maximum(q0 - s0 * s0 / w0, 0.0)
    d1 = np.maximum(q1 - s1 * s1 / w1, 0.0)
    score = np.zeros_like(w0)
    for w, d, share in ((w0, d0, omega), (w1, d1, 1.0 - omega)):
        p = w / total
        v = np.maximum((p * nu * tau**2 + d) / (p * nu + w), tiny)
        score += -d / v - w * np.log(v) + 2.0 * (w + kappa * share) * np.log(w)
    return score


def _mask(image: np.ndarray, threshold: float, foreground: str) -> np.ndarray:
    return image > threshold if foreground == "bright" else image <= threshold


def _best_split(scores: np.ndarray, centres: np.ndarray) -> float:
    """Threshold at the best split; ties take the mean of the tied bin centres."""
    return float(np.mean(centres[:-1][scores == scores.max()]))


@node("threshold.manual", version=1, check=ordered(("low", "high"), strict=True))
def manual(
    image: GrayImage,
    *,
    low: Fraction = 0.5,
    high: Fraction | None = None,
) -> BinaryImage:
    """Foreground where ``low < image`` (and ``image <= high`` when ``high`` is given).

    Parameters
    ----------
    image : (H, W) float32 ndarray
    low, high : float
        One threshold, or a band between two.

    Returns
    -------
    mask : (H, W) bool ndarray
    """
    mask = image > low
    return mask & (image <= high) if high is not None else mask


@node(
    "threshold.otsu",
    version=1,
    conformance=Conformance(
        "max_abs",
        0.004,
        mismatch=0.001,
        note=(
            "OpenCV splits 256 integer levels of the image's range whatever bins is; its level "
            "maps "
            "back to the middle of two levels"
        ),
    ),
)
def otsu(image: GrayImage, *, bins: Bins = 256, foreground: Foreground = "bright") -> Thresholded:
    r"""Otsu's threshold: the split of the histogram that maximises the between-class variance.

    .. math:: T^* = \arg\max_T\; \sigma_B^2(T) = w_0(T)\, w_1(T)\, (\mu_0(T) - \mu_1(T))^2

    computed for every split at once from cumulative sums of the histogram
    (bins over the image's range, as scikit-image does). The threshold is the
    centre of the last bin of the dark class; the mask is ``image > T``.

    Parameters
    ----------
    image : (H, W) float32 ndarray
    bins : int
    foreground : {"bright", "dark"}
        The mask marks ``image > T`` (bright) or ``image <= T`` (dark, e.g. ink).

    Returns
    -------
    mask : (H, W) bool ndarray
    threshold : float

    Raises
    ------
    ValueError
        For a constant image (no threshold exists).

    References
    ----------
    .. [1] N. Otsu, "A threshold selection method from gray-level
       histograms", IEEE Trans. SMC 9(1), 1979.
    """
    counts, centres = histogram(image, bins)
    n0, s0, _, n1, s1, _ = _cumulative(counts, centres)
    with np.errstate(divide="ignore", invalid="ignore"):
        between = n0 * n1 * (s0 / n0 - s1 / n1) ** 2
    between = np.nan_to_num(between, nan=-1.0)
    threshold = float(centres[int(np.argmax(between))])
    return Thresholded(_mask(image, threshold, foreground), threshold)


@node("threshold.ght", version=1)
def ght(
    image: GrayImage,
    *,
    nu: Annotated[float, Field(ge=0)] = 0.0,
    tau: Annotated[float, Field(ge=0)] = 0.0,
    kappa: Annotated[float, Field(ge=0)] = 0.0,
    omega: Fraction = 0.5,
    bins: Bins = 256,
    foreground: Foreground = "bright",
) -> Thresholded:
    r"""Barron's Generalized Histogram Thresholding (GHT), one pass over the histogram.

    Fits two Gaussians to the histogram with priors on their variances
    (scaled inverse chi-squared: strength ν, value τ², in intensity units)
    and on the mixture weight (beta: strength κ, mode ω), and picks the
    split maximising the expected complete log-likelihood (see
    :func:`split_scores`). Special cases, tested:

    * ν = κ = 0 (default): Minimum Error Thresholding (Kittler & Illingworth);
    * ν → ∞ with τ → 0: Otsu's method;
    * κ → ∞: the ω-th weighted percentile of the histogram.

    Parameters
    ----------
    image : (H, W) float32 ndarray
    nu, tau, kappa, omega : float
        Prior strengths and values (ν, τ, κ, ω in the paper).
    bins : int
    foreground : {"bright", "dark"}
        The mask marks ``image > T`` (bright) or ``image <= T`` (dark).

    Returns
    -------
    mask : (H, W) bool ndarray
    threshold : float

    References
    ----------
    .. [1] J. T. Barron, "A Generalization of Otsu's Method and Minimum Error
       Thresholding", ECCV 2020, https://arxiv.org/abs/2007.07350
    .. [2] J. Kittler and J. Illingworth, "Minimum error thresholding",
       Pattern Recognition 19(1), 1986.
    """
    counts, centres = histogram(image, bins)
    scores = split_scores(counts, centres, nu=nu, tau=tau, kappa=kappa, omega=omega)
    threshold = _best_split(scores, centres)
    return Thresholded(_mask(image, threshold, foreground), threshold)


@node("threshold.multi_otsu", version=1)
def multi_otsu(
    image: GrayImage, *, classes: Annotated[int, Field(ge=2, le=6)] = 3, bins: Bins = 256
) -> Classes:
    r"""Multi-level Otsu: ``classes - 1`` thresholds maximising the between-class variance.

    Maximising :math:`\sum_k w_k \mu_k^2 = \sum_k S_k^2 / W_k` over the ways
    of cutting the histogram into ``classes`` contiguous ranges is solved
    exactly by dynamic programming over the bins, :math:`O(K L^2)`.

    Parameters
    ----------
    image : GrayImage
        The image to split.
    classes : int
        Number of classes (thresholds + 1).
    bins : int
        Histogram bins over [0, 1].

    Returns
    -------
    labels : (H, W) int32 ndarray
        Class of each pixel, 1 (darkest) to ``classes`` (labels start at 1:
        no pixel is background).
    thresholds : (classes - 1,) float64 ndarray
        Increasing; class ``k`` is ``thresholds[k-2] < image <= thresholds[k-1]``.

    References
    ----------
    .. [1] P.-S. Liao, T.-S. Chen, P.-C. Chung, "A fast algorithm for
       multilevel thresholding", J. Inf. Sci. Eng. 17(5), 2001.
    """
    counts, centres = histogram(image, bins)
    if np.count_nonzero(counts) < classes:
        raise ValueError(
            f"the image has {np.count_nonzero(counts)} distinct gray levels; "
            f"{classes} classes need at least as many"
        )
    weight = np.concatenate([[0.0], np.cumsum(counts)])
    total = np.concatenate([[0.0], np.cumsum(counts * centres)])
    size = len(counts)
    # score[a, b]: S^2 / W of the class made of bins a..b-1 (b > a)
    start, stop = np.meshgrid(np.arange(size + 1), np.arange(size + 1), indexing="ij")
    with np.errstate(divide="ignore", invalid="ignore"):
        w = weight[stop] - weight[start]
        s = total[stop] - total[start]
        segment = np.where((stop > start) & (w > 0), s * s / w, -np.inf)
    best = segment[0].copy()  # best[b]: one class over bins 0..b-1
    cuts = []
    for _ in range(classes - 1):
        candidates = best[:, None] + segment  # end previous classes at a, next class a..b-1
        cuts.append(np.argmax(candidates, axis=0))
        best = candidates[cuts[-1], np.arange(size + 1)]
    edges, stop_at = [], size
    for cut in reversed(cuts):
        stop_at = int(cut[stop_at])
        edges.append(stop_at)
    thresholds = centres[np.array(sorted(edges)) - 1]
    labels = (np.searchsorted(thresholds, image, side="left") + 1).astype(np.int32)
    return Classes(labels, thresholds.astype(np.float64))
