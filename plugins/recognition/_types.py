"""The recognition family's values: labelled sample sets and trained models.

Every value is a frozen dataclass of arrays (plus JSON scalars) so that it is
validated, cached on disk and sent to another process in the array encoding
like any other port value; nothing is pickled. A trained model remembers the
``recipe`` of the features it was trained on (a JSON text such as
``{"kind": "hog", "window": [25, 25], ...}``) so that a detector can compute
the same features on every window of an image. The classifiers (the tree below
from ``Classifier``) are in ``_models``.

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
from typing import Annotated, Any

import numpy as np

from graphvision import ArrayPort, PortValueError, RecordPort

__all__ = [
    "Bags",
    "BagsPort",
    "DescriptorBags",
    "FeatureSet",
    "Features",
    "FeaturesPort",
    "SampleSet",
    "Samples",
    "SamplesPort",
    "Subspace",
    "SubspaceModel",
    "SubspacePort",
    "Vocabulary",
    "VocabularyPort",
    "mosaic",
    "recipe_of",
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
Vocabulary = Annotated[np.ndarray, VocabularyPort]
