"""Perspective warps, seeded random homographies, and two-view stitching."""

from __future__ import annotations

from typing import Annotated, Generic, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import BinaryImage, ColorImage, Homography, Image, ImageT, node

from ._homography import apply_homography

__all__ = ["random_warp", "stitch", "two_views", "warp"]


def _sample(
    image: np.ndarray,
    inverse: np.ndarray,
    shape: tuple[int, int],
    offset: tuple[float, float] = (0.0, 0.0),
    clip: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Bilinear samples of ``image`` at ``inverse`` applied to each output pixel, and validity."""
    import scipy.ndimage as ndi

    rows, cols = shape
    ys, xs = np.mgrid[0:rows, 0:cols].astype(np.float64)
    grid = np.column_stack([xs.ravel() + offset[0], ys.ravel() + offset[1]])
    source = apply_homography(inverse, grid)
    sx = source[:, 0].reshape(shape)
    sy = source[:, 1].reshape(shape)
    inside = (
        (sx >= -0.5) & (sx <= image.shape[1] - 0.5) & (sy >= -0.5) & (sy <= image.shape[0] - 0.5)
    )
    inside &= np.isfinite(sx) & np.isfinite(sy)
    sx, sy = np.nan_to_num(sx), np.nan_to_num(sy)
    planes = [image] if image.ndim == 2 else [image[..., c] for c in range(image.shape[2])]
    out = [
        ndi.map_coordinates(p, [sy, sx], order=1, mode="nearest", output=np.float32) for p in planes
    ]
    warped = out[0] if image.ndim == 2 else np.stack(out, axis=2)
    warped[~inside] = 0.0
    return (np.clip(warped, 0.0, 1.0) if clip else warped), inside


class Warped(NamedTuple):
    image: Image
    valid: BinaryImage


@node("geometry.warp", version=1)
def warp(
    image: Image,
    homography: Homography,
    *,
    width: Annotated[int, Field(ge=0)] = 0,
    height: Annotated[int, Field(ge=0)] = 0,
) -> Warped:
    r"""Perspective warp: output pixel :math:`x'` takes input :math:`H^{-1} x'`, bilinearly.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32
    homography : (3, 3) float64, mapping input to output coordinates
    width, height : int
        Output size; 0 keeps the input's.

    Returns
    -------
    image : the warped image (black outside the input)
    valid : (H', W') bool, pixels that come from inside the input
    """
    shape = (height or image.shape[0], width or image.shape[1])
    try:
        inverse = np.linalg.inv(homography)
    except np.linalg.LinAlgError:
        raise ValueError("the homography is singular: it has no inverse to warp with") from None
    warped, inside = _sample(image, inverse, shape)
    return Warped(warped.astype(np.float32), inside)


def _random_homography(
    shape: tuple[int, int],
    rng: np.random.Generator,
    max_rotation: float,
    scale_range: tuple[float, float],
    perspective: float,
) -> np.ndarray:
    rows, cols = shape
    centre = np.array([[1, 0, -(cols - 1) / 2], [0, 1, -(rows - 1) / 2], [0, 0, 1.0]])
    angle = np.deg2rad(rng.uniform(-max_rotation, max_rotation))
    scale = rng.uniform(*scale_range)
    similarity = np.array(
        [
            [scale * np.cos(angle), -scale * np.sin(angle), 0],
            [scale * np.sin(angle), scale * np.cos(angle), 0],
            [0, 0, 1.0],
        ]
    )
    size = max(rows, cols)
    projective = np.eye(3)
    projective[2, :2] = rng.uniform(-perspective, perspective, 2) / size
    h = np.linalg.inv(centre) @ projective @ similarity @ centre
    return h / h[2, 2]


class RandomWarp(NamedTuple, Generic[ImageT]):
    image: ImageT
    homography: Homography


@node("geometry.random_warp", version=1)
def random_warp(
    image: ImageT,
    *,
    max_rotation: Annotated[float, Field(ge=0, le=180)] = 30.0,
    min_scale: Annotated[float, Field(gt=0)] = 0.7,
    max_scale: Annotated[float, Field(gt=0)] = 1.3,
    perspective: Annotated[float, Field(ge=0, le=1)] = 0.3,
    seed: Annotated[int, Field(ge=0)] = 0,
) -> RandomWarp[ImageT]:
    """Warp the image by a seeded random homography about its centre, same output size.

    The homography is a rotation by up to ``max_rotation`` degrees, a scale
    in ``[min_scale, max_scale]`` and a perspective term of up to
    ``perspective`` (in units of the image size), all about the image centre.

    Parameters
    ----------
    image : Image
        The image to warp.
    max_rotation : float
        Largest rotation, in degrees, either way.
    min_scale, max_scale : float
        Range of the isotropic scale.
    perspective : float
        Largest perspective term, in units of the image size.
    seed : int
        Seed of the random homography.

    Returns
    -------
    image : the warped image
    homography : the true homography, mapping ``image`` coordinates to the warped ones
    """
    if min_scale > max_scale:
        raise ValueError(f"min_scale ({min_scale}) must not exceed max_scale ({max_scale})")
    rng = np.random.default_rng(seed)
    h = _random_homography(image.shape[:2], rng, max_rotation, (min_scale, max_scale), perspective)
    warped, _ = _sample(image, np.linalg.inv(h), image.shape[:2])
    return RandomWarp(warped.astype(np.float32), h)


class TwoViews(NamedTuple, Generic[ImageT]):
    left: ImageT
    right: ImageT
    homography: Homography


@node("geometry.two_views", version=1)
def two_views(
    image: ImageT,
    *,
    overlap: Annotated[float, Field(gt=0.1, lt=1)] = 0.5,
    rotation: Annotated[float, Field(ge=0, le=45)] = 8.0,
    perspective: Annotated[float, Field(ge=0, le=0.5)] = 0.1,
    seed: Annotated[int, Field(ge=0)] = 0,
) -> TwoViews[ImageT]:
    """Two overlapping views of one image: the left and right crops, each under its own homography.

    Each view is ``(1 + overlap) / 2`` of the width. The left one is the left
    crop as it is; the right one is the right crop seen through a seeded
    homography (rotation up to ``rotation`` degrees, a perspective term).

    Parameters
    ----------
    image : Image
        The scene both views look at.
    overlap : float
        Fraction of the image width the two crops share.
    rotation : float
        Largest rotation of each view, in degrees.
    perspective : float
        Largest perspective term of each view, in units of the image size.
    seed : int
        Seed of both homographies.

    Returns
    -------
    left, right : the two views
    homography : the true map from ``right`` coordinates to ``left`` coordinates
    """
    rows, cols = image.shape[:2]
    view = int(cols * (1 + overlap) / 2)
    shift = cols - view
    left = np.ascontiguousarray(image[:, :view])
    rng = np.random.default_rng(seed)
    local = _random_homography((rows, view), rng, rotation, (0.9, 1.1), perspective)
    # right view pixel -> its crop pixel (inverse of local) -> full image (+shift) -> left view
    crop_to_full = np.array([[1, 0, shift], [0, 1, 0], [0, 0, 1.0]])
    right, _ = _sample(image[:, shift:], np.linalg.inv(local), (rows, view))
    to_left = crop_to_full @ np.linalg.inv(local)
    return TwoViews(left, right.astype(np.float32), to_left / to_left[2, 2])


@node("geometry.stitch", version=1)
def stitch(base: Image, other: Image, homography: Homography) -> ColorImage:
    r"""Stitch ``other`` onto ``base``: a canvas holding both, overlap blended by feathering.

    ``homography`` maps ``other`` coordinates into ``base`` coordinates. The
    canvas is the bounding box of ``base`` and the mapped corners of
    ``other``; each image is weighted by its pixels' distance to its own
    border (feathering), so seams fade out.

    Parameters
    ----------
    base : Image
        The image that keeps its frame.
    other : Image
        The image mapped into ``base``'s frame.
    homography : Homography
        Maps ``other``'s pixel coordinates to ``base``'s.

    Returns
    -------
    panorama : (H, W, 3) float32
    """
    import scipy.ndimage as ndi

    rows, cols = other.shape[:2]
    corners = np.array([[0, 0], [cols - 1, 0], [cols - 1, rows - 1], [0, rows - 1]], float)
    mapped = apply_homography(homography, corners)
    if not np.isfinite(mapped).all():
        raise ValueError("the homography maps the other image to infinity: cannot stitch")
    points = np.vstack([mapped, [[0, 0], [base.shape[1] - 1, base.shape[0] - 1]]])
    low = np.floor(points.min(axis=0))
    high = np.ceil(points.max(axis=0))
    width, height = int(high[0] - low[0]) + 1, int(high[1] - low[1]) + 1
    if width * height > 64 * base.size:
        raise ValueError(
            f"the panorama would be {width}×{height} pixels: the homography is "
            "implausible for stitching"
        )
    offset = (float(low[0]), float(low[1]))

    def colour(image: np.ndarray) -> np.ndarray:
        return image if image.ndim == 3 else np.repeat(image[..., None], 3, axis=2)

    def feather(shape: tuple[int, int]) -> np.ndarray:
        weight = np.zeros((shape[0] + 2, shape[1] + 2), np.float32)
        weight[1:-1, 1:-1] = 1
        return ndi.distance_transform_cdt(weight)[1:-1, 1:-1].astype(np.float32)

    canvas_shape = (height, width)
    moved_base, _ = _sample(colour(base), np.eye(3), canvas_shape, offset)
    moved_other, _ = _sample(colour(other), np.linalg.inv(homography), canvas_shape, offset)
    weight_base, _ = _sample(feather(base.shape[:2]), np.eye(3), canvas_shape, offset, False)
    weight_other, _ = _sample(
        feather(other.shape[:2]), np.linalg.inv(homography), canvas_shape, offset, False
    )
    total = weight_base + weight_other
    blended = moved_base * weight_base[..., None] + moved_other * weight_other[..., None]
    np.divide(blended, total[..., None], out=blended, where=total[..., None] > 0)
    return np.clip(blended, 0, 1).astype(np.float32)
