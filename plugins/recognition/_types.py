"""The recognition family's values: labelled sample sets and trained models.

Every value is a frozen dataclass of arrays (plus JSON scalars) so that it is
validated, cached on disk and sent to another process in the array encoding
like any other port value; nothing is pickled. A trained model remembers the
``recipe`` of the features it was trained on (a JSON text such as
``{"kind": "hog", "window": [25, 25], ...}``) so that a detector can compute
the same features on every window of an image.

::

    Samples    images (N, H, W) float32 in [0, 1], labels (N,) int64
    Features   features (N, D) float64, labels (N,) int64, recipe
    Bags       descriptors (M, D) float32, owner (M,) int64 image index, labels (N,)
    Subspace   mean (D,), basis (D, K) orthonormal, eigenvalues, recipe
    Classifier ─┬─ LinearClassifier   weights (K, D), bias (K,)        (SVM)
                ├─ StumpClassifier    feature, threshold, polarity, alpha (AdaBoost)
                ├─ NearestClassifier  samples (N, D), labels (N,)      (1-NN)
                └─ Cascade            stumps of every stage, stage thresholds, rejections
    Vocabulary words (K, D) float64 (k-means centres)
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar

import numpy as np

from graphvision import ArrayPort, PortValueError, RecordPort

__all__ = [
    "Bags",
    "BagsPort",
    "Cascade",
    "CascadeModel",
    "CascadePort",
    "Classifier",
    "ClassifierModel",
    "ClassifierPort",
    "DescriptorBags",
    "FeatureSet",
    "Features",
    "FeaturesPort",
    "LinearClassifier",
    "LinearClassifierPort",
    "LinearModel",
    "NearestClassifier",
    "NearestClassifierPort",
    "NearestModel",
    "SampleSet",
    "Samples",
    "SamplesPort",
    "StumpClassifier",
    "StumpClassifierPort",
    "StumpModel",
    "Subspace",
    "SubspaceModel",
    "SubspacePort",
    "Vocabulary",
    "VocabularyPort",
    "mosaic",
    "recipe_of",
    "stump_votes",
]


def recipe_of(text: str) -> dict[str, Any]:
    """The feature recipe (a dict) stored as JSON text in sets and models."""
    recipe: dict[str, Any] = json.loads(text)
    return recipe


def mosaic(images: np.ndarray, columns: int = 8) -> np.ndarray:
    """Images (N, H, W) side by side in rows of ``columns``, one black pixel apart, each
    stretched to [0, 1]: float32."""
    count, height, width = images.shape
    low = images.min(axis=(1, 2), keepdims=True)
    span = images.max(axis=(1, 2), keepdims=True) - low
    scaled = np.divide(images - low, span, out=np.zeros(images.shape), where=span > 0)
    rows = -(-count // columns)
    canvas = np.zeros((rows * (height + 1) - 1, min(count, columns) * (width + 1) - 1))
    for index, image in enumerate(scaled):
        r, c = divmod(index, columns)
        canvas[
            r * (height + 1) : r * (height + 1) + height, c * (width + 1) : c * (width + 1) + width
        ] = image
    return canvas.astype(np.float32)


def _array(owner: str, name: str, value: Any, dtype: type, ndim: int) -> np.ndarray:
    if not isinstance(value, np.ndarray) or value.dtype != dtype or value.ndim != ndim:
        got = f"{value.dtype} {value.shape}" if isinstance(value, np.ndarray) else type(value)
        raise PortValueError(
            f"{owner} '{name}' must be a {ndim}-D {np.dtype(dtype).name}, got {got}"
        )
    if value.dtype.kind == "f" and not np.isfinite(value).all():
        raise PortValueError(f"{owner} '{name}' must be finite")
    return value


def _same_length(what: str, **columns: np.ndarray) -> None:
    lengths = {name: len(column) for name, column in columns.items()}
    if len(set(lengths.values())) > 1:
        raise PortValueError(f"{what} columns must have equal lengths, got {lengths}")


@dataclass(frozen=True, eq=False)
class SampleSet:
    """N equally sized gray images with an integer class label each."""

    images: np.ndarray
    labels: np.ndarray

    def __len__(self) -> int:
        return len(self.images)


class SamplesPort(RecordPort):
    """A :class:`SampleSet`: images float32 (N, H, W) in [0, 1], labels int64 (N,), N ≥ 1."""

    value_class = SampleSet

    @classmethod
    def validate(cls, value: Any) -> SampleSet:
        value = super().validate(value)
        images = _array("Samples", "images", value.images, np.float32, 3)
        _array("Samples", "labels", value.labels, np.int64, 1)
        _same_length("Samples", images=images, labels=value.labels)
        if images.size == 0 or images.min() < 0 or images.max() > 1:
            raise PortValueError("Samples 'images' must be a non-empty stack with values in [0, 1]")
        return value

    @classmethod
    def preview(cls, value: SampleSet) -> np.ndarray | None:
        """The first 64 samples."""
        return mosaic(value.images[:64])

    @classmethod
    def summary(cls, value: SampleSet) -> str:
        classes = np.unique(value.labels).tolist()
        side = "×".join(map(str, value.images.shape[1:]))
        return f"Samples {len(value)} × {side}, classes {classes}"


@dataclass(frozen=True, eq=False)
class FeatureSet:
    """N feature vectors (rows) with a class label each, and the recipe that computed them."""

    features: np.ndarray
    labels: np.ndarray
    recipe: str = "{}"

    def __len__(self) -> int:
        return len(self.features)


class FeaturesPort(RecordPort):
    """A :class:`FeatureSet`: features float64 (N, D) finite, labels int64 (N,), recipe JSON."""

    value_class = FeatureSet

    @classmethod
    def validate(cls, value: Any) -> FeatureSet:
        value = super().validate(value)
        _array("Features", "features", value.features, np.float64, 2)
        _array("Features", "labels", value.labels, np.int64, 1)
        _same_length("Features", features=value.features, labels=value.labels)
        return value

    @classmethod
    def summary(cls, value: FeatureSet) -> str:
        return f"Features {value.features.shape[0]}×{value.features.shape[1]}"


@dataclass(frozen=True, eq=False)
class DescriptorBags:
    """Local descriptors of N images: row m of ``descriptors`` belongs to image ``owner[m]``."""

    descriptors: np.ndarray
    owner: np.ndarray
    labels: np.ndarray

    def __len__(self) -> int:
        return len(self.labels)


class BagsPort(RecordPort):
    """A :class:`DescriptorBags`: descriptors float32 (M, D), owner int64 (M,) in [0, N),
    labels int64 (N,)."""

    value_class = DescriptorBags

    @classmethod
    def validate(cls, value: Any) -> DescriptorBags:
        value = super().validate(value)
        _array("Bags", "descriptors", value.descriptors, np.float32, 2)
        owner = _array("Bags", "owner", value.owner, np.int64, 1)
        _array("Bags", "labels", value.labels, np.int64, 1)
        _same_length("Bags", descriptors=value.descriptors, owner=owner)
        if len(owner) and (owner.min() < 0 or owner.max() >= len(value.labels)):
            raise PortValueError(f"Bags 'owner' must index the {len(value.labels)} images")
        return value

    @classmethod
    def summary(cls, value: DescriptorBags) -> str:
        return f"Bags {len(value.descriptors)} descriptors of {len(value)} images"


@dataclass(frozen=True, eq=False)
class SubspaceModel:
    r"""A linear subspace :math:`x \approx U y + \mu`: ``mean`` μ (D,), ``basis`` U (D, K)
    with orthonormal columns, ``eigenvalues`` λ of the covariance in decreasing order
    (all of them, so that the residual :math:`\varepsilon(m) = \sum_{j>m} \lambda_j` is
    known for every m), ``method`` (``covariance`` or ``gram``) and the feature ``recipe``."""

    mean: np.ndarray
    basis: np.ndarray
    eigenvalues: np.ndarray
    method: str = "covariance"
    recipe: str = "{}"


class SubspacePort(RecordPort):
    """A :class:`SubspaceModel` (a trained PCA subspace)."""

    value_class = SubspaceModel

    @classmethod
    def validate(cls, value: Any) -> SubspaceModel:
        value = super().validate(value)
        mean = _array("Subspace", "mean", value.mean, np.float64, 1)
        basis = _array("Subspace", "basis", value.basis, np.float64, 2)
        _array("Subspace", "eigenvalues", value.eigenvalues, np.float64, 1)
        if basis.shape[0] != len(mean) or basis.shape[1] == 0:
            raise PortValueError(
                f"Subspace 'basis' must be {len(mean)}×K with K ≥ 1, got {basis.shape}"
            )
        return value

    @classmethod
    def preview(cls, value: SubspaceModel) -> np.ndarray | None:
        """The mean and the first 15 basis vectors as images (eigenfaces), for pixel
        subspaces."""
        window = recipe_of(value.recipe).get("window")
        if window is None or len(value.mean) != window[0] * window[1]:
            return None
        vectors = np.column_stack([value.mean, value.basis[:, :15]]).T
        return mosaic(vectors.reshape(-1, window[0], window[1]))

    @classmethod
    def summary(cls, value: SubspaceModel) -> str:
        return f"Subspace {value.basis.shape[1]} of {value.basis.shape[0]} dimensions"


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


class VocabularyPort(ArrayPort):
    """Visual words: k-means centres, float64 (K, D), finite."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 K×D cluster centres"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if not np.isfinite(value).all():
            raise PortValueError("Vocabulary words must be finite")
        return value


Samples = Annotated[SampleSet, SamplesPort]
Features = Annotated[FeatureSet, FeaturesPort]
Bags = Annotated[DescriptorBags, BagsPort]
Subspace = Annotated[SubspaceModel, SubspacePort]
Classifier = Annotated[ClassifierModel, ClassifierPort]
LinearClassifier = Annotated[LinearModel, LinearClassifierPort]
StumpClassifier = Annotated[StumpModel, StumpClassifierPort]
NearestClassifier = Annotated[NearestModel, NearestClassifierPort]
Cascade = Annotated[CascadeModel, CascadePort]
Vocabulary = Annotated[np.ndarray, VocabularyPort]
