"""Labelled sample sets from the data shipped with scikit-image (nothing downloads)."""

from __future__ import annotations

import json
from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import node

from .._checks import to_float_image
from ._types import Features, FeatureSet, Samples, SampleSet

__all__ = [
    "FACE",
    "NON_FACE",
    "Split",
    "combine",
    "lfw_faces",
    "negative_patches",
    "pixels",
    "stratified_split",
    "texture_patches",
]

FACE = 1
NON_FACE = 0
Texture = Literal["brick", "grass", "gravel"]
FaceFree = Literal["brick", "grass", "gravel", "coins", "page", "text", "moon", "checkerboard"]


class Split(NamedTuple):
    train: Samples
    test: Samples


def _frozen(images: np.ndarray, labels: np.ndarray) -> SampleSet:
    return SampleSet(np.ascontiguousarray(images, np.float32), np.asarray(labels, np.int64))


def stratified_split(
    labels: np.ndarray, test_fraction: float, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """Indices (train, test): ``round(test_fraction · n_c)`` random members of each class c
    go to the test side, the rest to training (seeded, sorted)."""
    rng = np.random.default_rng(seed)
    train, test = [], []
    for label in np.unique(labels):
        members = rng.permutation(np.flatnonzero(labels == label))
        held = int(round(test_fraction * len(members)))
        test.append(members[:held])
        train.append(members[held:])
    return np.sort(np.concatenate(train)), np.sort(np.concatenate(test))


@node("recognition.lfw_faces", version=1)
def lfw_faces(
    *,
    test_fraction: Annotated[float, Field(gt=0, lt=1)] = 0.25,
    seed: Annotated[int, Field(ge=0)] = 0,
) -> Split:
    """scikit-image's ``lfw_subset``: 100 faces (label 1) and 100 non-faces (label 0), 25×25,
    split per class at random (seeded) into training and test sets.

    With the defaults the split is 150/50 with 75/25 of each class.

    Parameters
    ----------
    test_fraction : fraction of each class held out for testing
    seed : seed of the split

    Returns
    -------
    train, test : Samples (N, 25, 25)

    References
    ----------
    G. B. Huang et al., "Labeled Faces in the Wild", UMass TR 07-49, 2007.
    """
    from skimage.data import lfw_subset

    images = lfw_subset()
    labels = np.where(np.arange(len(images)) < 100, FACE, NON_FACE)
    train, test = stratified_split(labels, test_fraction, seed)
    return Split(_frozen(images[train], labels[train]), _frozen(images[test], labels[test]))


def _patches(image: np.ndarray, size: int, stride: int) -> np.ndarray:
    from numpy.lib.stride_tricks import sliding_window_view

    return sliding_window_view(image, (size, size))[::stride, ::stride].reshape(-1, size, size)


@node("recognition.texture_patches", version=1)
def texture_patches(
    *,
    textures: tuple[Texture, ...] = ("brick", "grass", "gravel"),
    size: Annotated[int, Field(ge=8, le=256)] = 64,
    stride: Annotated[int, Field(ge=1)] = 32,
) -> Split:
    """Square patches of scikit-image's textures, the left half of each image for training
    and the right half for testing; the label is the texture's index in ``textures``.

    Parameters
    ----------
    textures : texture images (512×512 each), one class each
    size : patch side in pixels
    stride : step between patches in pixels

    Returns
    -------
    train, test : Samples (N, size, size)
    """
    import skimage.data

    if len(set(textures)) < 2:
        raise ValueError(f"texture_patches needs two or more distinct textures, got {textures}")
    sides: dict[str, list[np.ndarray]] = {"train": [], "test": []}
    labels: dict[str, list[np.ndarray]] = {"train": [], "test": []}
    for label, name in enumerate(textures):
        image = to_float_image(getattr(skimage.data, name)(), source=f"sample '{name}'")
        half = image.shape[1] // 2
        for side, part in (("train", image[:, :half]), ("test", image[:, half:])):
            patches = _patches(part, size, stride)
            sides[side].append(patches)
            labels[side].append(np.full(len(patches), label))
    train, test = (
        _frozen(np.concatenate(sides[s]), np.concatenate(labels[s])) for s in ("train", "test")
    )
    return Split(train, test)


@node("recognition.negative_patches", version=1)
def negative_patches(
    *,
    images: tuple[FaceFree, ...] = ("brick", "grass", "gravel", "coins", "page", "text", "moon"),
    count: Annotated[int, Field(ge=1)] = 600,
    size: Annotated[int, Field(ge=4)] = 25,
    min_side: Annotated[int, Field(ge=4)] = 25,
    seed: Annotated[int, Field(ge=0)] = 0,
) -> Samples:
    """Negatives for a detector: random squares (side ``min_side`` to a third of the image)
    cut from face-free sample images and resized to ``size``×``size``; label 0.

    Parameters
    ----------
    images : face-free sample images to cut from
    count : number of patches (spread evenly over the images)
    size : side of the returned patches
    min_side : smallest square cut from an image, before resizing
    seed : seed of positions and sides

    Returns
    -------
    negatives : Samples (count, size, size)
    """
    import skimage.data
    from skimage.transform import resize

    rng = np.random.default_rng(seed)
    patches = []
    for index in range(count):
        name = images[index % len(images)]
        image = to_float_image(getattr(skimage.data, name)(), source=f"sample '{name}'")
        if image.ndim == 3:
            image = image.mean(axis=2)
        top = max(min_side, min(image.shape) // 3)
        side = int(rng.integers(min_side, top + 1))
        row = int(rng.integers(0, image.shape[0] - side + 1))
        col = int(rng.integers(0, image.shape[1] - side + 1))
        crop = image[row : row + side, col : col + side]
        patches.append(resize(crop, (size, size), anti_aliasing=True, preserve_range=True))
    return _frozen(np.clip(np.stack(patches), 0, 1), np.full(count, NON_FACE))


@node("recognition.combine", version=1)
def combine(a: Samples, b: Samples) -> Samples:
    """The samples of ``a`` followed by those of ``b`` (images of the same size).

    Parameters
    ----------
    a, b : Samples of equal image size

    Returns
    -------
    samples : Samples
    """
    if a.images.shape[1:] != b.images.shape[1:]:
        raise ValueError(
            f"recognition.combine needs images of one size, got {a.images.shape[1:]} "
            f"in 'a' and {b.images.shape[1:]} in 'b'"
        )
    return _frozen(np.concatenate([a.images, b.images]), np.concatenate([a.labels, b.labels]))


def pixel_features(images: np.ndarray) -> np.ndarray:
    """Each image as one row of its pixels (row-major), float64."""
    return images.reshape(len(images), -1).astype(np.float64)


@node("recognition.pixels", version=1)
def pixels(samples: Samples) -> Features:
    """Each image as the vector of its pixels (seed: "reshape training images into column
    vectors").

    Parameters
    ----------
    samples : Samples (N, H, W)

    Returns
    -------
    features : Features (N, H·W) with the samples' labels
    """
    window = list(samples.images.shape[1:])
    recipe = json.dumps({"kind": "pixels", "window": window})
    return FeatureSet(pixel_features(samples.images), samples.labels.copy(), recipe)
