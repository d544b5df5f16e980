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
from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import GrayImage, node

from ..shared.checks import all_of, at_most_values, ordered
from ..shared.params import Fraction, Seed
from ._compose import _background, _grow, _occlude, _paste, _quad_mask, _random_crop
from ._object_pose import _map, _rotation_z, _smallest_stretch, _translation, object_pose
from ._object_scene_set import ObjectScenes, ObjectSceneSet, model_corners

__all__ = [
    "CLUTTER_PHOTOGRAPHS",
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


def _clutter(
    canvas: np.ndarray,
    photographs: list[np.ndarray],
    shape: tuple[int, int],
    clutter: int,
    rng: np.random.Generator,
) -> None:
    """Paste ``clutter`` rotated, zoomed crops of ``photographs`` at random places."""
    for _ in range(clutter):
        patch = _random_crop(
            photographs, (int(rng.integers(24, 120)), int(rng.integers(24, 120))), rng
        )
        zoom = rng.uniform(0.7, 1.5)
        turn = _rotation_z(rng.uniform(-math.pi, math.pi))
        centre = _translation(-(patch.shape[1] - 1) / 2, -(patch.shape[0] - 1) / 2)
        place = _translation(rng.uniform(0, shape[1]), rng.uniform(0, shape[0]))
        _paste(canvas, patch, place @ np.diag([zoom, zoom, 1.0]) @ turn @ centre)


def _draw_instances(
    canvas: np.ndarray,
    model: np.ndarray,
    placed: list[_Instance],
    corners: np.ndarray,
    rng: np.random.Generator,
) -> list[np.ndarray]:
    """Paste each placed instance of ``model`` (blurred against aliasing, its brightness
    varied) and return the masks of their pixels."""
    import scipy.ndimage as ndi

    masks = []
    for instance in placed:
        shrink = min(_smallest_stretch(instance.homography, corners), 1.0)
        sigma = 0.5 * math.sqrt(max(1.0 / shrink**2 - 1.0, 0.0))
        seen = ndi.gaussian_filter(model, sigma) if sigma > 0.05 else model
        gain, offset = rng.uniform(0.7, 1.2), rng.uniform(-0.1, 0.1)
        lit = np.clip(gain * seen + offset, 0.0, 1.0).astype(np.float32)
        masks.append(_paste(canvas, lit, instance.homography) > 0.5)
    return masks


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
    rng = np.random.default_rng(seed)
    rows, cols = model.shape
    corners = model_corners(cols, rows)
    images, homographies, owners, visible, tilts, scale_of = [], [], [], [], [], []
    for scene in range(count):
        canvas = _background(photographs, shape, rng)
        _clutter(canvas, photographs, shape, clutter, rng)
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
        masks = _draw_instances(canvas, model, placed, corners, rng)
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
