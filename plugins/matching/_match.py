"""Nearest-neighbour matching with the ratio test and symmetric matches."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from graphvision import Conformance, Descriptors, Matches, MatchSet, node

__all__ = ["match", "nearest_two"]

_BLOCK = 2048


def _brute(query: np.ndarray, train: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two nearest ``train`` rows of each ``query`` row, and the nearest query row of each
    ``train`` row, from one pass over blocks of :math:`\\|a\\|^2 + \\|b\\|^2 - 2 a \\cdot b`."""
    from ._kernels import two_smallest

    a = query.astype(np.float32)
    b = train.astype(np.float32)
    b_norm = (b * b).sum(axis=1)
    index = np.empty((len(a), 2), np.int64)
    value = np.empty((len(a), 2), np.float32)
    column_value = np.full(len(b), np.inf)
    column_index = np.zeros(len(b), np.int64)
    for start in range(0, len(a), _BLOCK):
        block = a[start : start + _BLOCK]
        squared = (block * block).sum(axis=1)[:, None] + b_norm[None, :] - 2.0 * block @ b.T
        stop = start + len(block)
        two_smallest(
            squared, start, index[start:stop], value[start:stop], column_value, column_index
        )
    return index, np.sqrt(np.maximum(value, 0.0)).astype(np.float64), column_index


def nearest_two(
    query: np.ndarray, train: np.ndarray, method: str = "brute"
) -> tuple[np.ndarray, np.ndarray]:
    """Indices and Euclidean distances of the two nearest ``train`` rows of each ``query`` row.

    ``brute`` computes :math:`\\|a\\|^2 + \\|b\\|^2 - 2 a \\cdot b` in blocks
    (one matrix product each) and keeps each row's two smallest in a compiled
    pass; ``kdtree`` uses ``scipy.spatial.cKDTree``. With one train row, the
    second neighbour has infinite distance.
    """
    if method == "kdtree":
        from scipy.spatial import cKDTree

        k = min(2, len(train))
        distance, index = cKDTree(train).query(query, k=k)
        distance, index = distance.reshape(len(query), k), index.reshape(len(query), k)
        if k == 2:
            return index, distance
        return np.column_stack([index[:, 0], index[:, 0]]), np.column_stack(
            [distance[:, 0], np.full(len(distance), np.inf)]
        )
    index, distance, _ = _brute(query, train)
    if len(train) == 1:
        index[:, 1] = index[:, 0]
    return index, distance


@node("matching.match", version=1, conformance=Conformance("recall", 1.0))
def match(
    a: Descriptors,
    b: Descriptors,
    *,
    ratio: Annotated[float, Field(gt=0, le=1)] = 0.8,
    symmetric: bool = True,
    method: Literal["brute", "kdtree"] = "brute",
) -> Matches:
    r"""Match descriptors of ``a`` to ``b`` by Euclidean nearest neighbour.

    * **ratio test** (Lowe): keep a match when the nearest distance is below
      ``ratio`` times the second nearest — distinctive matches only (1
      disables it);
    * **symmetric**: keep ``(i, j)`` only when ``i`` is also the nearest
      neighbour of ``j`` in ``a``.

    ``brute`` is exact and fast with BLAS for a few thousand descriptors;
    ``kdtree`` helps for low-dimensional descriptors or very large sets.

    Parameters
    ----------
    a, b : Descriptors
        Descriptors of the first and of the second image.
    ratio : float
        Lowe's ratio: nearest distance below ``ratio`` times the second nearest.
    symmetric : bool
        Keep only mutual nearest neighbours.
    method : {"brute", "kdtree"}
        Exact search by matrix product, or with a k-d tree.

    Returns
    -------
    matches : pairs ``(i, j)`` sorted by distance, with their distances

    References
    ----------
    .. [1] D. G. Lowe, "Distinctive image features from scale-invariant
       keypoints", IJCV 60(2), 2004, section 7.1.
    """
    if a.shape[1:] != b.shape[1:]:
        raise ValueError(f"descriptors have different lengths: {a.shape[1]} and {b.shape[1]}")
    if len(a) == 0 or len(b) == 0:
        return MatchSet(np.zeros((0, 2), np.int64), np.zeros(0))
    if method == "brute":  # one pass gives both directions
        index, distance, back = _brute(a, b)
    else:
        index, distance = nearest_two(a, b, method)
        back = nearest_two(b, a, method)[0][:, 0] if symmetric else index[:, 0]
    keep = distance[:, 0] < ratio * distance[:, 1] if ratio < 1 else np.ones(len(a), bool)
    if symmetric:
        keep &= back[index[:, 0]] == np.arange(len(a))
    rows = np.flatnonzero(keep)
    order = np.argsort(distance[rows, 0], kind="stable")
    rows = rows[order]
    return MatchSet(
        np.column_stack([rows, index[rows, 0]]).astype(np.int64),
        distance[rows, 0].astype(np.float64),
    )
