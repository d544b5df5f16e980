"""Checkerboards seen through a known camera with lens distortion: truth for calibration.

A board lies in the world plane Z = 0 with its inner corners at
``(i·square, j·square, 0)``; a camera with distortion looks at it from Z < 0.
Each pixel's ray is found by undistorting the pixel (once for all views: the
intrinsics are shared), intersected with the plane, and the checker pattern is
box-filtered analytically over the pixel's footprint on the board, so edges
are anti-aliased without supersampling.
"""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, Camera, ImageT, PinholeCamera, Points3D, node

from ..camera import look_at, project_points, undistort_normalised
from ..shared.params import Fraction, Positive, Seed

__all__ = ["board_object_points", "board_views", "plane_view", "render_board"]

_DARK, _LIGHT, _BACKGROUND = 0.1, 0.9, 0.45


def board_object_points(columns: int, rows: int, square: float) -> np.ndarray:
    """The inner corners ``(i·square, j·square, 0)``, row by row, i fastest."""
    j, i = np.mgrid[0:rows, 0:columns]
    return np.column_stack([i.ravel() * square, j.ravel() * square, np.zeros(i.size)])


def _integrated_square_wave(t: np.ndarray) -> np.ndarray:
    """∫₀ᵗ s(τ) dτ for the ±1 square wave s of period 2 (s = +1 on [0, 1))."""
    frac = t - 2 * np.floor(t / 2)
    return np.where(frac < 1, frac, 2 - frac)


def _filtered_square_wave(t: np.ndarray, half_width: np.ndarray) -> np.ndarray:
    """The square wave box-filtered over [t − w, t + w]."""
    w = np.maximum(half_width, 1e-6)
    return (_integrated_square_wave(t + w) - _integrated_square_wave(t - w)) / (2 * w)


def _pixel_rays(camera: PinholeCamera, width: int, height: int) -> np.ndarray:
    """Normalised, undistorted ray directions ``H×W×2`` of every pixel centre."""
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    K = camera.K
    y = (v - K[1, 2]) / K[1, 1]
    x = (u - K[0, 2] - K[0, 1] * y) / K[0, 0]
    xy = undistort_normalised(np.column_stack([x.ravel(), y.ravel()]), camera.distortion)
    return xy.reshape(height, width, 2)


def render_board(
    rays: np.ndarray, R: np.ndarray, C: np.ndarray, columns: int, rows: int, square: float
) -> np.ndarray:
    """Render one view: ``rays`` from :func:`_pixel_rays`, pose ``R``, ``C``; float64 H×W."""
    directions = np.concatenate([rays, np.ones((*rays.shape[:2], 1))], axis=2) @ R  # Rᵀ d
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = -C[2] / directions[..., 2]
    hits = C[:2] + depth[..., None] * directions[..., :2]
    board = hits / square + 1.0  # square units, 0 at the board's outer edge
    valid = np.isfinite(board).all(axis=2) & (depth > 0)
    board = np.where(valid[..., None], board, -10.0)
    # footprint of a pixel on the board, from the neighbouring pixels' hits
    du = np.abs(np.gradient(board, axis=1))
    dv = np.abs(np.gradient(board, axis=0))
    half = 0.5 * (du + dv)
    checker = _filtered_square_wave(board[..., 0], half[..., 0]) * _filtered_square_wave(
        board[..., 1], half[..., 1]
    )
    squares_x, squares_y = columns + 1, rows + 1
    inside = (
        (board[..., 0] >= 0)
        & (board[..., 0] <= squares_x)
        & (board[..., 1] >= 0)
        & (board[..., 1] <= squares_y)
    )
    margin = (
        (board[..., 0] >= -1)
        & (board[..., 0] <= squares_x + 1)
        & (board[..., 1] >= -1)
        & (board[..., 1] <= squares_y + 1)
    )
    # square (0, 0) dark: the filtered wave product is +1 there
    image = np.where(inside, 0.5 * (_DARK + _LIGHT) - 0.5 * (_LIGHT - _DARK) * checker, _LIGHT)
    return np.where(margin & valid, image, _BACKGROUND)


def random_board_pose(
    rng: np.random.Generator, columns: int, rows: int, square: float, distance: float, tilt: float
) -> tuple[np.ndarray, np.ndarray]:
    """A camera pose looking at the board centre from ``distance``, tilted ≤ ``tilt``°."""
    centre = np.array([(columns - 1) / 2, (rows - 1) / 2, 0.0]) * square
    theta = np.deg2rad(rng.uniform(0.3, 1.0) * tilt)
    phi = rng.uniform(0, 2 * np.pi)
    direction = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), -np.cos(theta)])
    C = centre + distance * rng.uniform(0.9, 1.1) * direction
    target = centre + rng.uniform(-0.5, 0.5, 3) * square * np.array([1, 1, 0])
    R = look_at(C, target, roll=np.deg2rad(rng.uniform(-15, 15)))
    return R, C


class BoardViews(NamedTuple):
    views: Array
    corners: Array
    object_points: Points3D
    camera: Camera


def _board_outline(columns: int, rows: int, square: float) -> np.ndarray:
    """The corners (4, 3) of a rectangle two squares beyond the outermost inner corners, in
    world units: what must be seen for the whole board to be in the image."""
    outline = (
        np.array(
            [[-2, -2, 0], [columns + 1, -2, 0], [columns + 1, rows + 1, 0], [-2, rows + 1, 0]],
            float,
        )
        * square
    )
    return outline


def _inside(edge: np.ndarray, width: int, height: int) -> bool:
    """Whether the projected outline ``edge`` lies 4 px inside the image."""
    margin = 4.0
    return bool(
        np.isfinite(edge).all()
        and (edge >= margin).all()
        and (edge[:, 0] <= width - 1 - margin).all()
        and (edge[:, 1] <= height - 1 - margin).all()
    )


@node("synthetic.board_views", version=1)
def board_views(
    *,
    views: Annotated[int, Field(ge=1, le=100)] = 10,
    columns: Annotated[int, Field(ge=2, le=40)] = 9,
    rows: Annotated[int, Field(ge=2, le=40)] = 6,
    square: Positive = 25.0,
    width: Annotated[int, Field(ge=32, le=4096)] = 640,
    height: Annotated[int, Field(ge=32, le=4096)] = 480,
    focal: Positive = 800.0,
    aspect: Positive = 1.0,
    k1: float = -0.1,
    k2: float = 0.0,
    p1: float = 0.0,
    p2: float = 0.0,
    tilt: Annotated[float, Field(ge=0, lt=80)] = 35.0,
    fill: Annotated[float, Field(gt=0, le=1)] = 0.6,
    blur: Annotated[float, Field(ge=0)] = 0.7,
    noise: Annotated[float, Field(ge=0)] = 0.01,
    seed: Seed = 0,
) -> BoardViews:
    """Several views of a checkerboard through one known camera, with their true corners.

    The camera has focal lengths ``(focal, aspect·focal)``, principal point
    at the image centre (offset by a seeded few pixels) and distortion
    ``(k1, k2, p1, p2, 0)``; each view is a seeded pose looking at the board
    from its front (world Z < 0), tilted by up to ``tilt`` degrees, at the
    distance where the board spans about ``fill`` of the image width. Every
    view keeps the whole board inside the image. Images are Gaussian-blurred
    by ``blur`` px (the optics) and get Gaussian noise ``noise`` (intensity).

    Parameters
    ----------
    views : int
        Number of views.
    columns, rows : int
        Inner corners along the board's x and y (9 × 6: 10 × 7 squares).
    square : float
        Side of a square, in world units (millimetres).
    width, height : int
        Image size in pixels.
    focal : float
        Focal length fx in pixels.
    aspect : float
        fy / fx.
    k1, k2 : float
        Radial distortion coefficients.
    p1, p2 : float
        Tangential distortion coefficients.
    tilt : float
        Largest angle between the optical axis and the board normal, degrees.
    fill : float
        Fraction of the image width the board spans.
    blur : float
        σ of the Gaussian blur, pixels.
    noise : float
        σ of the additive Gaussian noise, intensity units.
    seed : int
        Seed of poses, principal point and noise.

    Returns
    -------
    views : (views, height, width) float32 images in [0, 1]
    corners : (views, rows·columns, 2) float64, the true (distorted) pixel
        positions of the inner corners, in the order of ``object_points``
    object_points : (rows·columns, 3) the corners on the board, Z = 0
    camera : the rendering camera (its pose is the first view's)
    """
    from ..shared.separable import smooth_gaussian

    rng = np.random.default_rng(seed)
    K = np.array(
        [
            [focal, 0.0, (width - 1) / 2 + rng.uniform(-5, 5)],
            [0.0, aspect * focal, (height - 1) / 2 + rng.uniform(-5, 5)],
            [0.0, 0.0, 1.0],
        ]
    )
    distortion = np.array([k1, k2, p1, p2, 0.0])
    intrinsics = PinholeCamera(K, distortion=distortion, size=np.array([width, height]))
    rays = _pixel_rays(intrinsics, width, height)
    objects = board_object_points(columns, rows, square)
    outline = _board_outline(columns, rows, square)
    distance = (columns + 3) * square * focal / (fill * width)
    images: list[np.ndarray] = []
    corners: list[np.ndarray] = []
    poses: list[tuple[np.ndarray, np.ndarray]] = []
    while len(images) < views:
        R, C = random_board_pose(rng, columns, rows, square, distance, tilt)
        edge = project_points(outline, K, R, C, distortion)
        if not _inside(edge, width, height):
            continue
        image = render_board(rays, R, C, columns, rows, square)
        if blur > 0:
            image = smooth_gaussian(image, blur, "nearest")
        image = image + rng.normal(0, noise, image.shape) if noise > 0 else image
        images.append(np.clip(image, 0, 1).astype(np.float32))
        corners.append(project_points(objects, K, R, C, distortion))
        poses.append((R, C))
    camera = PinholeCamera(
        K, R=poses[0][0], C=poses[0][1], distortion=distortion, size=np.array([width, height])
    )
    return BoardViews(np.stack(images), np.stack(corners), objects, camera)


@node("synthetic.plane_view", version=1)
def plane_view(
    texture: ImageT,
    camera: Camera,
    *,
    scale: Positive = 1.0,
    background: Fraction = 0.0,
) -> ImageT:
    """A textured plane photographed by a known camera (with its lens distortion).

    The texture lies on the world plane Z = 0, pixel (column, row) at
    ``(scale·column, scale·row, 0)``. Each image pixel's ray (undistorted by
    Newton's method) meets the plane; the texture is sampled there
    bilinearly. Points off the texture, or rays that miss the plane, show
    ``background``.

    Parameters
    ----------
    texture : Image
        The picture on the plane.
    camera : Camera
        The camera (K, R, C̃, distortion, size: the output is size[1] × size[0]).
    scale : float
        World units per texture pixel.
    background : float
        Intensity where the plane or the texture is not seen.

    Raises
    ------
    ValueError
        When the camera has no image size.
    """
    from scipy import ndimage

    width, height = (int(v) for v in camera.size)
    if width < 1 or height < 1:
        raise ValueError(
            f"camera size must be positive (width, height), got {camera.size.tolist()}"
        )
    rays: np.ndarray = _pixel_rays(camera, width, height)
    directions = np.concatenate([rays, np.ones((*rays.shape[:2], 1))], axis=2) @ camera.R
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = -camera.C[2] / directions[..., 2]
    hits = (camera.C[:2] + depth[..., None] * directions[..., :2]) / scale
    seen = np.isfinite(hits).all(axis=2) & (depth > 0)
    hits = np.where(seen[..., None], hits, -1e6)
    rows, cols = texture.shape[:2]
    seen &= (hits[..., 0] >= 0) & (hits[..., 0] <= cols - 1)
    seen &= (hits[..., 1] >= 0) & (hits[..., 1] <= rows - 1)
    coords = [hits[..., 1], hits[..., 0]]
    channels = [texture] if texture.ndim == 2 else [texture[..., c] for c in range(3)]
    sampled = [
        np.where(seen, ndimage.map_coordinates(ch, coords, order=1, mode="nearest"), background)
        for ch in channels
    ]
    out = sampled[0] if texture.ndim == 2 else np.stack(sampled, axis=-1)
    return np.clip(out, 0, 1).astype(np.float32)
