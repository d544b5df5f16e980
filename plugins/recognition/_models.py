"""The recognition family's trained classifiers (see :mod:`._types` for the tree of values):
linear (SVM), decision stumps (AdaBoost), 1-nearest-neighbour and Viola–Jones cascades,
each a frozen dataclass of arrays with its port."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any, ClassVar

import numpy as np

from graphvision import PortValueError, RecordPort

from ._types import _array

__all__ = [
    "Cascade",
    "CascadeModel",
    "CascadePort",
    "Classifier",
    "ClassifierModel",
    "ClassifierPort",
    "LinearClassifier",
    "LinearClassifierPort",
    "LinearModel",
    "NearestClassifier",
    "NearestClassifierPort",
    "NearestModel",
    "StumpClassifier",
    "StumpClassifierPort",
    "StumpModel",
    "stump_votes",
]


class ClassifierModel:
    """Base of trained classifiers: ``classes`` (C,) int64 and the feature ``recipe``.

    :meth:`decision` gives one score per sample for two classes (positive means
    ``classes[1]``) or one column per class; :meth:`predict` the labels.
    """

    classes: np.ndarray
    recipe: str

    def decision(self, features: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def predict(self, features: np.ndarray) -> np.ndarray:
        """Labels of the rows of ``features``."""
        score = self.decision(features)
        if score.ndim == 1:
            return self.classes[(score > 0).astype(np.intp)]
        return self.classes[np.argmax(score, axis=1)]

    def check_width(self, features: np.ndarray, width: int) -> None:
        if features.shape[1] != width:
            raise ValueError(
                f"the classifier was trained on {width} features, got {features.shape[1]} "
                "(were the test features computed with the same node and parameters?)"
            )


@dataclass(frozen=True, eq=False)
class LinearModel(ClassifierModel):
    """Linear scores ``features @ weights.T + bias``: one row for two classes, else one
    row per class (one-vs-rest)."""

    weights: np.ndarray
    bias: np.ndarray
    classes: np.ndarray
    recipe: str = "{}"

    def decision(self, features: np.ndarray) -> np.ndarray:
        self.check_width(features, self.weights.shape[1])
        score = features @ self.weights.T + self.bias
        return score[:, 0] if len(self.classes) == 2 else score


@dataclass(frozen=True, eq=False)
class StumpModel(ClassifierModel):
    r"""A boosted sum of decision stumps :math:`H(x) = \sum_t \alpha_t h_t(x)`,
    :math:`h_t(x) = p_t\,\mathrm{sign}(x_{f_t} - \theta_t)` with ``feature`` f, ``threshold``
    θ, ``polarity`` p ∈ {−1, +1} and weight ``alpha`` α; two ``classes``. ``width`` is the
    number of feature columns it was trained on."""

    feature: np.ndarray
    threshold: np.ndarray
    polarity: np.ndarray
    alpha: np.ndarray
    classes: np.ndarray
    width: int = 0
    recipe: str = "{}"

    def decision(self, features: np.ndarray) -> np.ndarray:
        self.check_width(features, self.width)
        return stump_votes(features, self.feature, self.threshold, self.polarity) @ self.alpha


def stump_votes(
    features: np.ndarray, feature: np.ndarray, threshold: np.ndarray, polarity: np.ndarray
) -> np.ndarray:
    """±1 votes (N, T) of T stumps: ``polarity`` where the feature exceeds ``threshold``."""
    return np.where(features[:, feature] > threshold, polarity, -polarity)


@dataclass(frozen=True, eq=False)
class NearestModel(ClassifierModel):
    """1-nearest-neighbour: the training ``samples`` (N, D) and their ``labels``."""

    samples: np.ndarray
    labels: np.ndarray
    classes: np.ndarray
    recipe: str = "{}"

    def decision(self, features: np.ndarray) -> np.ndarray:
        """Minus the squared distance to the nearest training sample of each class."""
        self.check_width(features, self.samples.shape[1])
        distance = (
            (features**2).sum(axis=1)[:, None]
            - 2.0 * features @ self.samples.T
            + (self.samples**2).sum(axis=1)[None, :]
        )
        per_class = np.stack(
            [distance[:, self.labels == c].min(axis=1) for c in self.classes], axis=1
        )
        return -per_class if len(self.classes) > 2 else per_class[:, 0] - per_class[:, 1]


@dataclass(frozen=True, eq=False)
class CascadeModel(ClassifierModel):
    """A Viola–Jones cascade: stage ``stage[t]`` owns stump t; a window passes stage s when
    its stage sum reaches ``stage_threshold[s]``; it is positive when it passes every stage.
    ``rejected[s]`` counts the training negatives that stage s rejected,
    ``false_positive_rate[s]`` and ``detection_rate[s]`` are the cascade's rates on the
    training set after stage s."""

    feature: np.ndarray
    threshold: np.ndarray
    polarity: np.ndarray
    alpha: np.ndarray
    stage: np.ndarray
    stage_threshold: np.ndarray
    rejected: np.ndarray
    detection_rate: np.ndarray
    false_positive_rate: np.ndarray
    classes: np.ndarray
    width: int = 0
    recipe: str = "{}"

    def stage_scores(self, features: np.ndarray) -> np.ndarray:
        """(N, S) stage sums minus stage thresholds."""
        self.check_width(features, self.width)
        votes = stump_votes(features, self.feature, self.threshold, self.polarity) * self.alpha
        stages = len(self.stage_threshold)
        sums = np.zeros((len(features), stages))
        for s in range(stages):
            sums[:, s] = votes[:, self.stage == s].sum(axis=1)
        return sums - self.stage_threshold

    def decision(self, features: np.ndarray) -> np.ndarray:
        """The last stage's margin for windows that pass every stage, else the first failure's."""
        scores = self.stage_scores(features)
        failed = scores < 0
        first = np.where(failed.any(axis=1), failed.argmax(axis=1), scores.shape[1] - 1)
        margin = scores[np.arange(len(scores)), first]
        return np.where(failed.any(axis=1), np.minimum(margin, -1e-12), np.maximum(margin, 1e-12))


_MODELS: dict[str, type[ClassifierModel]] = {
    "linear": LinearModel,
    "stumps": StumpModel,
    "nearest": NearestModel,
    "cascade": CascadeModel,
}


class ClassifierPort(RecordPort):
    """Any trained classifier (:class:`ClassifierModel`): linear, stumps, 1-NN or cascade."""

    value_class: ClassVar[type] = ClassifierModel

    @classmethod
    def validate(cls, value: Any) -> Any:
        value = super().validate(value)
        _array(cls.type_name(), "classes", value.classes, np.int64, 1)
        if len(value.classes) < 2:
            raise PortValueError(f"{cls.type_name()} needs at least two classes")
        return value

    @classmethod
    def encode(cls, value: Any) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays, meta = super().encode(value)
        kind = next(name for name, model in _MODELS.items() if type(value) is model)
        return arrays, {**meta, "model": kind}

    @classmethod
    def decode(cls, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> Any:
        fields = {name: item for name, item in meta.items() if name != "model"}
        return _MODELS[meta["model"]](**arrays, **fields)

    @classmethod
    def summary(cls, value: Any) -> str:
        return f"{type(value).__name__} classes {value.classes.tolist()}"


class LinearClassifierPort(ClassifierPort):
    """A :class:`LinearModel` (a linear SVM)."""

    value_class = LinearModel


class StumpClassifierPort(ClassifierPort):
    """A :class:`StumpModel` (discrete AdaBoost over decision stumps)."""

    value_class = StumpModel


class NearestClassifierPort(ClassifierPort):
    """A :class:`NearestModel` (1-nearest-neighbour)."""

    value_class = NearestModel


class CascadePort(ClassifierPort):
    """A :class:`CascadeModel` (a Viola–Jones cascade of boosted stages)."""

    value_class = CascadeModel


Classifier = Annotated[ClassifierModel, ClassifierPort]


LinearClassifier = Annotated[LinearModel, LinearClassifierPort]


StumpClassifier = Annotated[StumpModel, StumpClassifierPort]


NearestClassifier = Annotated[NearestModel, NearestClassifierPort]


Cascade = Annotated[CascadeModel, CascadePort]
