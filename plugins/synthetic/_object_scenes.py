"""Scenes holding instances of a planar object with known quadrilaterals (seeded).

An :class:`ObjectSceneSet` holds N equally sized gray scenes and the true instances of
one *model* image in them: for each instance the homography ``homographies[m]`` from
model pixel coordinates to scene pixel coordinates, the model's corners mapped by it
(``quads[m]``: the pixel centres (0, 0), (w-1, 0), (w-1, h-1), (0, h-1) in that order),
the scene it belongs to (``owner``), the fraction of its area left visible, its
out-of-plane tilt and its scale.

Each scene is a random crop of one of scikit-image's photographs (never the one the
model was cut from when it is among them: pass that name in ``exclude``), covered
with clutter (rotated crops of the other photographs), then 0 to 3 instances of the
model seen by a camera from a random pose, then occluders (more crops, each hiding up
to ``occlusion`` of an instance), then Gaussian noise.

**Pose.** A model point :math:`p` is centred, :math:`q = p - c`, put on the plane
:math:`Z = 0` and turned by :math:`R = R_z(\\psi) R_z(\\phi) R_x(\\theta) R_z(-\\phi)`: a
tilt :math:`\\theta` out of the image plane about an axis at angle :math:`\\phi`, then a
rotation :math:`\\psi` in the image plane. A perspective camera at distance :math:`D`
with focal length :math:`f = sD` sees it at

.. math:: x' = t + f \\frac{(X_1, X_2)}{D + X_3}, \\qquad X = R\\,(q_x, q_y, 0)^T,

so the scale at the centre is :math:`s`; the homography is
:math:`H = \\mathrm{diag}(f, f, 1)\\,[r_1\\; r_2\\; D e_3]\\,T_{-c}` with the translation
:math:`t` added. An affine instance is the limit :math:`D \\to \\infty`,
:math:`x' = t + s\\,(X_1, X_2)` (orthographic projection, scaled). :math:`D` is drawn in
1.5 to 3 model diagonals, so the near edge of a tilted instance is up to twice as large
as the far one.

The model is blurred before each warp by the Gaussian that keeps it from aliasing where
the warp shrinks it most (:math:`\\sigma = \\tfrac12\\sqrt{1/m^2 - 1}` model pixels,
:math:`m` the smallest singular value of the warp's Jacobian over the model), and
resampled bilinearly; its edge is blended by its bilinear coverage.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Any, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import GrayImage, PortValueError, RecordPort, node

from ..shared.checks import all_of, at_most_values, ordered
from ..shared.params import Fraction, Seed

__all__ = [
    "CLUTTER_PHOTOGRAPHS",
    "ObjectSceneSet",
    "ObjectScenes",
    "ObjectScenesPort",
    "model_corners",
    "object_pose",
    "object_scenes",
    "render_object_scenes",
]

Photograph = Literal[
    "astronaut",
    "brick",
    "camera",
    "chelsea",
    "coffee",
    "coins",
    "grass",
    "gravel",
    "immunohistochemistry",
    "moon",
    "rocket",
]
"""scikit-image photographs bundled with the package (nothing is downloaded)."""

CLUTTER_PHOTOGRAPHS: tuple[str, ...] = (
    "brick",
    "camera",
    "chelsea",
    "coffee",
    "coins",
    "grass",
    "gravel",
    "immunohistochemistry",
    "moon",
    "rocket",
)
"""The photographs backgrounds, clutter and occluders are cut from by default."""


def model_corners(width: int, height: int) -> np.ndarray:
    """The model's corner pixel centres (0, 0), (w-1, 0), (w-1, h-1), (0, h-1), (4, 2)."""
    return np.array([[0, 0], [width - 1, 0], [width - 1, height - 1], [0, height - 1]], float)


@dataclass(frozen=True, eq=False)
class ObjectSceneSet:
    """Scenes (N, H, W) float32 in [0, 1] and the true instances of the model in them
    (see the module): ``quads`` (M, 4, 2), ``homographies`` (M, 3, 3) model → scene,
    ``owner`` (M,) int64, ``visible``, ``tilt`` (degrees) and ``scale`` (M,) float64."""

    images: np.ndarray
    quads: np.ndarray
    homographies: np.ndarray
    owner: np.ndarray
    visible: np.ndarray
    tilt: np.ndarray
    scale: np.ndarray

    def __len__(self) -> int:
        return len(self.images)

    def quads_of(self, scene: int) -> np.ndarray:
        """The true quadrilaterals (K, 4, 2) of one scene."""
        return self.quads[self.owner == scene]


class ObjectScenesPort(RecordPort):
    """An :class:`ObjectSceneSet`: images float32 (N, H, W) in [0, 1]; quads float64
    (M, 4, 2) and homographies (M, 3, 3), finite; owner int64 (M,) in [0, N); visible,
    tilt and scale float64 (M,)."""

    value_class = ObjectSceneSet

    @classmethod
    def validate(cls, value: Any) -> ObjectSceneSet:
        value = super().validate(value)
        images = value.images
        if not isinstance(images, np.ndarray) or images.dtype != np.float32 or images.ndim != 3:
            raise PortValueError("ObjectScenes 'images' must be float32 (N, H, W)")
        count = len(value.owner) if isinstance(value.owner, np.ndarray) else -1
        shapes = {
            "quads": (np.float64, (count, 4, 2)),
            "homographies": (np.float64, (count, 3, 3)),
            "owner": (np.int64, (count,)),
            "visible": (np.float64, (count,)),
            "tilt": (np.float64, (count,)),
            "scale": (np.float64, (count,)),
        }
        for name, (dtype, shape) in shapes.items():
            column = getattr(value, name)
            if not isinstance(column, np.ndarray) or column.dtype != dtype or column.shape != shape:
                raise PortValueError(
                    f"ObjectScenes '{name}' must be {np.dtype(dtype).name} {shape}: one per "
                    "instance"
                )
        if not (np.isfinite(value.quads).all() and np.isfinite(value.homographies).all()):
            raise PortValueError("ObjectScenes 'quads' and 'homographies' must be finite")
        if count and (value.owner.min() < 0 or value.owner.max() >= len(images)):
            raise PortValueError(f"ObjectScenes 'owner' must index the {len(images)} scenes")
        return value

    @classmethod
    def preview(cls, value: ObjectSceneSet) -> np.ndarray | None:
        """The first four scenes side by side, two white columns apart."""
        shown = value.images[:4]
        height, width = shown.shape[1:]
        canvas = np.ones((height, len(shown) * (width + 2)), np.float32)
        for index, image in enumerate(shown):
            canvas[:, index * (width + 2) : index * (width + 2) + width] = image
        return canvas

    @classmethod
    def summary(cls, value: ObjectSceneSet) -> str:
        side = f"{value.images.shape[1]}×{value.images.shape[2]}"
        return f"ObjectScenes {len(value)} × {side}, {len(value.owner)} instances"


ObjectScenes = Annotated[ObjectSceneSet, ObjectScenesPort]


def _rotation_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rotation_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def object_pose(
    width: int,
    height: int,
    *,
    scale: float,
    tilt: float,
    axis: float,
    roll: float,
    distance: float | None,
) -> np.ndarray:
    r"""The homography taking model pixels to scene pixels, the model's centre to (0, 0).

    ``tilt``, ``axis`` and ``roll`` (radians) are :math:`\theta`, :math:`\phi` and
    :math:`\psi` of the module's pose; ``distance`` is :math:`D` in model diagonals
    (None: affine, the orthographic limit). Add the position with a translation.
    """
    rotation = _rotation_z(roll) @ _rotation_z(axis) @ _rotation_x(tilt) @ _rotation_z(-axis)
    centre = np.array([[1.0, 0.0, -(width - 1) / 2], [0.0, 1.0, -(height - 1) / 2], [0, 0, 1.0]])
    if distance is None:
        plane = np.array([[*rotation[0, :2], 0.0], [*rotation[1, :2], 0.0], [0.0, 0.0, 1.0]])
        h = np.diag([scale, scale, 1.0]) @ plane @ centre
    else:
        depth = distance * math.hypot(width, height)
        plane = np.column_stack([rotation[:, 0], rotation[:, 1], [0.0, 0.0, depth]])
        h = np.diag([scale * depth, scale * depth, 1.0]) @ plane @ centre
    return h / h[2, 2]


def _map(h: np.ndarray, points: np.ndarray) -> np.ndarray:
    mapped = points @ h[:2, :2].T + h[:2, 2]
    return mapped / (points @ h[2, :2] + h[2, 2])[:, None]


def _smallest_stretch(h: np.ndarray, points: np.ndarray) -> float:
    """The smallest singular value of the warp's Jacobian at ``points`` (model pixels)."""
    smallest = math.inf
    for x, y in points:
        w = h[2, 0] * x + h[2, 1] * y + h[2, 2]
        u = (h[0, 0] * x + h[0, 1] * y + h[0, 2]) / w
        v = (h[1, 0] * x + h[1, 1] * y + h[1, 2]) / w
        jacobian = np.array(
            [
                [(h[0, 0] - u * h[2, 0]) / w, (h[0, 1] - u * h[2, 1]) / w],
                [(h[1, 0] - v * h[2, 0]) / w, (h[1, 1] - v * h[2, 1]) / w],
            ]
        )
        smallest = min(smallest, float(np.linalg.svd(jacobian, compute_uv=False)[-1]))
    return smallest


def _paste(
    canvas: np.ndarray, source: np.ndarray, h: np.ndarray, coverage: np.ndarray | None = None
) -> np.ndarray:
    """Blend ``source`` warped by ``h`` (source pixels → canvas pixels) into ``canvas`` in
    place, bilinearly, its edge weighted by its bilinear coverage; returns the coverage
    (canvas-sized, float32). ``coverage`` (the source's own alpha) defaults to ones."""
    import scipy.ndimage as ndi

    rows, cols = source.shape
    corners = _map(h, model_corners(cols, rows))
    low = np.floor(corners.min(axis=0) - 1).astype(int)
    high = np.ceil(corners.max(axis=0) + 2).astype(int)
    x0, y0 = max(low[0], 0), max(low[1], 0)
    x1, y1 = min(high[0], canvas.shape[1]), min(high[1], canvas.shape[0])
    alpha_full = np.zeros(canvas.shape, np.float32)
    if x0 >= x1 or y0 >= y1:
        return alpha_full
    ys, xs = np.mgrid[y0:y1, x0:x1].astype(np.float64)
    back = _map(np.linalg.inv(h), np.column_stack([xs.ravel(), ys.ravel()]))
    where = [back[:, 1].reshape(xs.shape), back[:, 0].reshape(xs.shape)]
    alpha_source = np.ones_like(source) if coverage is None else coverage
    alpha = ndi.map_coordinates(alpha_source, where, order=1, mode="constant", cval=0.0)
    colour = ndi.map_coordinates(source * alpha_source, where, order=1, mode="constant", cval=0.0)
    window = canvas[y0:y1, x0:x1]
    canvas[y0:y1, x0:x1] = window * (1.0 - alpha) + colour
    alpha_full[y0:y1, x0:x1] = alpha
    return alpha_full


def _translation(x: float, y: float) -> np.ndarray:
    return np.array([[1.0, 0.0, x], [0.0, 1.0, y], [0.0, 0.0, 1.0]])


def _random_crop(
    photographs: list[np.ndarray], side: tuple[int, int], rng: np.random.Generator
) -> np.ndarray:
    """A crop of a random photograph of ``side`` (rows, cols) or smaller when it is smaller,
    its contrast stretched to a random range inside [0, 1]."""
    photo = photographs[int(rng.integers(len(photographs)))]
    rows, cols = min(side[0], photo.shape[0]), min(side[1], photo.shape[1])
    top = int(rng.integers(0, photo.shape[0] - rows + 1))
    left = int(rng.integers(0, photo.shape[1] - cols + 1))
    crop = photo[top : top + rows, left : left + cols]
    low, high = float(crop.min()), float(crop.max())
    floor = rng.uniform(0.0, 0.3)
    span = rng.uniform(0.5, 1.0 - floor)
    return (floor + span * (crop - low) / max(high - low, 1e-6)).astype(np.float32)


def _background(
    photographs: list[np.ndarray], shape: tuple[int, int], rng: np.random.Generator
) -> np.ndarray:
    """A crop of half the scene's size of a random photograph, enlarged twice (bilinear) and
    padded by reflection when the photograph is smaller."""
    import scipy.ndimage as ndi

    crop = _random_crop(photographs, (shape[0] // 2 + 1, shape[1] // 2 + 1), rng)
    grown = ndi.zoom(crop, 2.0, order=1)[: shape[0], : shape[1]]
    pad = ((0, shape[0] - grown.shape[0]), (0, shape[1] - grown.shape[1]))
    return np.ascontiguousarray(np.pad(grown, pad, mode="reflect"), dtype=np.float32)


def _quad_mask(quad: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The pixels whose centres lie inside the convex quadrilateral (either orientation)."""
    mask = np.zeros(shape, bool)
    low = np.maximum(np.floor(quad.min(axis=0)).astype(int), 0)
    high = np.minimum(np.ceil(quad.max(axis=0)).astype(int) + 1, [shape[1], shape[0]])
    if (high <= low).any():
        return mask
    ys, xs = np.mgrid[low[1] : high[1], low[0] : high[0]]
    edges = np.roll(quad, -1, axis=0) - quad
    cross = [
        edge[0] * (ys - corner[1]) - edge[1] * (xs - corner[0])
        for corner, edge in zip(quad, edges, strict=True)
    ]
    inside = np.all([c >= 0 for c in cross], axis=0) | np.all([c <= 0 for c in cross], axis=0)
    mask[low[1] : high[1], low[0] : high[0]] = inside
    return mask


def _grow(mask: np.ndarray, margin: int) -> np.ndarray:
    """``mask`` dilated by ``margin`` pixels (a square), computed over its bounding box."""
    import scipy.ndimage as ndi

    rows, cols = np.nonzero(mask)
    grown = np.zeros_like(mask)
    if len(rows) == 0:
        return grown
    r0, r1 = max(rows.min() - margin, 0), min(rows.max() + margin + 1, mask.shape[0])
    c0, c1 = max(cols.min() - margin, 0), min(cols.max() + margin + 1, mask.shape[1])
    grown[r0:r1, c0:c1] = ndi.maximum_filter(mask[r0:r1, c0:c1], size=2 * margin + 1)
    return grown


def _occlude(
    canvas: np.ndarray,
    mask: np.ndarray,
    photographs: list[np.ndarray],
    occlusion: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Paste a rectangular crop centred on a random point of the instance's outline
    (``mask``), sized to hide a random fraction up to ``occlusion`` of it (about half the
    rectangle falls on the instance; shrunk until it hides no more than ``occlusion``);
    returns the pixels it covers."""
    import scipy.ndimage as ndi

    hidden = np.zeros(canvas.shape, bool)
    area = int(mask.sum())
    goal = rng.uniform(0.0, occlusion)
    if goal < 0.02 or area == 0:
        return hidden
    outline = np.argwhere(mask & ~ndi.minimum_filter(mask, size=3))
    y, x = outline[int(rng.integers(len(outline)))]
    side = math.sqrt(2.0 * goal * area)
    aspect = math.exp(rng.uniform(-0.5, 0.5))
    while True:
        height, width = max(int(side / aspect), 4), max(int(side * aspect), 4)
        top, left = max(y - height // 2, 0), max(x - width // 2, 0)
        bottom, right = min(top + height, canvas.shape[0]), min(left + width, canvas.shape[1])
        if mask[top:bottom, left:right].sum() <= occlusion * area or side < 8:
            break
        side *= 0.8
    patch = _random_crop(photographs, (bottom - top, right - left), rng)
    _paste(canvas, patch, _translation(left, top))
    hidden[top : top + patch.shape[0], left : left + patch.shape[1]] = True
    return hidden


class _Instance(NamedTuple):
    homography: np.ndarray
    tilt: float
    scale: float


def _place_instance(
    model_shape: tuple[int, int],
    scene_shape: tuple[int, int],
    taken: np.ndarray,
    rng: np.random.Generator,
    *,
    scales: tuple[float, float],
    max_tilt: float,
    perspective: float,
) -> _Instance | None:
    """A random pose whose quad lies inside the scene, 4 px clear of the scene's border and
    of the instances placed already (``taken``, grown by 4 px); None after 20 poses × 30
    positions."""
    rows, cols = model_shape
    corners = model_corners(cols, rows)
    margin = 4
    for _pose in range(20):
        scale = math.exp(rng.uniform(math.log(scales[0]), math.log(scales[1])))
        tilt = rng.uniform(0.0, max_tilt)
        axis, roll = rng.uniform(0.0, math.pi), rng.uniform(-math.pi, math.pi)
        distance = rng.uniform(1.5, 3.0) if rng.random() < perspective else None
        h = object_pose(
            cols,
            rows,
            scale=scale,
            tilt=math.radians(tilt),
            axis=axis,
            roll=roll,
            distance=distance,
        )
        quad = _map(h, corners)
        low, high = quad.min(axis=0), quad.max(axis=0)
        x_range = (margin - low[0], scene_shape[1] - 1 - margin - high[0])
        y_range = (margin - low[1], scene_shape[0] - 1 - margin - high[1])
        if x_range[0] > x_range[1] or y_range[0] > y_range[1]:
            continue
        for _position in range(30):
            shift = _translation(rng.uniform(*x_range), rng.uniform(*y_range))
            placed = shift @ h
            mask = _quad_mask(_map(placed, corners), scene_shape)
            if not (mask & taken).any():
                taken |= _grow(mask, margin)
                return _Instance(placed / placed[2, 2], tilt, scale)
    return None


def render_object_scenes(
    model: np.ndarray,
    photographs: list[np.ndarray],
    *,
    count: int,
    shape: tuple[int, int],
    instances: tuple[int, int],
    scales: tuple[float, float],
    max_tilt: float,
    perspective: float,
    occlusion: float,
    clutter: int,
    noise: float,
    seed: int,
) -> ObjectSceneSet:
    """``count`` scenes of ``shape`` holding ``instances`` (min, max) instances of ``model``
    each (fewer when no free place is found), on crops of ``photographs`` (see the module)."""
    import scipy.ndimage as ndi

    rng = np.random.default_rng(seed)
    rows, cols = model.shape
    corners = model_corners(cols, rows)
    images, homographies, owners, visible, tilts, scale_of = [], [], [], [], [], []
    for scene in range(count):
        canvas = _background(photographs, shape, rng)
        for _ in range(clutter):
            patch = _random_crop(
                photographs, (int(rng.integers(24, 120)), int(rng.integers(24, 120))), rng
            )
            zoom = rng.uniform(0.7, 1.5)
            turn = _rotation_z(rng.uniform(-math.pi, math.pi))
            centre = _translation(-(patch.shape[1] - 1) / 2, -(patch.shape[0] - 1) / 2)
            place = _translation(rng.uniform(0, shape[1]), rng.uniform(0, shape[0]))
            _paste(canvas, patch, place @ np.diag([zoom, zoom, 1.0]) @ turn @ centre)
        taken = np.zeros(shape, bool)
        placed: list[_Instance] = []
        for _ in range(int(rng.integers(instances[0], instances[1] + 1))):
            found = _place_instance(
                (rows, cols),
                shape,
                taken,
                rng,
                scales=scales,
                max_tilt=max_tilt,
                perspective=perspective,
            )
            if found is not None:
                placed.append(found)
        masks = []
        for instance in placed:
            shrink = min(_smallest_stretch(instance.homography, corners), 1.0)
            sigma = 0.5 * math.sqrt(max(1.0 / shrink**2 - 1.0, 0.0))
            seen = ndi.gaussian_filter(model, sigma) if sigma > 0.05 else model
            gain, offset = rng.uniform(0.7, 1.2), rng.uniform(-0.1, 0.1)
            lit = np.clip(gain * seen + offset, 0.0, 1.0).astype(np.float32)
            masks.append(_paste(canvas, lit, instance.homography) > 0.5)
        hidden = np.zeros(shape, bool)
        for mask in masks:
            hidden |= _occlude(canvas, mask, photographs, occlusion, rng)
        for instance, mask in zip(placed, masks, strict=True):
            homographies.append(instance.homography)
            owners.append(scene)
            visible.append(float((mask & ~hidden).sum() / max(mask.sum(), 1)))
            tilts.append(instance.tilt)
            scale_of.append(instance.scale)
        if noise > 0:
            canvas = canvas + rng.normal(0.0, noise, shape)
        images.append(np.clip(canvas, 0.0, 1.0))
    h = np.asarray(homographies, np.float64).reshape(-1, 3, 3)
    quads = np.array([_map(one, corners) for one in h], np.float64).reshape(-1, 4, 2)
    return ObjectSceneSet(
        np.asarray(images, np.float32).reshape(count, *shape),
        quads,
        h,
        np.asarray(owners, np.int64),
        np.asarray(visible, np.float64),
        np.asarray(tilts, np.float64),
        np.asarray(scale_of, np.float64),
    )


def _photograph(name: str) -> np.ndarray:
    """A bundled scikit-image photograph as gray float32 in [0, 1] (channel mean)."""
    from skimage import data

    image = np.asarray(getattr(data, name)(), np.float32)
    if image.ndim == 3:
        image = image[..., :3].mean(axis=2)
    return image / max(float(image.max()), 1.0) if image.max() > 1 else image


class ObjectScenesResult(NamedTuple):
    model: GrayImage
    scenes: ObjectScenes


@node(
    "synthetic.object_scenes",
    version=1,
    check=all_of(
        ordered(("min_instances", "max_instances"), ("min_scale", "max_scale")),
        at_most_values("count", "height", "width"),
    ),
)
def object_scenes(
    image: GrayImage,
    *,
    box: Annotated[list[Annotated[int, Field(ge=0)]], Field(min_length=4, max_length=4)] = [  # noqa: B006
        130,
        270,
        330,
        430,
    ],
    count: Annotated[int, Field(ge=1, le=1000)] = 12,
    height: Annotated[int, Field(ge=32, le=2048)] = 480,
    width: Annotated[int, Field(ge=32, le=2048)] = 640,
    min_instances: Annotated[int, Field(ge=0, le=20)] = 0,
    max_instances: Annotated[int, Field(ge=0, le=20)] = 3,
    min_scale: Annotated[float, Field(gt=0.05, le=8)] = 0.5,
    max_scale: Annotated[float, Field(gt=0.05, le=8)] = 2.0,
    max_tilt: Annotated[float, Field(ge=0, le=80)] = 60.0,
    perspective: Fraction = 0.5,
    occlusion: Annotated[float, Field(ge=0, le=0.9)] = 0.25,
    clutter: Annotated[int, Field(ge=0, le=200)] = 8,
    noise: Annotated[float, Field(ge=0, le=0.5)] = 0.01,
    photographs: Annotated[list[Photograph], Field(min_length=1)] = list(CLUTTER_PHOTOGRAPHS),  # type: ignore[arg-type]  # noqa: B006
    seed: Seed = 0,
) -> ObjectScenesResult:
    r"""Seeded scenes holding 0 to 3 instances of a model cut from ``image``, each under a
    random affine or perspective pose, with occlusion and clutter, and their true
    quadrilaterals (the pose and rendering are described in the module).

    The model is ``image[y0:y1, x0:x1]`` for ``box = [x0, y0, x1, y1]``. Each instance has
    a scale :math:`s` log-uniform in [``min_scale``, ``max_scale``] (at its centre), a
    tilt :math:`\theta` uniform in [0, ``max_tilt``] degrees out of the image plane about
    a random axis, a random rotation in the plane, and is seen in perspective (camera 1.5
    to 3 model diagonals away) with probability ``perspective``, else affinely; a random
    gain (0.7–1.2) and offset (±0.1) change its brightness. Instances do not overlap each
    other (a pose that finds no free place is drawn again, so large scales are somewhat
    rarer than log-uniform); an occluder (a crop of a photograph) on each one's outline
    hides a random fraction up to ``occlusion`` of it.

    Parameters
    ----------
    image : GrayImage
        The photograph the model is cut from (not one of ``photographs``).
    box : [x0, y0, x1, y1]
        The model's crop, in pixels (x1, y1 excluded).
    count : int
        Number of scenes.
    height, width : int
        Size of each scene in pixels.
    min_instances, max_instances : int
        Fewest and most instances per scene, drawn uniformly (fewer when one finds no
        free place in 20 poses × 30 positions).
    min_scale, max_scale : float
        Range of the scale at an instance's centre.
    max_tilt : float
        Largest out-of-plane rotation, in degrees.
    perspective : float
        Fraction of instances seen in perspective (the others: affine).
    occlusion : float
        Largest fraction of an instance an occluder hides.
    clutter : int
        Rotated crops of the photographs pasted over each background before the instances.
    noise : float
        Standard deviation of the Gaussian noise added last.
    photographs : list of str
        scikit-image photographs the backgrounds, clutter and occluders are cut from.
    seed : int
        Seed of everything random.

    Returns
    -------
    model : GrayImage
        The crop, (y1 - y0, x1 - x0).
    scenes : ObjectScenes
        Images (count, height, width) and the true instances: homographies from model
        to scene pixels and the model's corners mapped by them.

    References
    ----------
    .. [1] D. G. Lowe, "Distinctive image features from scale-invariant keypoints", IJCV
       60(2), 2004, section 7 (recognition of planar objects under affine and
       perspective change, occlusion and clutter).
    .. [2] R. Hartley, A. Zisserman, *Multiple View Geometry*, 2nd ed., 2004, section
       8.1.1 (the homography induced by a plane, :math:`H = K [r_1\; r_2\; t]`).
    """
    x0, y0, x1, y1 = box
    if not (x0 < x1 <= image.shape[1] and y0 < y1 <= image.shape[0]):
        raise ValueError(
            f"box {box} is not a crop [x0, y0, x1, y1] with x0 < x1 and y0 < y1 inside the "
            f"{image.shape[1]}×{image.shape[0]} image"
        )
    if x1 - x0 < 16 or y1 - y0 < 16:
        raise ValueError(f"box {box} gives a {x1 - x0}×{y1 - y0} model: make it at least 16×16")
    model = np.ascontiguousarray(image[y0:y1, x0:x1], dtype=np.float32)
    scenes = render_object_scenes(
        model,
        [_photograph(name) for name in photographs],
        count=count,
        shape=(height, width),
        instances=(min_instances, max_instances),
        scales=(min_scale, max_scale),
        max_tilt=max_tilt,
        perspective=perspective,
        occlusion=occlusion,
        clutter=clutter,
        noise=noise,
        seed=seed,
    )
    return ObjectScenesResult(model, scenes)
