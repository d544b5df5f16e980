"""Labelled sample sets from the data shipped with scikit-image (nothing downloads)."""

from __future__ import annotations

import json
from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import AfterValidator, Field

from graphvision import node

from ..shared.checks import at_most_values, to_float_image
from ..shared.params import MAX_SIDE, Probability, Seed
from ._types import Features, FeatureSet, Samples, SampleSet

__all__ = [
    "FACE",
    "NON_FACE",
    "FaceFree",
    "Split",
    "augment",
    "combine",
    "face_free_image",
    "lfw_faces",
    "negative_patches",
    "pixels",
    "stratified_split",
    "texture_patches",
]

FACE = 1
NON_FACE = 0
Texture = Literal["brick", "grass", "gravel"]
FaceFree = Literal[
    "brick",
    "checkerboard",
    "chelsea",
    "clock",
    "coffee",
    "coins",
    "grass",
    "gravel",
    "hubble_deep_field",
    "immunohistochemistry",
    "moon",
    "page",
    "rocket",
    "text",
]


class Split(NamedTuple):
    train: Samples
    test: Samples


def _frozen(images: np.ndarray, labels: np.ndarray) -> SampleSet:
    return SampleSet(np.ascontiguousarray(images, np.float32), np.asarray(labels, np.int64))


def stratified_split(
    labels: np.ndarray, test_fraction: float, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """Indices (train, test): ``round(test_fraction · n_c)`` random members of each class c
    go to the test side, the rest to training (seeded, sorted). ValueError naming
    ``test_fraction`` when it leaves a class without a training sample (a classifier
    cannot learn it) or the test side empty (nothing to measure)."""
    rng = np.random.default_rng(seed)
    train, test = [], []
    for label in np.unique(labels):
        members = rng.permutation(np.flatnonzero(labels == label))
        held = int(round(test_fraction * len(members)))
        if held == len(members):
            raise ValueError(
                f"test_fraction={test_fraction:g} holds out all {len(members)} samples of class "
                f"{label}, leaving it no training sample: use a test_fraction below "
                f"{(len(members) - 0.5) / len(members):.3g}"
            )
        test.append(members[:held])
        train.append(members[held:])
    if not sum(len(part) for part in test):
        largest = max(len(part) for part in train)
        raise ValueError(
            f"test_fraction={test_fraction:g} holds out no sample of any class: use a "
            f"test_fraction above {0.5 / largest:.3g}"
        )
    return np.sort(np.concatenate(train)), np.sort(np.concatenate(test))


@node("recognition.lfw_faces", version=1)
def lfw_faces(
    *,
    test_fraction: Probability = 0.25,
    seed: Seed = 0,
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


def _distinct(textures: tuple[str, ...]) -> tuple[str, ...]:
    """``textures`` itself when it names two or more distinct textures (two classes)."""
    if len(set(textures)) < 2:
        raise ValueError(f"needs two or more distinct textures, got {list(textures)}")
    return textures


Textures = Annotated[tuple[Texture, ...], Field(min_length=1), AfterValidator(_distinct)]
"""Two or more distinct textures, one class each."""


@node("recognition.texture_patches", version=1)
def texture_patches(
    *,
    textures: Textures = ("brick", "grass", "gravel"),
    size: Annotated[int, Field(ge=8, le=256)] = 64,
    stride: Annotated[int, Field(ge=1, le=MAX_SIDE)] = 32,
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


def face_free_image(name: str) -> np.ndarray:
    """A face-free scikit-image sample as a gray float32 image (channel mean)."""
    import skimage.data

    image = to_float_image(getattr(skimage.data, name)(), source=f"sample '{name}'")
    return image.mean(axis=2) if image.ndim == 3 else image


NEGATIVE_SOURCES: tuple[FaceFree, ...] = (
    "brick",
    "grass",
    "gravel",
    "coins",
    "page",
    "text",
    "moon",
)
"""The face-free images ``recognition.negative_patches`` cuts patches from by default."""


@node("recognition.negative_patches", version=1, check=at_most_values("count", "size", "size"))
def negative_patches(
    *,
    images: Annotated[tuple[FaceFree, ...], Field(min_length=1)] = NEGATIVE_SOURCES,
    count: Annotated[int, Field(ge=1, le=100_000)] = 600,
    size: Annotated[int, Field(ge=4, le=256)] = 25,
    min_side: Annotated[int, Field(ge=4, le=MAX_SIDE)] = 25,
    seed: Seed = 0,
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
    from skimage.transform import resize

    rng = np.random.default_rng(seed)
    loaded = {name: face_free_image(name) for name in images}
    patches = []
    for index in range(count):
        image = loaded[images[index % len(images)]]
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


@node("recognition.augment", version=1)
def augment(
    samples: Samples,
    *,
    copies: Annotated[int, Field(ge=0, le=100)] = 4,
    shift: Annotated[float, Field(ge=0)] = 1.5,
    scale: Annotated[float, Field(ge=0, lt=1)] = 0.08,
    angle: Annotated[float, Field(ge=0, le=180)] = 8.0,
    seed: Seed = 0,
) -> Samples:
    """The samples, their mirror images, and ``copies`` jittered copies of each: a random
    similarity about the centre (log-scale in ±``scale``, rotation in ±``angle`` degrees,
    shift in ±``shift`` pixels; seeded), mirrored half of the time. A detector trained
    on them tolerates windows that frame the object a little differently.

    Parameters
    ----------
    samples : Samples (N, H, W)
    copies : jittered copies per sample
    shift : largest shift in pixels
    scale : largest |log| of the scale factor
    angle : largest rotation in degrees
    seed : seed of the jitter

    Returns
    -------
    samples : Samples ((copies + 2) · N, H, W), labels repeated
    """
    from skimage.transform import warp

    rng = np.random.default_rng(seed)
    images = samples.images
    height, width = images.shape[1:]
    centre = np.array([(width - 1) / 2, (height - 1) / 2])
    out = [images, images[:, :, ::-1]]
    for _ in range(copies):
        jittered = np.empty_like(images)
        for index, image in enumerate(images):
            factor = np.exp(rng.uniform(-scale, scale))
            theta = np.deg2rad(rng.uniform(-angle, angle))
            offset = rng.uniform(-shift, shift, 2)
            if rng.random() < 0.5:
                image = image[:, ::-1]
            # output (x, y) ← input R⁻¹ (x − c − t) / s + c: the inverse map warp expects
            cos, sin = np.cos(theta) / factor, np.sin(theta) / factor
            linear = np.array([[cos, sin], [-sin, cos]])
            inverse = np.eye(3)
            inverse[:2, :2] = linear
            inverse[:2, 2] = centre - linear @ (centre + offset)
            jittered[index] = warp(
                np.array(image, np.float64), inverse, mode="edge", preserve_range=True
            )
        out.append(jittered)
    labels = np.tile(samples.labels, copies + 2)
    return _frozen(np.clip(np.concatenate(out), 0, 1), labels)


def pixel_features(images: np.ndarray, normalise: bool = False) -> np.ndarray:
    """Each image as one row of its pixels (row-major), float64; with ``normalise`` each row
    minus its mean and divided by its norm (rows without contrast stay zero)."""
    rows = images.reshape(len(images), -1).astype(np.float64)
    if not normalise:
        return rows
    rows = rows - rows.mean(axis=1, keepdims=True)
    norms = np.linalg.norm(rows, axis=1, keepdims=True)
    return np.divide(rows, norms, out=np.zeros_like(rows), where=norms > 1e-12)


@node("recognition.pixels", version=1)
def pixels(samples: Samples, *, normalise: bool = False) -> Features:
    """Each image as the vector of its pixels (seed: "reshape training images into column
    vectors"), optionally normalised to zero mean and unit norm (then brightness and
    contrast do not matter, as for detection by distance from a subspace).

    Parameters
    ----------
    samples : Samples (N, H, W)
    normalise : subtract each vector's mean and divide by its norm

    Returns
    -------
    features : Features (N, H·W) with the samples' labels
    """
    window = list(samples.images.shape[1:])
    recipe = json.dumps({"kind": "pixels", "window": window, "normalise": normalise})
    return FeatureSet(pixel_features(samples.images, normalise), samples.labels.copy(), recipe)
