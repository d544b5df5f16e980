"""Perspective warps and two-view stitching."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import BinaryImage, ColorImage, Conformance, Homography, Image, node

from ..shared.params import MAX_SIDE
from ._homography import apply_homography

__all__ = ["sample_homography", "stitch", "warp"]


def sample_homography(
    image: np.ndarray,
    inverse: np.ndarray,
    shape: tuple[int, int],
    offset: tuple[float, float] = (0.0, 0.0),
    clip: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Bilinear samples of ``image`` at ``inverse`` applied to each output pixel, and validity.

    Output pixel ``(x, y)`` (plus ``offset``) takes the input at
    :math:`H^{-1} (x, y, 1)^T`; pixels that map outside the input are 0 and
    marked invalid. ``clip`` keeps the result in [0, 1].
    """
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


@node("geometry.warp", version=1, conformance=Conformance("max_abs", 1e-4))
def warp(
    image: Image,
    homography: Homography,
    *,
    width: Annotated[int, Field(ge=0, le=MAX_SIDE)] = 0,
    height: Annotated[int, Field(ge=0, le=MAX_SIDE)] = 0,
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
    warped, inside = sample_homography(image, inverse, shape)
    return Warped(warped.astype(np.float32), inside)


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
    moved_base, _ = sample_homography(colour(base), np.eye(3), canvas_shape, offset)
    moved_other, _ = sample_homography(
        colour(other), np.linalg.inv(homography), canvas_shape, offset
    )
    weight_base, _ = sample_homography(
        feather(base.shape[:2]), np.eye(3), canvas_shape, offset, False
    )
    weight_other, _ = sample_homography(
        feather(other.shape[:2]), np.linalg.inv(homography), canvas_shape, offset, False
    )
    total = weight_base + weight_other
    blended = moved_base * weight_base[..., None] + moved_other * weight_other[..., None]
    np.divide(blended, total[..., None], out=blended, where=total[..., None] > 0)
    return np.clip(blended, 0, 1).astype(np.float32)
