"""A linear support vector machine, solved in the primal (seed: "train a person/nonperson
classifier in a linear SVM")."""

from __future__ import annotations

import numpy as np

from graphvision import node

from ..shared.params import Iterations, Positive
from ._models import LinearClassifier, LinearModel
from ._subspace import check_classes
from ._types import Features

__all__ = ["fit_linear_svm", "linear_svm"]


def fit_linear_svm(
    features: np.ndarray, signs: np.ndarray, C: float, max_iterations: int = 1000
) -> tuple[np.ndarray, float]:
    r"""Weights w and bias b minimising the L2-regularised squared hinge loss

    .. math:: \tfrac12 \|w\|^2 + C \sum_i \max(0,\ 1 - y_i (w^T x_i + b))^2,
              \qquad y_i \in \{-1, +1\}

    (the loss scikit-learn's ``LinearSVC`` minimises by default, without a
    penalty on b). It is convex and continuously differentiable, so L-BFGS
    reaches its minimum with the exact gradient

    .. math:: \nabla_w = w - 2C \sum_{i \in A} y_i m_i x_i, \quad
              \partial_b = -2C \sum_{i \in A} y_i m_i, \quad
              m_i = 1 - y_i (w^T x_i + b),\ A = \{i : m_i > 0\}.

    Deterministic: no random order, no seed.
    """
    from scipy.optimize import minimize

    dimension = features.shape[1]

    def objective(wb: np.ndarray) -> tuple[float, np.ndarray]:
        w, b = wb[:dimension], wb[dimension]
        margin = 1.0 - signs * (features @ w + b)
        active = margin > 0
        slack = np.where(active, margin, 0.0)
        loss = 0.5 * w @ w + C * slack @ slack
        pull = 2.0 * C * signs * slack
        gradient = np.concatenate([w - features.T @ pull, [-pull.sum()]])
        return float(loss), gradient

    found = minimize(
        objective,
        np.zeros(dimension + 1),
        jac=True,
        method="L-BFGS-B",
        options={"maxiter": max_iterations, "gtol": 1e-8},
    )
    return found.x[:dimension], float(found.x[dimension])


@node("recognition.linear_svm", version=1)
def linear_svm(
    train: Features,
    *,
    C: Positive = 1.0,
    max_iterations: Iterations = 1000,
) -> LinearClassifier:
    r"""A linear SVM: the hyperplane :math:`w^T x + b = 0` of maximal margin, soft margins
    traded against :math:`\|w\|` by C (squared hinge loss, see :func:`fit_linear_svm`).

    Two classes give one hyperplane (positive scores mean the larger label); more
    classes give one hyperplane per class, each against the rest, and the class of
    the largest score wins. Written here rather than wrapping scikit-learn's
    ``LinearSVC`` (an optional extra): the primal problem is smooth, so scipy's
    L-BFGS solves it in a few lines, deterministically.

    Parameters
    ----------
    train : Features (N, D) of at least two classes
    C : cost of margin violations (larger fits the training set more tightly)
    max_iterations : L-BFGS iterations per hyperplane

    Returns
    -------
    classifier : LinearClassifier (weights (K, D), bias (K,), classes)

    References
    ----------
    C. Cortes and V. Vapnik, "Support-vector networks", Machine Learning 20, 1995.
    """
    classes = check_classes(train.labels, "recognition.linear_svm")
    targets = classes[1:] if len(classes) == 2 else classes
    weights, biases = [], []
    for positive in targets:
        signs = np.where(train.labels == positive, 1.0, -1.0)
        w, b = fit_linear_svm(train.features, signs, C, max_iterations)
        weights.append(w)
        biases.append(b)
    return LinearModel(np.array(weights), np.array(biases), classes, train.recipe)
