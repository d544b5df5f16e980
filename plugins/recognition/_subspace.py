"""Subspace methods (seed: "Learning natural coordinate systems by subspace methods"):
PCA through the covariance matrix, dual PCA through the Gram matrix, projection,
reconstruction, the residual ε(m), and 1-nearest-neighbour classification."""

from __future__ import annotations

import json
from typing import Literal

import numpy as np

from graphvision import Array, node

from ..shared.params import Count
from ._models import NearestClassifier, NearestModel
from ._types import Features, FeatureSet, Subspace, SubspaceModel, recipe_of

__all__ = [
    "fit_pca",
    "nearest_neighbour",
    "pca",
    "project",
    "reconstruction_error",
    "residual",
]


def check_classes(labels: np.ndarray, what: str) -> np.ndarray:
    """The sorted classes of ``labels``; a ValueError when fewer than two."""
    classes = np.unique(labels)
    if len(classes) < 2:
        raise ValueError(
            f"{what} needs training samples of at least two classes, got only class "
            f"{classes.tolist()} ({len(labels)} samples)"
        )
    return classes.astype(np.int64)


def fit_pca(
    data: np.ndarray, components: int, method: Literal["auto", "covariance", "gram"] = "auto"
) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    r"""Mean, basis (D, K), all non-zero eigenvalues and the method used.

    With centred data :math:`X` (D×N, one sample per column) the covariance is
    :math:`\Sigma = \frac{1}{N-1} X X^T` and its eigenvectors are the basis.
    Dual PCA decomposes the N×N Gram matrix :math:`G = \frac{1}{N-1} X^T X = V
    \Lambda V^T` instead (cheaper when D > N): it has the same non-zero eigenvalues
    and :math:`U = X V \Lambda^{-1/2} / \sqrt{N-1}`. ``auto`` uses the Gram
    matrix when D > N. Each basis vector's sign is fixed so that its largest
    component is positive (the two methods then agree exactly, up to round-off).
    """
    count, dimension = data.shape
    mean = data.mean(axis=0)
    centred = data - mean
    if method == "auto":
        method = "gram" if dimension > count else "covariance"
    if method == "covariance":
        values, vectors = np.linalg.eigh(centred.T @ centred / (count - 1))
        order = np.argsort(values)[::-1]
        values, basis = values[order], vectors[:, order]
    else:
        values, vectors = np.linalg.eigh(centred @ centred.T / (count - 1))
        order = np.argsort(values)[::-1]
        values, vectors = values[order], vectors[:, order]
        keep = values > values[0] * 1e-12
        basis = centred.T @ vectors[:, keep] / np.sqrt(values[keep] * (count - 1))
        values = values[keep]
    nonzero = values > max(values[0], 0) * 1e-12
    values = values[nonzero]
    if components > len(values):
        raise ValueError(
            f"asked for {components} components, but the {count} training samples span only "
            f"{len(values)} dimensions (at most N - 1 = {count - 1})"
        )
    basis = basis[:, :components]
    signs = np.sign(basis[np.abs(basis).argmax(axis=0), np.arange(components)])
    return mean, basis * signs, values, method


@node("recognition.pca", version=1)
def pca(
    train: Features,
    *,
    components: Count = 20,
    method: Literal["auto", "covariance", "gram"] = "auto",
) -> Subspace:
    r"""PCA subspace of the training features: the directions of largest variance.

    The variance of a projection :math:`a = u^T (x - \mu)` is :math:`u^T \Sigma u`,
    maximised by the eigenvectors of :math:`\Sigma` of the largest eigenvalues;
    dual PCA reaches the same subspace through the Gram matrix when the
    dimension exceeds the number of samples (see :func:`fit_pca`).

    Parameters
    ----------
    train : Features (N, D); labels are ignored
    components : K, the number of basis vectors kept
    method : ``covariance``, ``gram`` (dual PCA) or ``auto`` (gram when D > N)

    Returns
    -------
    subspace : Subspace (mean, basis D×K, all eigenvalues)

    References
    ----------
    M. Turk and A. Pentland, "Eigenfaces for recognition", J. Cognitive
    Neuroscience 3(1), 1991.
    """
    if len(train.features) < 2:
        raise ValueError(f"PCA needs at least 2 training samples, got {len(train.features)}")
    mean, basis, values, used = fit_pca(train.features, components, method)
    return SubspaceModel(mean, basis, values, used, train.recipe)


@node("recognition.project", version=1)
def project(features: Features, subspace: Subspace) -> Features:
    r"""Coordinates in the subspace: :math:`y = U^T (x - \mu)`.

    Parameters
    ----------
    features : Features (N, D)
    subspace : Subspace of dimension D

    Returns
    -------
    projected : Features (N, K), labels kept
    """
    _check_dimension(features, subspace)
    projected = (features.features - subspace.mean) @ subspace.basis
    recipe = json.dumps({**recipe_of(features.recipe), "projected": subspace.basis.shape[1]})
    return FeatureSet(projected, features.labels.copy(), recipe)


def _check_dimension(features: FeatureSet, subspace: SubspaceModel) -> None:
    if features.features.shape[1] != len(subspace.mean):
        raise ValueError(
            f"the subspace has dimension {len(subspace.mean)}, the features "
            f"{features.features.shape[1]}"
        )


def reconstruction_error(data: np.ndarray, mean: np.ndarray, basis: np.ndarray) -> np.ndarray:
    r"""Squared distance from the subspace :math:`\|x - (U U^T (x - \mu) + \mu)\|^2` per row."""
    centred = data - mean
    coordinates = centred @ basis
    return np.maximum((centred**2).sum(axis=1) - (coordinates**2).sum(axis=1), 0.0)


@node("recognition.residual", version=1)
def residual(features: Features, subspace: Subspace) -> Array:
    r"""Distance from the subspace: the squared reconstruction error of each sample,
    :math:`\|x - \hat x\|^2` with :math:`\hat x = U y + \mu`. Small for samples of the
    category the subspace was built from (seed: "Detection by distance from subspace").

    Averaged over the training set it equals (× (N−1)/N) the eigenvalues left out,
    :math:`\varepsilon(m) = \sum_{j>m} \lambda_j`.

    Parameters
    ----------
    features : Features (N, D)
    subspace : Subspace of dimension D

    Returns
    -------
    error : (N,) float64
    """
    _check_dimension(features, subspace)
    return reconstruction_error(features.features, subspace.mean, subspace.basis)


@node("recognition.nearest_neighbour", version=1)
def nearest_neighbour(train: Features) -> NearestClassifier:
    """A 1-nearest-neighbour classifier: a sample takes the label of the closest training
    sample (Euclidean distance; seed: "We select the one with minimal distance").

    Parameters
    ----------
    train : Features (N, D) of at least two classes

    Returns
    -------
    classifier : NearestClassifier (keeps the training samples)
    """
    classes = check_classes(train.labels, "recognition.nearest_neighbour")
    return NearestModel(train.features.copy(), train.labels.copy(), classes, train.recipe)
