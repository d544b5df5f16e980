"""A rectified pair of a piecewise-planar scene textured with photographs, with its exact
disparity and occlusion mask."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Literal, get_args

import numpy as np
from pydantic import Field

from graphvision import node

from ..shared.checks import ordered
from ..shared.params import Seed
from ._stereo_pair import StereoPair

__all__ = ["PHOTOGRAPHS", "planar_stereo_scene"]

Photograph = Literal[
    "astronaut", "brick", "camera", "cat", "clock", "coffee", "coins", "grass", "gravel",
    "moon", "page", "rocket", "text",
]  # fmt: skip
"""scikit-image's bundled photographs and textures (no synthetic pattern, no stereo pair)."""

PHOTOGRAPHS: tuple[str, ...] = get_args(Photograph)

SUPERSAMPLE = 3
"""Samples per pixel side: each pixel is the mean of 3 × 3 point samples (its area)."""


@dataclass(frozen=True)
class _Plane:
    """A planar patch in the left camera's pixel coordinates: disparity
    ``d = c + a·x + b·y`` on the region ``inside(x, y)``, texture ``photo`` mapped by
    ``(u, v) = A (x − x0, y − y0) + centre``, and a contrast ``gain``, ``level``."""

    a: float
    b: float
    c: float
    region: tuple[str, tuple[float, ...]]
    photo: str
    affine: tuple[float, float, float, float]
    origin: tuple[float, float]
    gain: float
    level: float

    def disparity(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return self.c + self.a * x + self.b * y

    def left_x(self, x_right: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The left column whose point of the plane the right camera sees at ``x_right``:
        ``x_r = x − d(x, y)`` solved for ``x``."""
        return (x_right + self.c + self.b * y) / (1.0 - self.a)

    def inside(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        kind, values = self.region
        if kind == "all":
            return np.ones(np.broadcast(x, y).shape, dtype=bool)
        if kind == "below":  # y >= values[0]
            return np.broadcast_to(y >= values[0], np.broadcast(x, y).shape)
        if kind == "disc":
            cx, cy, radius = values
            return (x - cx) ** 2 + (y - cy) ** 2 <= radius**2
        if kind == "bar":  # x0 <= x < x1, y0 <= y < y1
            x0, x1, y0, y1 = values
            return (x >= x0) & (x < x1) & (y >= y0) & (y < y1)
        # a rectangle turned by an angle: centre, half sides, angle
        cx, cy, half_w, half_h, angle = values
        cos, sin = np.cos(angle), np.sin(angle)
        along = (x - cx) * cos + (y - cy) * sin
        across = -(x - cx) * sin + (y - cy) * cos
        return (np.abs(along) <= half_w) & (np.abs(across) <= half_h)


def _photo(name: str) -> np.ndarray:
    """The cubic B-spline coefficients of the photograph, gray in [0, 1] (sampled by
    ``map_coordinates(..., order=3, mode="mirror", prefilter=False)``)."""
    from scipy import ndimage

    from ..colour import to_gray
    from ..io import read_sample

    image = read_sample(name)
    gray = np.asarray(to_gray(image) if image.ndim == 3 else image, dtype=np.float64)
    coefficients: np.ndarray = ndimage.spline_filter(gray, order=3, mode="mirror")
    return coefficients


def _layout(
    rng: np.random.Generator, width: int, height: int, photos: list[str], far: float, near: float
) -> list[_Plane]:
    """A back wall, a floor, two turned slanted boards, a fronto-parallel disc and a thin
    pole, placed at random; disparities between ``far`` (the least) and ``near``."""
    span = near - far

    def plane(a: float, b: float, c: float, region: tuple[str, tuple[float, ...]]) -> _Plane:
        """The plane with a photograph turned, scaled and shifted at random."""
        scale = rng.uniform(0.6, 1.5)  # photograph pixels per image pixel
        angle = rng.uniform(-0.5, 0.5)
        cos, sin = np.cos(angle), np.sin(angle)
        photo = photos[int(rng.integers(len(photos)))]
        affine = (scale * cos, -scale * sin, scale * sin, scale * cos)
        origin = (rng.uniform(0, width), rng.uniform(0, height))
        return _Plane(
            a, b, c, region, photo, affine, origin, rng.uniform(0.6, 1.0), rng.uniform(-0.1, 0.1)
        )

    # the wall: far, slanted left to right and a little top to bottom
    slope_x = rng.uniform(-0.06, 0.06) * span / width
    slope_y = rng.uniform(0.0, 0.05) * span / height
    wall_c = far + 0.06 * span - min(slope_x, 0) * width
    planes = [plane(slope_x, slope_y, wall_c, ("all", ()))]
    # the floor: from the horizon to the bottom row, its disparity growing to about `near`
    horizon = rng.uniform(0.45, 0.6) * height
    wall_at_horizon = wall_c + slope_y * horizon + max(slope_x, 0) * width
    bottom = near - rng.uniform(0.0, 0.08) * span
    floor_b = (bottom - wall_at_horizon) / (height - horizon)
    floor_c = wall_at_horizon - floor_b * horizon + 0.5
    planes.append(plane(0.0, floor_b, floor_c, ("below", (horizon,))))
    # two boards turned in the image and slanted in depth, kept inside [far + 1, near - 1]
    for _ in range(2):
        cx = rng.uniform(0.25, 0.75) * width
        cy = rng.uniform(0.25, 0.55) * height
        centre_d = far + rng.uniform(0.3, 0.6) * span
        slant_x = rng.uniform(-0.12, 0.12)  # disparity per column: a board turned about y
        slant_y = rng.uniform(-0.05, 0.05)
        half_w = rng.uniform(0.12, 0.2) * width
        half_h = rng.uniform(0.12, 0.22) * height
        reach = (abs(slant_x) + abs(slant_y)) * np.hypot(half_w, half_h)
        room = min(centre_d - far, near - centre_d) - 1.0
        if reach > room:
            slant_x, slant_y = slant_x * room / reach, slant_y * room / reach
        region = ("turned", (cx, cy, half_w, half_h, rng.uniform(-0.4, 0.4)))
        planes.append(plane(slant_x, slant_y, centre_d - slant_x * cx - slant_y * cy, region))
    # a fronto-parallel disc, nearer
    disc = (
        rng.uniform(0.2, 0.8) * width,
        rng.uniform(0.3, 0.7) * height,
        rng.uniform(0.07, 0.12) * height,
    )
    planes.append(plane(0.0, 0.0, far + rng.uniform(0.65, 0.8) * span, ("disc", disc)))
    # a thin pole standing on the floor (from the top to where the floor is as near)
    pole_x = rng.uniform(0.15, 0.85) * width
    pole_d = near - rng.uniform(0.0, 0.1) * span
    bar = (pole_x, pole_x + rng.uniform(4.0, 8.0), -1.0, (pole_d - floor_c) / floor_b)
    planes.append(plane(0.0, 0.0, pole_d, ("bar", bar)))
    return planes


def _front(
    planes: list[_Plane], x: np.ndarray, y: np.ndarray, right: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Index of the nearest plane (largest disparity) seen at each sample, its disparity,
    and the left column of the point seen (``x`` itself for the left camera)."""
    best = np.full(x.shape, -np.inf)
    which = np.full(x.shape, -1, dtype=np.int64)
    column = np.zeros(x.shape)
    for i, plane in enumerate(planes):
        x_left = plane.left_x(x, y) if right else x
        d = plane.disparity(x_left, y)
        nearer = plane.inside(x_left, y) & (d > best)
        best = np.where(nearer, d, best)
        which = np.where(nearer, i, which)
        column = np.where(nearer, x_left, column)
    return which, best, column


def _shade(
    planes: list[_Plane], photos: dict[str, np.ndarray], x: np.ndarray, y: np.ndarray, right: bool
) -> np.ndarray:
    """Intensity of each point sample: the nearest plane's texture at its point."""
    from scipy import ndimage

    which, _, column = _front(planes, x, y, right)
    out = np.zeros(x.shape)
    for i, plane in enumerate(planes):
        mine = which == i
        if not mine.any():
            continue
        a11, a12, a21, a22 = plane.affine
        photo = photos[plane.photo]
        dx, dy = column[mine] - plane.origin[0], y[mine] - plane.origin[1]
        u = a11 * dx + a12 * dy + photo.shape[1] / 2
        v = a21 * dx + a22 * dy + photo.shape[0] / 2
        values = ndimage.map_coordinates(photo, [v, u], order=3, mode="mirror", prefilter=False)
        out[mine] = plane.level + 0.5 + plane.gain * (values - 0.5)
    return out


def _render(
    planes: list[_Plane], photos: dict[str, np.ndarray], width: int, height: int, right: bool
) -> np.ndarray:
    """Each pixel the mean of SUPERSAMPLE² point samples over its area."""
    offsets = (np.arange(SUPERSAMPLE) + 0.5) / SUPERSAMPLE - 0.5
    total = np.zeros((height, width))
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    for oy in offsets:
        for ox in offsets:
            total += _shade(planes, photos, x + ox, y + oy, right)
    return total / SUPERSAMPLE**2


@node(
    "synthetic.planar_stereo_scene",
    version=1,
    check=ordered(("min_disparity", "max_disparity"), strict=True),
)
def planar_stereo_scene(
    *,
    width: Annotated[int, Field(ge=64, le=2048)] = 480,
    height: Annotated[int, Field(ge=48, le=2048)] = 360,
    min_disparity: Annotated[float, Field(ge=1, le=256)] = 10.0,
    max_disparity: Annotated[float, Field(ge=1, le=256)] = 45.0,
    textures: Annotated[tuple[Photograph, ...], Field(min_length=1)] = (
        "astronaut",
        "coffee",
        "cat",
        "rocket",
        "brick",
        "gravel",
    ),
    gain: Annotated[float, Field(gt=0)] = 1.0,
    offset: float = 0.0,
    noise: Annotated[float, Field(ge=0)] = 0.005,
    seed: Seed = 0,
) -> StereoPair:
    r"""A rectified pair of a piecewise-planar scene textured with photographs, with the
    exact disparity and occlusion mask.

    The scene, placed at random from ``seed``: a slanted back wall, a floor
    from a horizon to the bottom row, two boards turned in the image and
    slanted in depth, a fronto-parallel disc and a thin pole (4–8 px) in
    front. A plane is given in the left camera's pixels by its disparity
    :math:`d(x, y) = c + a x + b y` (a plane in space has a disparity affine
    in the image) and its texture, a photograph from ``textures`` turned,
    scaled and shifted at random. The right camera sees at :math:`x_r` the
    point of each plane with :math:`x_r = x - d(x, y)`, i.e.
    :math:`x = (x_r + c + b y) / (1 - a)`, and shows the nearest (largest
    disparity) of them: occlusions are exact. Each pixel averages 3 × 3
    point samples over its area (edges are mixed as a camera mixes them);
    the truth is the nearest plane's disparity at the pixel centre.

    The right image is then :math:`\text{gain} \cdot R + \text{offset}` (a
    camera with another exposure), both get Gaussian noise of σ ``noise``,
    and both are clipped to [0, 1] and quantised to 8 bits (k / 255, as a
    camera delivers them: ``np.round(255 * image)`` is exact).

    Parameters
    ----------
    width, height : int
        Image size.
    min_disparity, max_disparity : float
        Disparities of the farthest and nearest points of the scene, pixels.
    textures : tuple of str
        scikit-image photographs the planes are textured with (drawn at random).
    gain, offset : float
        Exposure of the right camera relative to the left.
    noise : float
        σ of the Gaussian noise of both images.
    seed : int
        Seed of the layout, the textures and the noise.

    Returns
    -------
    left, right : GrayImage
    disparity : Disparity
        The left image's true disparity (every pixel).
    visible : BinaryImage
        Left pixels whose point the right camera sees: not occluded by a
        nearer plane, not outside the right image.

    References
    ----------
    .. [1] D. Scharstein & R. Szeliski, "A taxonomy and evaluation of dense two-frame
       stereo correspondence algorithms", IJCV 47, 2002 (piecewise-planar scenes with
       photographic textures as stereo ground truth).
    """
    rng = np.random.default_rng(seed)
    photos: dict[str, np.ndarray] = {name: _photo(name) for name in dict.fromkeys(textures)}
    planes = _layout(rng, width, height, list(textures), min_disparity, max_disparity)
    images = [_render(planes, photos, width, height, right) for right in (False, True)]
    images[1] = gain * images[1] + offset
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    which, truth, _ = _front(planes, x, y, right=False)
    # visible: the right camera's nearest plane at x − d is this pixel's own plane
    seen, _, _ = _front(planes, x - truth, y, right=True)
    visible = (x - truth >= 0) & (seen == which)
    pair = []
    for image in images:
        noisy = image + rng.normal(0.0, noise, image.shape) if noise > 0 else image
        pair.append((np.round(255 * np.clip(noisy, 0.0, 1.0)) / 255).astype(np.float32))
    return StereoPair(pair[0], pair[1], truth.astype(np.float32), visible)
