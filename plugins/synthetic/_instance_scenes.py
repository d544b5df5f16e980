"""Instance segmentation scenes: the digit scenes of :mod:`._digit_scenes` with one mask per
digit, digits allowed to touch and overlap (seeded).

Digits are pasted one after the other over a textured background; a digit pasted later
lies on top: its ink (bilinear coverage above ``INK``) is its mask, and it hides the ink
of the digits below it, whose masks lose those pixels. With probability ``touching`` a
digit is placed against a digit already in the scene (its centre at 0.5 to 1.0 times the
half-sum of their sides, in a random direction), so that boxes overlap and inks touch or
cross; a placement that would hide more than ``max_hidden`` of a digit's visible ink is
drawn again (20 tries, then the digit is left out). Each true box is the extent of its
visible mask.
"""

from __future__ import annotations

from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, node

from ..shared.checks import all_of, at_most_values, ordered
from ..shared.params import Fraction, Seed
from ._digit_scenes import INK, Scenes, SceneSet, _background, _textures

__all__ = ["InstanceScenes", "instance_scenes", "render_instance_scenes"]


class InstanceScenes(NamedTuple):
    scenes: Scenes
    masks: Array


def _place(
    side: int, size: int, masks: list[np.ndarray], touching: float, rng: np.random.Generator
) -> tuple[int, int]:
    """Top-left corner of a ``side`` × ``side`` digit: against a random earlier digit with
    probability ``touching``, else anywhere."""
    if masks and rng.random() < touching:
        other = masks[rng.integers(len(masks))]
        rows, cols = np.nonzero(other)
        cy, cx = rows.mean(), cols.mean()
        extent = max(rows.max() - rows.min(), cols.max() - cols.min()) + 1
        angle = rng.uniform(0, 2 * np.pi)
        reach = rng.uniform(0.5, 1.0) * (extent + side) / 2
        top = int(round(cy + reach * np.sin(angle) - side / 2))
        left = int(round(cx + reach * np.cos(angle) - side / 2))
        return int(np.clip(top, 0, size - side)), int(np.clip(left, 0, size - side))
    top, left = rng.integers(0, size - side + 1, 2)
    return int(top), int(left)


def _paste_one(
    canvas: np.ndarray, masks: list[np.ndarray], coverage: np.ndarray, *, touching: float,
    max_hidden: float, rng: np.random.Generator,
) -> np.ndarray | None:  # fmt: skip
    """Paste ``coverage`` into ``canvas`` (in place) where it hides at most ``max_hidden``
    of each visible mask (which lose the hidden pixels); its full-scene mask, or None."""
    size, side = canvas.shape[0], coverage.shape[0]
    for _attempt in range(20):
        top, left = _place(side, size, masks, touching, rng)
        ink = np.zeros(canvas.shape, bool)
        ink[top : top + side, left : left + side] = coverage > INK
        if any((m & ink).sum() > max_hidden * m.sum() for m in masks):
            continue
        for m in masks:
            m &= ~ink
        window = canvas[top : top + side, left : left + side]
        canvas[top : top + side, left : left + side] = window * (1 - coverage) + coverage
        return ink
    return None


def render_instance_scenes(
    digits: np.ndarray, labels: np.ndarray, *, count: int, size: int,
    objects: tuple[int, int], scales: tuple[int, int], touching: float, max_hidden: float,
    seed: int,
) -> tuple[SceneSet, np.ndarray]:  # fmt: skip
    """``count`` scenes with their true boxes and visible instance masks (M, H, W) bool."""
    from skimage.transform import resize

    rng = np.random.default_rng(seed)
    textures = _textures()
    images, all_masks, classes, owners = [], [], [], []
    for scene in range(count):
        canvas = _background(textures, size, rng)
        masks: list[np.ndarray] = []
        for _ in range(rng.integers(objects[0], objects[1] + 1)):
            pick = rng.integers(len(digits))
            side = int(rng.integers(scales[0], scales[1] + 1))
            coverage = np.clip(resize(digits[pick], (side, side), order=1), 0, 1)
            ink = _paste_one(
                canvas, masks, coverage, touching=touching, max_hidden=max_hidden, rng=rng
            )
            if ink is not None:
                masks.append(ink)
                classes.append(int(labels[pick]))
                owners.append(scene)
        images.append(canvas)
        all_masks.extend(masks)
    stack = np.asarray(all_masks, bool).reshape(-1, size, size)
    boxes = np.zeros((len(stack), 4))
    for index, mask in enumerate(stack):
        rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
        boxes[index] = cols[0], rows[0], cols[-1] + 1, rows[-1] + 1
    scenes = SceneSet(
        np.asarray(images, np.float32), boxes, np.asarray(classes, np.int64),
        np.asarray(owners, np.int64),
    )  # fmt: skip
    return scenes, stack


@node(
    "synthetic.instance_scenes",
    version=1,
    check=all_of(
        ordered(("min_objects", "max_objects"), ("min_scale", "max_scale")),
        at_most_values("count", "size", "size"),
        at_most_values("count", "max_objects", "size", "size"),
    ),
)
def instance_scenes(
    *,
    split: Literal["train", "test"] = "train",
    count: Annotated[int, Field(ge=1, le=10_000)] = 60,
    size: Annotated[int, Field(ge=16, le=512)] = 80,
    min_objects: Annotated[int, Field(ge=0, le=100)] = 2,
    max_objects: Annotated[int, Field(ge=0, le=100)] = 4,
    min_scale: Annotated[int, Field(ge=8)] = 16,
    max_scale: Annotated[int, Field(ge=8)] = 28,
    touching: Fraction = 0.5,
    max_hidden: Fraction = 0.3,
    seed: Seed = 0,
) -> InstanceScenes:
    """Seeded instance segmentation scenes: scikit-learn's 8×8 digits pasted at random
    scales on textured backgrounds, touching and overlapping, each with its visible mask.

    Parameters
    ----------
    split : {'train', 'test'}
        Paste digits of the training or of the held-out 20 % of scikit-learn's digits
        (as ``synthetic.digit_scenes``).
    count : int
        Number of scenes.
    size : int
        Side of each (square) scene in pixels.
    min_objects, max_objects : int
        Fewest and most digits per scene (fewer when one finds no place in 20 tries).
    min_scale, max_scale : int
        Smallest and largest side of a pasted digit (pixels).
    touching : float
        Probability that a digit is placed against one already in the scene.
    max_hidden : float
        Most of a digit's visible ink a later digit may hide.
    seed : int
        Seed of the backgrounds, the digits drawn, their scales and positions.

    Returns
    -------
    scenes : Scenes
        Images (count, size, size), true boxes (each visible mask's extent) and classes.
    masks : Array
        (M, size, size) bool, the visible ink of each true box, in the boxes' order.
    """
    from ..cnn._digits import load_digits_images
    from ..recognition._data import stratified_split

    if max_scale > size:
        raise ValueError(
            f"max_scale ({max_scale}) must be at most the scene's size ({size}): a digit is "
            "pasted whole"
        )
    images, labels = load_digits_images()
    train, test = stratified_split(labels, 0.2, 0)
    chosen = train if split == "train" else test
    scenes, masks = render_instance_scenes(
        images[chosen], labels[chosen], count=count, size=size,
        objects=(min_objects, max_objects), scales=(min_scale, max_scale),
        touching=touching, max_hidden=max_hidden, seed=seed,
    )  # fmt: skip
    return InstanceScenes(scenes, masks)
