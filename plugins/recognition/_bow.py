"""The bag-of-words model (seed: "Recognition using local features: Bag of words model"):
dense SIFT descriptors, a k-means vocabulary of visual words, and normalised histograms of
word occurrences."""

from __future__ import annotations

import json
from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import KeypointSet, node

from ..features import describe_sift
from ..shared.checks import at_most_values
from ..shared.params import Count, Iterations, Positive, Seed
from ._types import (
    Bags,
    DescriptorBags,
    Features,
    FeatureSet,
    Samples,
    Vocabulary,
)

__all__ = ["bag_of_words", "dense_sift", "fit_kmeans", "kmeans", "nearest_word"]


@node("recognition.dense_sift", version=1)
def dense_sift(
    samples: Samples,
    *,
    step: Count = 8,
    scale: Positive = 2.0,
    margin: Annotated[int, Field(ge=0)] = 8,
    upsample: bool = True,
) -> Bags:
    """SIFT descriptors (``features.describe_sift``) on a regular grid of every sample: one
    keypoint every ``step`` pixels, ``margin`` pixels from the border, at scale σ =
    ``scale`` and orientation 0 (textures keep their orientation).

    Parameters
    ----------
    samples : Samples (N, H, W)
    step : grid spacing in pixels
    scale : keypoint scale σ in pixels (the descriptor spans about 12σ)
    margin : distance of the grid from the border
    upsample : build the SIFT pyramid from the image doubled in size (Lowe's default)

    Returns
    -------
    bags : Bags (128-d descriptors, the sample each belongs to, the samples' labels)

    References
    ----------
    D. G. Lowe, "Distinctive image features from scale-invariant keypoints", IJCV 60(2),
    2004.
    """
    height, width = samples.images.shape[1:]
    ys = np.arange(margin, height - margin, step, dtype=np.float64)
    xs = np.arange(margin, width - margin, step, dtype=np.float64)
    if len(ys) == 0 or len(xs) == 0:
        raise ValueError(
            f"no grid point fits in a {height}×{width} sample with margin {margin}: "
            "use a smaller margin"
        )
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    count = len(grid)
    keypoints = KeypointSet(grid, np.full(count, scale), np.zeros(count), np.ones(count))
    descriptors = [describe_sift(image, keypoints, upsample=upsample) for image in samples.images]
    owner = np.repeat(np.arange(len(samples.images), dtype=np.int64), count)
    return DescriptorBags(
        np.concatenate(descriptors).astype(np.float32), owner, samples.labels.copy()
    )


def _squared_distances(points: np.ndarray, centres: np.ndarray) -> np.ndarray:
    return np.maximum(
        (points**2).sum(axis=1)[:, None]
        - 2.0 * points @ centres.T
        + (centres**2).sum(axis=1)[None, :],
        0.0,
    )


def nearest_word(points: np.ndarray, words: np.ndarray) -> np.ndarray:
    """Index of the closest word (Euclidean) of each row of ``points``."""
    return np.argmin(_squared_distances(points, words), axis=1)


def fit_kmeans(points: np.ndarray, k: int, iterations: int, seed: int) -> np.ndarray:
    r"""k cluster centres minimising :math:`\sum_i \min_j \|x_i - c_j\|^2` (Lloyd's
    algorithm from a greedy k-means++ start, seeded: each new centre is the best of
    2 + ln k candidates drawn with probability ∝ D², the squared distance to the
    nearest centre so far): assign each point to its nearest centre,
    move each centre to the mean of its points, until no assignment changes. A centre
    left without points moves to the point farthest from its own centre.

    References
    ----------
    D. Arthur and S. Vassilvitskii, "k-means++: the advantages of careful seeding",
    SODA 2007.
    """
    rng = np.random.default_rng(seed)
    centres = np.empty((k, points.shape[1]))
    centres[0] = points[rng.integers(len(points))]
    closest = _squared_distances(points, centres[:1])[:, 0]
    trials = 2 + int(np.log(k))
    for j in range(1, k):
        total = closest.sum()
        if total > 0:
            candidates = rng.choice(len(points), trials, p=closest / total)
        else:
            candidates = rng.integers(len(points), size=trials)
        # greedy k-means++: of a few candidates drawn ∝ D², keep the one leaving least
        reach = np.minimum(closest[None, :], _squared_distances(points[candidates], points))
        best = int(np.argmin(reach.sum(axis=1)))
        centres[j] = points[candidates[best]]
        closest = reach[best]
    assignment = np.full(len(points), -1)
    for _ in range(iterations):
        distances = _squared_distances(points, centres)
        new = np.argmin(distances, axis=1)
        if np.array_equal(new, assignment):
            break
        assignment = new
        members = np.zeros((k, len(points)))
        members[assignment, np.arange(len(points))] = 1.0
        counts = members.sum(axis=1)
        sums = members @ points
        empty = counts == 0
        centres[~empty] = sums[~empty] / counts[~empty, None]
        if empty.any():
            far = np.argsort(-distances[np.arange(len(points)), assignment])[: empty.sum()]
            centres[empty] = points[far]
    return centres


MAX_ASSIGNMENTS = 2**26
"""Most words × descriptors for k-means: each Lloyd iteration makes two arrays of that
many float64 values (distances and memberships), 512 MB each at this maximum."""


@node(
    "recognition.kmeans",
    version=2,
    check=at_most_values("words", "max_descriptors", limit=MAX_ASSIGNMENTS),
)
def kmeans(
    bags: Bags,
    *,
    words: Annotated[int, Field(ge=1, le=4096)] = 50,
    iterations: Iterations = 50,
    max_descriptors: Annotated[int, Field(ge=0, le=1_000_000)] = 5000,
    seed: Seed = 0,
) -> Vocabulary:
    """A vocabulary of visual words: the k-means centres of the training descriptors
    (similar descriptors form clusters; each centre is a word).

    Parameters
    ----------
    bags : Bags of training descriptors
    words : k, the number of words
    iterations : most Lloyd iterations
    max_descriptors : cluster a random subset (seeded) of at most this many descriptors
        (0: all of them); words × descriptors is at most 2^26
    seed : seed of the subset and of the k-means++ start

    Returns
    -------
    vocabulary : (words, D) float64

    References
    ----------
    J. Sivic and A. Zisserman, "Video Google: a text retrieval approach to object
    matching in videos", ICCV 2003.
    """
    if words > len(bags.descriptors):
        raise ValueError(
            f"recognition.kmeans cannot make {words} words from {len(bags.descriptors)} "
            "descriptors: ask for fewer words or give more descriptors"
        )
    points = bags.descriptors.astype(np.float64)
    if 0 < max_descriptors < len(points):
        chosen = np.random.default_rng(seed).choice(len(points), max_descriptors, replace=False)
        points = points[np.sort(chosen)]
    if words * len(points) > MAX_ASSIGNMENTS:
        raise ValueError(
            f"{words} words × {len(points):,} descriptors would make {words * len(points):,} "
            f"distances per iteration ({words * len(points) * 8 / 2**30:.1f} GiB), at most "
            f"{MAX_ASSIGNMENTS:,}: lower words or max_descriptors"
        )
    return fit_kmeans(points, words, iterations, seed)


@node("recognition.bag_of_words", version=1)
def bag_of_words(bags: Bags, vocabulary: Vocabulary) -> Features:
    """Each image as the normalised histogram of its descriptors' nearest words (sums to 1;
    all zeros for an image without descriptors).

    Parameters
    ----------
    bags : Bags of the images to describe
    vocabulary : words from ``recognition.kmeans`` (same descriptor length)

    Returns
    -------
    features : Features (N, words) with the images' labels
    """
    if bags.descriptors.shape[1] != vocabulary.shape[1]:
        raise ValueError(
            f"the vocabulary's words have {vocabulary.shape[1]} dimensions, the descriptors "
            f"{bags.descriptors.shape[1]}"
        )
    words = len(vocabulary)
    word = nearest_word(bags.descriptors.astype(np.float64), vocabulary)
    counts = np.bincount(bags.owner * words + word, minlength=len(bags) * words)
    histograms = counts.reshape(len(bags), words).astype(np.float64)
    totals = histograms.sum(axis=1, keepdims=True)
    histograms = np.divide(histograms, totals, out=np.zeros_like(histograms), where=totals > 0)
    recipe = json.dumps({"kind": "bow", "words": words})
    return FeatureSet(histograms, bags.labels.copy(), recipe)
