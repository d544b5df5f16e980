"""Discrete AdaBoost over decision stumps, and the Viola–Jones cascade (seed: "AdaBoost",
"cascade of classifiers")."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Table, node

from ..shared.params import Iterations, Probability
from ._models import Cascade, CascadeModel, StumpClassifier, StumpModel, stump_votes
from ._subspace import check_classes
from ._types import Features

__all__ = ["Stump", "adaboost", "boost_stumps", "cascade", "cascade_table", "train_cascade"]


class Stump(NamedTuple):
    """One weak classifier ``polarity · sign(x[feature] − threshold)`` and its weight."""

    feature: int
    threshold: float
    polarity: float
    alpha: float


def boost_stumps(
    features: np.ndarray, signs: np.ndarray, weights: np.ndarray | None = None
) -> Iterator[Stump]:
    r"""Discrete AdaBoost: yields one stump per round, forever (the caller stops).

    Each round picks the stump of least weighted error ε over every feature, threshold
    (midpoints between consecutive distinct values) and polarity, all at once from
    cumulative sums of the weights sorted by each feature; then

    .. math:: \alpha = \tfrac12 \ln\frac{1 - \varepsilon}{\varepsilon}, \qquad
              w_i \leftarrow w_i\, e^{-\alpha y_i h(x_i)} / Z

    so that misclassified samples weigh more in the next round.

    References
    ----------
    Y. Freund and R. E. Schapire, "A decision-theoretic generalization of on-line
    learning and an application to boosting", J. Comput. Syst. Sci. 55(1), 1997.
    """
    count = len(signs)
    w = np.full(count, 1.0 / count) if weights is None else weights / weights.sum()
    order = np.argsort(features, axis=0, kind="stable")
    ranked = np.take_along_axis(features, order, axis=0)  # (N, F) each column sorted
    # a threshold between ranked[k − 1] and ranked[k]; k = 0 and k = N put every sample on
    # one side; equal neighbours cannot be separated
    cuts = np.vstack([ranked[:1] - 1.0, (ranked[1:] + ranked[:-1]) / 2, ranked[-1:] + 1.0])
    tied = np.vstack([np.zeros((1, ranked.shape[1]), bool), ranked[1:] == ranked[:-1]])
    tied = np.vstack([tied, np.zeros((1, ranked.shape[1]), bool)])
    positive = signs[order] > 0
    while True:
        sorted_w = w[order]
        below_pos = np.vstack([np.zeros((1, ranked.shape[1])), np.cumsum(sorted_w * positive, 0)])
        below_neg = np.vstack([np.zeros((1, ranked.shape[1])), np.cumsum(sorted_w * ~positive, 0)])
        total_neg = below_neg[-1]
        # polarity +1 says positive above the cut: errors are positives below, negatives above
        error_plus = below_pos + (total_neg - below_neg)
        error_plus[tied] = np.inf
        error_minus = np.where(tied, np.inf, 1.0 - error_plus)
        best_plus, best_minus = (
            np.unravel_index(np.argmin(error_plus), error_plus.shape),
            np.unravel_index(np.argmin(error_minus), error_minus.shape),
        )
        if error_plus[best_plus] <= error_minus[best_minus]:
            (cut, feature), polarity, error = best_plus, 1.0, error_plus[best_plus]
        else:
            (cut, feature), polarity, error = best_minus, -1.0, error_minus[best_minus]
        error = float(np.clip(error, 1e-10, 1 - 1e-10))
        alpha = 0.5 * np.log((1 - error) / error)
        threshold = float(cuts[cut, feature])
        votes = np.where(features[:, feature] > threshold, polarity, -polarity)
        w = w * np.exp(-alpha * signs * votes)
        w /= w.sum()
        yield Stump(int(feature), threshold, polarity, float(alpha))


def _two_classes(labels: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    classes = check_classes(labels, what)
    if len(classes) != 2:
        raise ValueError(f"{what} separates two classes, got {len(classes)}: {classes.tolist()}")
    return classes, np.where(labels == classes[1], 1.0, -1.0)


@node("recognition.adaboost", version=1)
def adaboost(
    train: Features,
    *,
    rounds: Iterations = 100,
) -> StumpClassifier:
    r"""Discrete AdaBoost over decision stumps: a strong classifier
    :math:`H(x) = \mathrm{sign}\sum_t \alpha_t h_t(x)` from weak ones that each split the
    reweighted training set better than chance (see :func:`boost_stumps`).

    Parameters
    ----------
    train : Features (N, D) of two classes
    rounds : number of stumps

    Returns
    -------
    classifier : StumpClassifier (positive sums mean the larger label)

    References
    ----------
    Y. Freund and R. E. Schapire, J. Comput. Syst. Sci. 55(1), 1997.
    """
    classes, signs = _two_classes(train.labels, "recognition.adaboost")
    stumps = boost_stumps(train.features, signs)
    chosen = [next(stumps) for _ in range(rounds)]
    feature, threshold, polarity, alpha = (np.array(column) for column in zip(*chosen, strict=True))
    return StumpModel(
        feature.astype(np.int64),
        threshold,
        polarity,
        alpha,
        classes,
        train.features.shape[1],
        train.recipe,
    )


def _train_stage(
    features: np.ndarray,
    signs: np.ndarray,
    positives: np.ndarray,
    pool: np.ndarray,
    detection_rate: float,
    false_positive_rate: float,
    max_stumps: int,
) -> tuple[int, tuple[np.ndarray, ...], float, np.ndarray]:
    """One stage of :func:`train_cascade` on the samples ``pool``: stumps boosted until the
    stage, its threshold lowered to keep ``detection_rate`` of the positives, passes at
    most ``false_positive_rate`` of the negatives (or holds ``max_stumps``). Returns its
    stump count, its columns (feature, threshold, polarity, alpha), its threshold and
    which samples of the pool pass it."""
    # each stage starts from weights balanced between the classes (Viola–Jones)
    weights = np.where(positives[pool], 0.5 / positives[pool].sum(), 0.5 / (~positives[pool]).sum())
    stumps = boost_stumps(features[pool], signs[pool], weights)
    chosen: list[Stump] = []
    while len(chosen) < max_stumps:
        chosen.append(next(stumps))
        feature, threshold, polarity, alpha = (np.array(c) for c in zip(*chosen, strict=True))
        sums = stump_votes(features[pool], feature.astype(int), threshold, polarity) @ alpha
        # lower the stage threshold until it keeps the required share of positives
        pos_sums = np.sort(sums[positives[pool]])
        keep = int(np.floor((1 - detection_rate) * len(pos_sums)))
        stage_threshold = float(pos_sums[keep]) if len(pos_sums) else 0.0
        passed = sums >= stage_threshold
        fp = passed[~positives[pool]].mean()
        if fp <= false_positive_rate:
            break
    return len(chosen), (feature, threshold, polarity, alpha), stage_threshold, passed


def train_cascade(
    features: np.ndarray,
    signs: np.ndarray,
    *,
    detection_rate: float,
    false_positive_rate: float,
    target_false_positive_rate: float,
    max_stages: int,
    max_stumps: int,
) -> dict[str, np.ndarray]:
    """The arrays of a cascade (see :func:`cascade`), trained stage by stage."""
    positives = signs > 0
    alive = np.ones(len(signs), bool)  # samples every stage so far accepted
    columns: dict[str, list] = {name: [] for name in ("feature", "threshold", "polarity", "alpha")}
    stage_of: list[int] = []
    thresholds, rejected, detected, false_rates = [], [], [], []
    negatives_total = int((~positives).sum())
    for stage in range(max_stages):
        pool = np.flatnonzero(alive)
        if not (~positives[pool]).any():
            break
        count, stage_columns, stage_threshold, passed = _train_stage(
            features, signs, positives, pool, detection_rate, false_positive_rate, max_stumps
        )
        for name, value in zip(
            ("feature", "threshold", "polarity", "alpha"), stage_columns, strict=True
        ):
            columns[name].append(value)
        stage_of += [stage] * count
        thresholds.append(stage_threshold)
        rejected.append(int((~passed & ~positives[pool]).sum()))
        alive[pool[~passed]] = False
        detected.append(float(alive[positives].mean()))
        false_rates.append(float(alive[~positives].sum() / max(negatives_total, 1)))
        if false_rates[-1] <= target_false_positive_rate:
            break
    return {
        "feature": np.concatenate(columns["feature"]).astype(np.int64),
        "threshold": np.concatenate(columns["threshold"]),
        "polarity": np.concatenate(columns["polarity"]),
        "alpha": np.concatenate(columns["alpha"]),
        "stage": np.array(stage_of, np.int64),
        "stage_threshold": np.array(thresholds),
        "rejected": np.array(rejected, np.int64),
        "detection_rate": np.array(detected),
        "false_positive_rate": np.array(false_rates),
    }


@node("recognition.cascade", version=1)
def cascade(
    train: Features,
    *,
    detection_rate: Annotated[float, Field(gt=0, le=1)] = 0.99,
    false_positive_rate: Probability = 0.5,
    target_false_positive_rate: Annotated[float, Field(ge=0, lt=1)] = 0.01,
    max_stages: Iterations = 10,
    max_stumps: Iterations = 50,
) -> Cascade:
    """A Viola–Jones cascade: boosted stages, each cheap enough to reject most negatives
    early, trained one after the other on the positives and the negatives that all
    earlier stages let through.

    Each stage adds stumps (AdaBoost) until, with its threshold lowered to keep at least
    ``detection_rate`` of the positives, it passes at most ``false_positive_rate`` of
    its negatives (or it holds ``max_stumps``). Training stops when the whole cascade
    passes at most ``target_false_positive_rate`` of the negatives, when no negative is
    left, or after ``max_stages``.

    Parameters
    ----------
    train : Features (N, D) of two classes (the larger label is the object)
    detection_rate : share of positives each stage must keep
    false_positive_rate : share of its negatives a stage may pass
    target_false_positive_rate : when the cascade is done
    max_stages : most stages
    max_stumps : most stumps per stage

    Returns
    -------
    cascade : Cascade, with per stage the training negatives it rejected and the
        cascade's detection and false-positive rates after it

    References
    ----------
    P. Viola and M. Jones, "Robust real-time face detection", IJCV 57(2), 2004.
    """
    classes, signs = _two_classes(train.labels, "recognition.cascade")
    arrays = train_cascade(
        train.features,
        signs,
        detection_rate=detection_rate,
        false_positive_rate=false_positive_rate,
        target_false_positive_rate=target_false_positive_rate,
        max_stages=max_stages,
        max_stumps=max_stumps,
    )
    return CascadeModel(
        **arrays, classes=classes, width=train.features.shape[1], recipe=train.recipe
    )


@node("recognition.cascade_table", version=1)
def cascade_table(model: Cascade) -> Table:
    """One row per stage of a cascade: stumps, training negatives rejected, and the
    cascade's detection and false-positive rates on its training set after the stage.

    Parameters
    ----------
    model : a trained Cascade

    Returns
    -------
    table : columns stage, stumps, rejected, detection_rate, false_positive_rate
    """
    stages = len(model.stage_threshold)
    return {
        "stage": np.arange(stages),
        "stumps": np.bincount(model.stage, minlength=stages).astype(np.int64),
        "rejected": model.rejected.copy(),
        "detection_rate": model.detection_rate.copy(),
        "false_positive_rate": model.false_positive_rate.copy(),
    }
