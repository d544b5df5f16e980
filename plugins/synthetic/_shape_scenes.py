r"""Semantic segmentation scenes with a known class at every pixel: filled shapes (discs,
squares, triangles, crosses) on textured backgrounds (seeded).

A :class:`LabelledSceneSet` holds N equally sized gray scenes, their label maps (N, H,
W) int32 (0 the background, k the k-th of ``names[1:]``) and the class names. A shape
of class k with centre :math:`c`, size :math:`r` and rotation :math:`\phi` covers the
points :math:`p` whose rotated offset :math:`(u, v) = R_{-\phi}(p - c)` satisfies

* disc: :math:`u^2 + v^2 \le r^2`;
* square: :math:`\max(|u|, |v|) \le 0.8\,r`;
* triangle (equilateral, circumradius :math:`r`): :math:`n_i \cdot (u, v) \le r/2`
  for its three edge normals :math:`n_i`;
* cross: :math:`\min(|u|, |v|) \le 0.3\,r` and :math:`\max(|u|, |v|) \le r`.

Every shape has its own gray level :math:`g`, drawn from the same range for every class,
times its class's surface pattern (``surfaces``; period :math:`P` = 5 px, in the shape's
own frame): a disc is flat, a square striped (:math:`\sin(2\pi u/P) > 0`), a triangle
checked (:math:`\sin(2\pi u/P)\sin(2\pi v/P) > 0`) and a cross ringed
(:math:`\sin(2\pi \lVert(u, v)\rVert/P) > 0`), 1 where the test holds and 0.6 elsewhere,
as real classes differ in their surfaces as well as their outlines. Without patterns a
class is told only by its outline, which needs a context as wide as the shape.

Each pixel's coverage is the fraction of its 4×4 sub-pixel centres inside the shape; the
shape, shaded by the mean of :math:`g` times the pattern over those sub-pixels, is
blended over the scene by that coverage, and the pixel takes the shape's class where the
coverage is at least one half (shapes drawn later cover earlier ones). Backgrounds are
random crops of scikit-image's photographs, their contrast stretched into a random
sub-range of ``min_background`` .. ``max_background``; Gaussian noise comes last.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field

from graphvision import PortValueError, RecordPort, node

from ..shared.checks import all_of, at_most_values, ordered
from ..shared.params import Seed

__all__ = [
    "SHAPES",
    "LabelledSceneSet",
    "LabelledScenes",
    "LabelledScenesPort",
    "render_shape_scenes",
    "shape_mask",
    "shape_scenes",
    "shape_surface",
]

SHAPES = ("disc", "square", "triangle", "cross")
"""The shape classes, in the order of their default labels 1..4."""
SUBPIXELS = 4
"""Sub-pixel centres per pixel side of the coverage."""
PERIOD = 5.0
"""Period of the surface patterns, in pixels."""

Shape = Literal["disc", "square", "triangle", "cross"]
Texture = Literal["brick", "grass", "gravel", "camera", "coffee", "moon", "coins", "rocket"]


@dataclass(frozen=True, eq=False)
class LabelledSceneSet:
    """Scenes ``images`` (N, H, W) float32 in [0, 1], their ``labels`` (N, H, W) int32 (0 the
    background) and ``names``, the JSON list of the class names (``names[0]`` the
    background's)."""

    images: np.ndarray
    labels: np.ndarray
    names: str

    def __len__(self) -> int:
        return len(self.images)

    @property
    def class_names(self) -> list[str]:
        """The class names, the background's first."""
        return list(json.loads(self.names))


class LabelledScenesPort(RecordPort):
    """A :class:`LabelledSceneSet`: images float32 (N, H, W) in [0, 1]; labels int32 of the
    same shape in [0, K) for K names."""

    value_class = LabelledSceneSet

    @classmethod
    def validate(cls, value: Any) -> LabelledSceneSet:
        value = super().validate(value)
        images, labels = value.images, value.labels
        if not isinstance(images, np.ndarray) or images.dtype != np.float32 or images.ndim != 3:
            raise PortValueError("LabelledScenes 'images' must be float32 (N, H, W)")
        if not isinstance(labels, np.ndarray) or labels.dtype != np.int32:
            raise PortValueError("LabelledScenes 'labels' must be int32 (N, H, W)")
        if labels.shape != images.shape:
            raise PortValueError(
                f"LabelledScenes 'labels' {labels.shape} must have the images' shape {images.shape}"
            )
        try:
            names = json.loads(value.names)
        except (TypeError, ValueError):
            raise PortValueError("LabelledScenes 'names' must be a JSON list of names") from None
        if not isinstance(names, list) or len(names) < 2:
            raise PortValueError("LabelledScenes 'names' must list the background and a class")
        if labels.size and (labels.min() < 0 or labels.max() >= len(names)):
            raise PortValueError(f"LabelledScenes 'labels' must lie in [0, {len(names)})")
        return value

    @classmethod
    def preview(cls, value: LabelledSceneSet) -> np.ndarray | None:
        """The first eight scenes above their label maps (class k in gray level k / K)."""
        shown = value.images[:8]
        levels = value.labels[:8] / max(len(value.class_names) - 1, 1)
        return np.concatenate(
            [np.concatenate(list(shown), axis=1), np.concatenate(list(levels), axis=1)], axis=0
        ).astype(np.float32)

    @classmethod
    def summary(cls, value: LabelledSceneSet) -> str:
        side = f"{value.images.shape[1]}×{value.images.shape[2]}"
        return f"LabelledScenes {len(value)} × {side}, classes {', '.join(value.class_names)}"


LabelledScenes = Annotated[LabelledSceneSet, LabelledScenesPort]


def shape_mask(shape: str, u: np.ndarray, v: np.ndarray, size: float) -> np.ndarray:
    """Whether the offsets ``(u, v)``, in the shape's own rotated frame, lie inside a
    ``shape`` of size ``size`` (see the module for each shape's inequalities)."""
    if shape == "disc":
        return u * u + v * v <= size * size
    if shape == "square":
        return np.maximum(np.abs(u), np.abs(v)) <= 0.8 * size
    if shape == "triangle":
        inside = np.ones(u.shape, bool)
        for angle in (np.pi / 2, np.pi / 2 + 2 * np.pi / 3, np.pi / 2 + 4 * np.pi / 3):
            inside &= np.cos(angle) * u + np.sin(angle) * v <= size / 2
        return inside
    if shape == "cross":
        near, far = np.minimum(np.abs(u), np.abs(v)), np.maximum(np.abs(u), np.abs(v))
        return (near <= 0.3 * size) & (far <= size)
    raise ValueError(f"unknown shape '{shape}'; choose one of {', '.join(SHAPES)}")


def shape_surface(shape: str, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The surface pattern of a ``shape`` at the offsets ``(u, v)`` of its own frame, in
    [0.6, 1] (the shape's gray level multiplies it; see the module)."""
    wave = 2 * np.pi / PERIOD
    if shape == "disc":
        return np.ones(u.shape)
    if shape == "square":
        high = np.sin(wave * u) > 0
    elif shape == "triangle":
        high = np.sin(wave * u) * np.sin(wave * v) > 0
    else:
        high = np.sin(wave * np.hypot(u, v)) > 0
    return np.where(high, 1.0, 0.6)


def _coverage(
    shape: str, centre: np.ndarray, size: float, angle: float, surface: bool = False
) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """The coverage (in [0, 1]) of the shape over its bounding window of the scene, the
    mean of its surface pattern over the pixel (times the coverage; the coverage itself
    when ``surface`` is off), and the window's top-left corner (row, col)."""
    reach = int(np.ceil(size)) + 1
    top, left = int(centre[1]) - reach, int(centre[0]) - reach
    offsets = (np.arange(SUBPIXELS) + 0.5) / SUBPIXELS - 0.5
    rows = np.arange(top, top + 2 * reach + 1)[:, None] + offsets[None, :]
    cols = np.arange(left, left + 2 * reach + 1)[:, None] + offsets[None, :]
    y = rows.reshape(-1)[:, None] - centre[1]
    x = cols.reshape(-1)[None, :] - centre[0]
    u = np.cos(angle) * x + np.sin(angle) * y
    v = -np.sin(angle) * x + np.cos(angle) * y
    inside = shape_mask(shape, u, v, size).astype(np.float64)
    paint = inside * shape_surface(shape, u, v) if surface else inside
    n = 2 * reach + 1
    coverage = inside.reshape(n, SUBPIXELS, n, SUBPIXELS).mean(axis=(1, 3))
    shade = paint.reshape(n, SUBPIXELS, n, SUBPIXELS).mean(axis=(1, 3))
    return coverage, shade, (top, left)


def _paint(
    canvas: np.ndarray,
    labels: np.ndarray,
    cover: tuple[np.ndarray, np.ndarray],
    corner: tuple[int, int],
    value: tuple[float, int],
) -> None:
    """Blend a shape of coverage and shade ``cover``, gray level ``value[0]`` and class
    ``value[1]`` into the scene, clipped to it."""
    coverage, shade = cover
    top, left = corner
    r0, c0 = max(top, 0), max(left, 0)
    r1 = min(top + coverage.shape[0], canvas.shape[0])
    c1 = min(left + coverage.shape[1], canvas.shape[1])
    if r0 >= r1 or c0 >= c1:
        return
    inner = (slice(r0 - top, r1 - top), slice(c0 - left, c1 - left))
    window = canvas[r0:r1, c0:c1]
    window[:] = window * (1 - coverage[inner]) + value[0] * shade[inner]
    labels[r0:r1, c0:c1][coverage[inner] >= 0.5] = value[1]


def _background(photo: np.ndarray, side: int, levels: tuple, rng: np.random.Generator):
    top = rng.integers(0, photo.shape[0] - side + 1)
    left = rng.integers(0, photo.shape[1] - side + 1)
    crop = photo[top : top + side, left : left + side]
    low, high = float(crop.min()), float(crop.max())
    stretched = (crop - low) / max(high - low, 1e-6)
    lo, hi = np.sort(rng.uniform(levels[0], levels[1], 2))
    return lo + (hi - lo) * stretched


def render_shape_scenes(
    photos: list[np.ndarray],
    *,
    classes: list[str],
    count: int,
    side: int,
    objects: tuple[int, int],
    sizes: tuple[float, float],
    levels: tuple[float, float],
    background: tuple[float, float],
    noise: float,
    seed: int,
    surfaces: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """``count`` scenes ``side`` × ``side`` (float32) and their labels (int32): each a
    crop of one of ``photos`` holding ``objects`` (min, max) shapes of ``classes`` (label
    k + 1 for ``classes[k]``), sizes uniform in ``sizes``, gray levels in ``levels``, anywhere
    in the scene (they may overlap and leave it)."""
    rng = np.random.default_rng(seed)
    images = np.empty((count, side, side), np.float32)
    labels = np.zeros((count, side, side), np.int32)
    for scene in range(count):
        photo = photos[rng.integers(len(photos))]
        canvas = _background(photo, side, background, rng)
        for _ in range(rng.integers(objects[0], objects[1] + 1)):
            kind = int(rng.integers(len(classes)))
            size = float(rng.uniform(*sizes))
            centre = rng.uniform(0, side, 2)
            angle = float(rng.uniform(0, 2 * np.pi))
            coverage, shade, corner = _coverage(classes[kind], centre, size, angle, surfaces)
            value = (float(rng.uniform(*levels)), kind + 1)
            _paint(canvas, labels[scene], (coverage, shade), corner, value)
        canvas += rng.normal(0, noise, canvas.shape)
        images[scene] = np.clip(canvas, 0, 1)
    return images, labels


@functools.lru_cache(maxsize=16)
def _photograph(name: str) -> np.ndarray:
    """A bundled scikit-image photograph as gray float64 in [0, 1], read once (read-only)."""
    from skimage import data

    image = np.asarray(getattr(data, name)(), np.float64)
    if image.ndim == 3:
        image = image[..., :3].mean(axis=2)
    image /= 255.0
    image.flags.writeable = False
    return image


def _check_shapes(classes: list[str], max_size: float, side: int, **_: object) -> None:
    """Each class named once; a shape fits in the scene."""
    if len(set(classes)) != len(classes):
        raise ValueError(f"classes {classes} names a shape twice; name each at most once")
    if 2 * max_size >= side:
        raise ValueError(
            f"max_size ({max_size:g}) must be below half the scene's side ({side}): a shape "
            "spans 2 × size pixels"
        )


@node(
    "synthetic.shape_scenes",
    version=1,
    check=all_of(
        _check_shapes,
        ordered(
            ("min_objects", "max_objects"),
            ("min_size", "max_size"),
            ("min_level", "max_level"),
            ("min_background", "max_background"),
        ),
        at_most_values("count", "side", "side"),
    ),
)
def shape_scenes(
    *,
    count: Annotated[int, Field(ge=1, le=10_000)] = 100,
    side: Annotated[int, Field(ge=16, le=512)] = 64,
    classes: Annotated[list[Shape], Field(min_length=1, max_length=4)] = list(SHAPES),  # type: ignore[arg-type]  # noqa: B006
    min_objects: Annotated[int, Field(ge=0, le=50)] = 2,
    max_objects: Annotated[int, Field(ge=0, le=50)] = 5,
    min_size: Annotated[float, Field(ge=2, le=128)] = 6.0,
    max_size: Annotated[float, Field(ge=2, le=128)] = 12.0,
    min_level: Annotated[float, Field(ge=0, le=1)] = 0.5,
    max_level: Annotated[float, Field(ge=0, le=1)] = 1.0,
    min_background: Annotated[float, Field(ge=0, le=1)] = 0.0,
    max_background: Annotated[float, Field(ge=0, le=1)] = 0.45,
    textures: Annotated[list[Texture], Field(min_length=1)] = ["brick", "grass", "gravel"],  # noqa: B006
    noise: Annotated[float, Field(ge=0, le=0.5)] = 0.02,
    surfaces: bool = True,
    seed: Seed = 0,
) -> LabelledScenes:
    r"""Seeded semantic segmentation scenes: filled discs, squares, triangles and crosses
    of random sizes, rotations and gray levels on textured backgrounds, with the class of
    every pixel (the shapes and their rendering are described in the module).

    Parameters
    ----------
    count : int
        Number of scenes.
    side : int
        Side of each (square) scene in pixels.
    classes : list of {'disc', 'square', 'triangle', 'cross'}
        The shapes drawn; ``classes[k]`` has label k + 1 (0 is the background).
    min_objects, max_objects : int
        Fewest and most shapes per scene, drawn uniformly; they may overlap (a later
        one covers an earlier one) and leave the scene.
    min_size, max_size : float
        Range of a shape's size :math:`r` (a disc's radius, a triangle's circumradius),
        in pixels.
    min_level, max_level : float
        Range of a shape's gray level (the same for every class).
    min_background, max_background : float
        Range a background's contrast is stretched into (a random sub-range of it).
    textures : list of str
        scikit-image photographs the backgrounds are cut from.
    noise : float
        Standard deviation of the Gaussian noise added last.
    surfaces : bool
        Give each class its surface pattern (see the module); without them the classes
        differ only by their outlines.
    seed : int
        Seed of everything random.

    Returns
    -------
    LabelledScenes
        Images (count, side, side), their labels and the class names
        (``background`` first).

    References
    ----------
    J. Long, E. Shelhamer, T. Darrell, "Fully convolutional networks for semantic
    segmentation", CVPR 2015 (per-pixel labels as the training target).
    """
    images, labels = render_shape_scenes(
        [_photograph(name) for name in textures],
        classes=list(classes),
        count=count,
        side=side,
        objects=(min_objects, max_objects),
        sizes=(min_size, max_size),
        levels=(min_level, max_level),
        background=(min_background, max_background),
        noise=noise,
        seed=seed,
        surfaces=surfaces,
    )
    return LabelledSceneSet(images, labels, json.dumps(["background", *classes]))
