"""Image retrieval by colour histograms: a gallery of samples and copies, ranked by distance."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, Descriptors, Float, node

from ..shared.params import Count, Seed
from ._histograms import Bins, Metric, colour_histogram, histogram_distances

__all__ = ["Gallery", "Retrieval", "gallery", "retrieve", "transformed_copies"]

COLOUR_SAMPLES = ("astronaut", "chelsea", "coffee", "rocket", "immunohistochemistry")


def transformed_copies(image: np.ndarray, count: int, rng: np.random.Generator) -> list:
    """Seeded copies a colour histogram should survive: mirrored, cropped (60–90 % of each
    side), rescaled in brightness (0.8–1.1) and a little noise (σ 0.02)."""
    copies = []
    rows, cols = image.shape[:2]
    for _ in range(count):
        copy = image[:, ::-1] if rng.random() < 0.5 else image
        h, w = (int(rows * rng.uniform(0.6, 0.9)), int(cols * rng.uniform(0.6, 0.9)))
        top, left = rng.integers(0, rows - h + 1), rng.integers(0, cols - w + 1)
        copy = copy[top : top + h, left : left + w] * rng.uniform(0.8, 1.1)
        copy = copy + rng.normal(0, 0.02, copy.shape)
        copies.append(np.clip(copy, 0, 1).astype(np.float32))
    return copies


class Gallery(NamedTuple):
    histograms: Descriptors
    labels: Array


@node("colour.gallery", version=1)
def gallery(
    *,
    copies: Annotated[int, Field(ge=1, le=50)] = 4,
    bins: Bins = 8,
    seed: Seed = 0,
) -> Gallery:
    """A retrieval gallery: scikit-image's colour samples and seeded transformed copies.

    Five pictures (astronaut, chelsea, coffee, rocket, immunohistochemistry)
    and ``copies`` copies of each (see :func:`transformed_copies`);
    each entry is its normalised joint colour histogram, labelled by its
    source picture.

    Parameters
    ----------
    copies : int
        Transformed copies per picture.
    bins : int
        Histogram bins per channel.
    seed : int
        Seed of the transformations.

    Returns
    -------
    histograms : (5 (copies + 1), bins³) float32
    labels : (5 (copies + 1),) int, the source picture's index
    """
    import skimage.data

    rng = np.random.default_rng(seed)
    rows, labels = [], []
    for label, name in enumerate(COLOUR_SAMPLES):
        image = (getattr(skimage.data, name)()[..., :3] / 255.0).astype(np.float32)
        for version in [image, *transformed_copies(image, copies, rng)]:
            rows.append(colour_histogram(version, bins).ravel())
            labels.append(label)
    return Gallery(np.array(rows, dtype=np.float32), np.array(labels))


class Retrieval(NamedTuple):
    precision: Float
    ranking: Array


@node("colour.retrieve", version=1)
def retrieve(
    histograms: Descriptors,
    labels: Array,
    *,
    metric: Metric = "chi2",
    k: Count = 4,
) -> Retrieval:
    r"""Rank the gallery for each entry as a query (leave one out); precision at ``k``.

    .. math:: P@k = \frac{1}{N} \sum_q \frac{|\{\text{k nearest of } q\} \cap
              \text{class}(q)|}{k}

    Parameters
    ----------
    histograms : (N, D) float32
        One flattened normalised histogram per gallery entry.
    labels : (N,) int
        The class of each entry.
    metric : {"euclidean", "chi2", "hellinger", "intersection"}
        Histogram distance used for ranking.
    k : int
        How many nearest entries count; less than N.

    Returns
    -------
    precision : float, the mean precision at k
    ranking : (N, N - 1) int, each query's other entries, nearest first
    """
    count = len(histograms)
    if labels.shape != (count,):
        raise ValueError(f"labels must have one entry per histogram ({count}), got {labels.shape}")
    if k >= count:
        raise ValueError(f"k ({k}) must be smaller than the gallery ({count} entries)")
    data = histograms.astype(np.float64)
    ranking = np.empty((count, count - 1), dtype=np.intp)
    for query in range(count):
        distance = histogram_distances(data[query], data, metric)
        distance[query] = np.inf
        ranking[query] = np.argsort(distance, kind="stable")[: count - 1]
    hits = labels[ranking[:, :k]] == labels[:, None]
    return Retrieval(float(hits.mean()), ranking)
