"""Detection scenes with known boxes: handwritten digits pasted at random positions and
scales on textured backgrounds (seeded).

A :class:`SceneSet` holds N equally sized gray scenes and their true objects: boxes
``xyxy`` (M, 4) (x0, y0, x1, y1; the ink's extent, in pixels), class ``label`` (M,)
and the scene each belongs to, ``owner`` (M,). The digits are scikit-learn's 8×8 digits
(the ``cnn.digits`` loader), split per class at random (seeded, 80/20): training scenes
use the training digits and test scenes the held-out ones, so a detector is measured on
digits it never saw. Backgrounds are random crops of scikit-image's brick, grass and
gravel textures, their contrast reduced to [0.05, 0.45] so that the white digits (ink
blended over the texture) stay the brightest things in a scene.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field

from graphvision import PortValueError, RecordPort, node

from ..shared.boxes import check_boxes
from ..shared.checks import all_of, at_most_values, ordered
from ..shared.params import Seed

__all__ = ["SceneSet", "Scenes", "ScenesPort", "digit_scenes", "render_digit_scenes"]

INK = 0.2
"""A pixel whose digit coverage exceeds this belongs to the digit's box."""


@dataclass(frozen=True, eq=False)
class SceneSet:
    """Scenes (N, H, W) float32 in [0, 1] and their true objects (see the module)."""

    images: np.ndarray
    xyxy: np.ndarray
    label: np.ndarray
    owner: np.ndarray

    def __len__(self) -> int:
        return len(self.images)

    def boxes_of(self, scene: int) -> tuple[np.ndarray, np.ndarray]:
        """The true boxes and labels of one scene."""
        mine = self.owner == scene
        return self.xyxy[mine], self.label[mine]


class ScenesPort(RecordPort):
    """A :class:`SceneSet`: images float32 (N, H, W) in [0, 1]; xyxy float64 (M, 4) with
    x0 < x1, y0 < y1; label and owner int64 (M,), owner in [0, N)."""

    value_class = SceneSet

    @classmethod
    def validate(cls, value: Any) -> SceneSet:
        value = super().validate(value)
        images, xyxy = value.images, value.xyxy
        if not isinstance(images, np.ndarray) or images.dtype != np.float32 or images.ndim != 3:
            raise PortValueError("Scenes 'images' must be float32 (N, H, W)")
        if not isinstance(xyxy, np.ndarray) or xyxy.dtype != np.float64 or xyxy.shape[1:] != (4,):
            raise PortValueError("Scenes 'xyxy' must be float64 (M, 4)")
        for name in ("label", "owner"):
            column = getattr(value, name)
            if not isinstance(column, np.ndarray) or column.dtype != np.int64:
                raise PortValueError(f"Scenes '{name}' must be int64 (M,)")
            if column.shape != (len(xyxy),):
                raise PortValueError(f"Scenes '{name}' must have one entry per box")
        try:
            check_boxes(xyxy, "Scenes box")
        except ValueError as error:
            raise PortValueError(str(error)) from None
        if len(value.owner) and (value.owner.min() < 0 or value.owner.max() >= len(images)):
            raise PortValueError(f"Scenes 'owner' must index the {len(images)} scenes")
        return value

    @classmethod
    def preview(cls, value: SceneSet) -> np.ndarray | None:
        """The first eight scenes side by side, two white columns apart."""
        shown = value.images[:8]
        height, width = shown.shape[1:]
        canvas = np.ones((height, len(shown) * (width + 2)), np.float32)
        for index, image in enumerate(shown):
            canvas[:, index * (width + 2) : index * (width + 2) + width] = image
        return canvas

    @classmethod
    def summary(cls, value: SceneSet) -> str:
        side = f"{value.images.shape[1]}×{value.images.shape[2]}"
        return f"Scenes {len(value)} × {side}, {len(value.xyxy)} objects"


Scenes = Annotated[SceneSet, ScenesPort]


def _textures() -> list[np.ndarray]:
    from skimage import data

    return [data.brick() / 255.0, data.grass() / 255.0, data.gravel() / 255.0]


def _background(textures: list[np.ndarray], size: int, rng: np.random.Generator) -> np.ndarray:
    texture = textures[rng.integers(len(textures))]
    top = rng.integers(0, texture.shape[0] - size)
    left = rng.integers(0, texture.shape[1] - size)
    crop = texture[top : top + size, left : left + size]
    low, high = crop.min(), crop.max()
    stretched = (crop - low) / max(high - low, 1e-6)
    return 0.05 + 0.4 * stretched


def render_digit_scenes(
    digits: np.ndarray,
    labels: np.ndarray,
    *,
    count: int,
    size: int,
    objects: tuple[int, int],
    scales: tuple[int, int],
    seed: int,
) -> SceneSet:
    """``count`` scenes of ``size`` × ``size`` with ``objects`` (min, max) digits each,
    every digit scaled (bilinear) to a side in ``scales`` (min, max) pixels, placed where it
    does not overlap another (the ink boxes of one scene are disjoint)."""
    from skimage.transform import resize

    rng = np.random.default_rng(seed)
    textures = _textures()
    images, boxes, classes, owners = [], [], [], []
    for scene in range(count):
        canvas = _background(textures, size, rng)
        taken: list[np.ndarray] = []
        for _ in range(rng.integers(objects[0], objects[1] + 1)):
            pick = rng.integers(len(digits))
            side = int(rng.integers(scales[0], scales[1] + 1))
            coverage = np.clip(resize(digits[pick], (side, side), order=1), 0, 1)
            rows = np.flatnonzero(coverage.max(axis=1) > INK)
            cols = np.flatnonzero(coverage.max(axis=0) > INK)
            for _attempt in range(20):
                top, left = rng.integers(0, size - side + 1, 2)
                box = np.array(
                    [left + cols[0], top + rows[0], left + cols[-1] + 1, top + rows[-1] + 1],
                    np.float64,
                )
                clear = all(
                    box[0] >= other[2] + 1
                    or other[0] >= box[2] + 1
                    or box[1] >= other[3] + 1
                    or other[1] >= box[3] + 1
                    for other in taken
                )
                if clear:
                    window = canvas[top : top + side, left : left + side]
                    canvas[top : top + side, left : left + side] = (
                        window * (1 - coverage) + coverage
                    )
                    taken.append(box)
                    classes.append(int(labels[pick]))
                    owners.append(scene)
                    break
        images.append(canvas)
        boxes.extend(taken)
    return SceneSet(
        np.asarray(images, np.float32),
        np.asarray(boxes, np.float64).reshape(-1, 4),
        np.asarray(classes, np.int64),
        np.asarray(owners, np.int64),
    )


Digit = Annotated[int, Field(ge=0, le=9)]
"""A digit class."""


def _digit_fits(**params: Any) -> None:
    """A digit is pasted whole: its largest side is at most the scene's."""
    if params["max_scale"] > params["size"]:
        raise ValueError(
            f"max_scale ({params['max_scale']}) must be at most the scene's size "
            f"({params['size']}): a digit is pasted whole"
        )


@node(
    "synthetic.digit_scenes",
    version=1,
    check=all_of(
        ordered(("min_objects", "max_objects"), ("min_scale", "max_scale")),
        at_most_values("count", "size", "size"),
        _digit_fits,
    ),
)
def digit_scenes(
    *,
    split: Literal["train", "test"] = "train",
    count: Annotated[int, Field(ge=1, le=10_000)] = 60,
    size: Annotated[int, Field(ge=16, le=512)] = 80,
    min_objects: Annotated[int, Field(ge=0, le=100)] = 1,
    max_objects: Annotated[int, Field(ge=0, le=100)] = 3,
    min_scale: Annotated[int, Field(ge=8)] = 16,
    max_scale: Annotated[int, Field(ge=8)] = 28,
    classes: Annotated[list[Digit], Field(min_length=1)] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9],  # noqa: B006
    seed: Seed = 0,
) -> Scenes:
    """Seeded detection scenes: scikit-learn's 8×8 digits pasted at random positions and
    scales on textured backgrounds, with their true boxes and classes.

    Parameters
    ----------
    split : {'train', 'test'}
        Paste digits of the training or of the held-out 20 % of scikit-learn's digits
        (the seeded stratified split of ``cnn.digits``, seed 0).
    count : int
        Number of scenes.
    size : int
        Side of each (square) scene in pixels.
    min_objects : int
        Fewest digits per scene.
    max_objects : int
        Most digits per scene (fewer when no free place is found in 20 tries).
    min_scale : int
        Smallest side of a pasted digit (pixels).
    max_scale : int
        Largest side of a pasted digit (pixels).
    classes : list of int
        Digit classes to paste.
    seed : int
        Seed of the backgrounds, the digits drawn, their scales and positions.

    Returns
    -------
    Scenes
        Images (count, size, size) and the true boxes (the ink's extent) with classes.
    """
    from ..cnn._digits import load_digits_images
    from ..recognition._data import stratified_split

    images, labels = load_digits_images()
    train, test = stratified_split(labels, 0.2, 0)
    chosen = train if split == "train" else test
    chosen = chosen[np.isin(labels[chosen], classes)]
    return render_digit_scenes(
        images[chosen],
        labels[chosen],
        count=count,
        size=size,
        objects=(min_objects, max_objects),
        scales=(min_scale, max_scale),
        seed=seed,
    )
