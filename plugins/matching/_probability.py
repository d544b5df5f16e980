"""Lowe's probability that a pose's agreeing matches are not chance (2004, section 7.4):
the binomial tail of the inliers among the features inside the projected model, by
Bayes' rule."""

from __future__ import annotations

import math

import numpy as np

from graphvision import KeypointSet

from ..geometry import apply_homography
from ._model_views import ConstellationParams, ModelViews, _corners
from ._polygons import _inside_convex, polygon_area

__all__ = [
    "log_binomial_tail",
    "match_probability",
    "pose_probability",
]


def log_binomial_tail(k: int, n: int, p: float) -> float:
    r""":math:`\log P(X \ge k)` for :math:`X \sim B(n, p)`, summed in log space
    (:math:`\log \binom{n}{j}` from ``math.lgamma``) so that a tail far below the
    smallest float is still compared rightly with a small prior.

    >>> round(math.exp(log_binomial_tail(2, 3, 0.5)), 6)
    0.5
    """
    if k <= 0 or p >= 1.0:
        return 0.0
    if k > n or p <= 0.0:
        return -math.inf
    j = np.arange(k, n + 1)
    log_choose = np.array(
        [math.lgamma(n + 1) - math.lgamma(v + 1) - math.lgamma(n - v + 1) for v in j]
    )
    log_terms = log_choose + j * math.log(p) + (n - j) * math.log1p(-p)
    top = float(log_terms.max())
    return min(top + math.log(float(np.exp(log_terms - top).sum())), 0.0)


def match_probability(
    inliers: int, candidates: int, p: float, prior: float, sample: int = 4
) -> float:
    r"""Lowe's probability that ``inliers`` agreeing matches reveal the model (section 7.4).

    Of the :math:`n` = ``candidates`` scene features inside the projected model, each
    agrees with the pose by chance with probability :math:`p`; the chance of :math:`k`
    such agreements is the binomial tail

    .. math:: P(f \mid \neg m) = \sum_{j=k}^{n} \binom{n}{j} p^j (1 - p)^{n - j},

    and Bayes' rule with :math:`P(f \mid m) = 1` and the prior :math:`P(m)` gives

    .. math:: P(m \mid f) = \frac{P(m)}{P(m) + P(f \mid \neg m)\,(1 - P(m))}.

    The ``sample`` matches a homography passes through agree by construction, so
    :math:`k` and :math:`n` count the features beyond them.

    >>> round(match_probability(10, 100, 0.01, 0.01), 4)
    0.9592
    >>> match_probability(4, 100, 0.01, 0.01) == 0.01
    True
    """
    beyond = inliers - sample
    if beyond <= 0:
        return prior
    log_chance = log_binomial_tail(beyond, max(candidates - sample, beyond), p)
    odds = math.exp(min(log_chance - math.log(prior) + math.log1p(-prior), 700.0))
    return 1.0 / (1.0 + odds)


def _unique_positions(points: np.ndarray) -> int:
    return len(np.unique(np.round(points, 3), axis=0)) if len(points) else 0


def pose_probability(
    h: np.ndarray,
    inliers: np.ndarray,
    views: ModelViews,
    scene_keypoints: KeypointSet,
    pairs: np.ndarray,
    params: ConstellationParams,
) -> float:
    r""":func:`match_probability` of a pose. :math:`k`: the inliers' distinct scene
    positions; :math:`n`: the scene keypoints' distinct positions inside the projected
    model; :math:`p = d\,l\,r\,s` (Lowe's product): :math:`d` the fraction of scene
    keypoints matched to the model at all, :math:`l = \pi \tau^2 / A` the chance that a
    match lands within ``threshold`` :math:`\tau` of its prediction (:math:`A` the
    projected model's area), :math:`r = 2\,\Delta\theta / 360°` for the orientation
    tolerance and :math:`s = 0.5` for the scale (Lowe's value)."""
    quad = apply_homography(h, _corners(views.size))
    inside = _inside_convex(quad, scene_keypoints.xy)
    candidates = _unique_positions(scene_keypoints.xy[inside])
    k = _unique_positions(scene_keypoints.xy[pairs[inliers, 0]])
    d = len(np.unique(pairs[:, 0])) / max(len(scene_keypoints), 1)
    location = min(math.pi * params.threshold**2 / max(abs(polygon_area(quad)), 1e-9), 1.0)
    rotation = min(2 * params.orientation_tolerance / 360.0, 1.0)
    return match_probability(k, max(candidates, k), d * location * rotation * 0.5, params.prior)
