"""Gaussian and Laplacian pyramids, naive subsampling beside them, and reconstruction."""

from __future__ import annotations

import itertools
from functools import lru_cache
from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import ColorImage, Conformance, FloatImage, GrayImage, Image, node

from ._ports import ImagePyramid, Pyramid

__all__ = [
    "blur",
    "expand",
    "gaussian_levels",
    "gaussian_pyramid",
    "laplacian_pyramid",
    "mosaic",
    "naive_pyramid",
    "pyramid_level",
    "reconstruct",
    "zone_plate",
]

Levels = Annotated[int, Field(ge=1, le=16, description="Number of levels, the image included.")]
Sigma = Annotated[float, Field(gt=0, le=10, description="Gaussian σ before each halving.")]


def blur(image: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing of each channel (mirror boundary), truncated at 3σ, in float32."""
    from ..shared.separable import smooth_gaussian

    return smooth_gaussian(image, sigma, "mirror", truncate=3.0)


def expand(coarse: np.ndarray, shape: tuple[int, ...], sigma: float) -> np.ndarray:
    """Up-sample ``coarse`` to ``shape``: samples at even pixels, zeros between, blurred and
    multiplied by 4 so the mean is kept (Burt and Adelson's EXPAND)."""
    fine = np.zeros(shape, dtype=np.float32)
    fine[::2, ::2] = coarse
    return blur(fine, sigma) * np.float32(4.0)


@lru_cache(maxsize=64)
def _chain_plan(
    shape: tuple[int, int], levels: int, sigma: float
) -> tuple[list[tuple[int, int]], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Shapes of the levels, their table, the end and size of each level after the first in
    the buffer, and the float32 taps: kept for the next call of the same shape (read-only;
    at 512² building them cost a quarter of the kernel's time)."""
    from ..shared.separable import gaussian_taps

    shapes = [shape]
    while len(shapes) < levels and min(shapes[-1]) >= 2:
        shapes.append(((shapes[-1][0] + 1) // 2, (shapes[-1][1] + 1) // 2))
    table = np.array(shapes, dtype=np.int64)
    sizes = table[1:, 0] * table[1:, 1]
    ends = np.cumsum(sizes)
    taps = gaussian_taps(sigma, 3.0).astype(np.float32)
    for array in (table, sizes, ends, taps):
        array.flags.writeable = False
    return shapes, table, ends, sizes, taps


def gaussian_levels(image: np.ndarray, levels: int, sigma: float) -> list[np.ndarray]:
    """``blur(level, sigma)[::2, ::2]`` level after level, only the kept pixels computed.

    Level 0 is ``image`` itself, read-only (a float32 array is not copied); the others of a
    plane come from one compiled call (``_pyramid_kernels``) into one buffer, views of it.
    A colour image is done plane by plane.
    """
    from ._pyramid_kernels import gaussian_chain

    first = np.ascontiguousarray(image, dtype=np.float32).view()
    first.flags.writeable = False
    shapes, table, ends, sizes, taps = _chain_plan(
        (int(image.shape[0]), int(image.shape[1])), levels, float(sigma)
    )
    if not len(sizes):
        return [first]
    planes = [first] if first.ndim == 2 else [first[..., c] for c in range(first.shape[2])]
    buffers = []
    for plane in planes:
        buffers.append(np.empty(int(ends[-1]), dtype=np.float32))
        gaussian_chain(np.ascontiguousarray(plane), taps, table, buffers[-1])
    result = [first]
    for (rows, cols), end, size in zip(shapes[1:], ends, sizes, strict=True):
        views = [buffer[end - size : end].reshape(rows, cols) for buffer in buffers]
        result.append(views[0] if first.ndim == 2 else np.stack(views, axis=2))
    return result


@node("pyramids.gaussian", version=1, conformance=Conformance("max_abs", 1e-5))
def gaussian_pyramid(image: Image, *, levels: Levels = 4, sigma: Sigma = 1.0) -> Pyramid:
    r"""Gaussian pyramid: blur, then keep every second row and column, ``levels - 1`` times.

    Subsampling by 2 halves the sampling frequency, so only frequencies
    below a quarter cycle per pixel of the finer level can be represented
    (Nyquist: sample at least twice the highest frequency). The Gaussian,
    a low-pass filter with compact support in both domains, removes what
    cannot be represented first: its transfer function
    :math:`e^{-2\pi^2\sigma^2 f^2}` is 0.29 at :math:`f = 1/4` for
    :math:`\sigma = 1` and falls to 0.007 at :math:`f = 1/2`, where naive
    subsampling folds the full amplitude back as aliasing.

    Parameters
    ----------
    image : Image
        Gray or colour, in [0, 1].
    levels : int
        Number of levels, the image itself included (stops early at 1 pixel).
    sigma : float
        Standard deviation of the Gaussian applied before each halving.

    Returns
    -------
    pyramid : Pyramid, finest first; level 0 is the image itself, read-only (not a copy)

    References
    ----------
    .. [1] P. J. Burt, E. H. Adelson, "The Laplacian pyramid as a compact image
       code", IEEE Trans. Communications 31(4), 1983.
    """
    return ImagePyramid(tuple(gaussian_levels(image, levels, sigma)), "gaussian")


@node("pyramids.naive", version=1)
def naive_pyramid(image: Image, *, levels: Levels = 4) -> Pyramid:
    """Subsampling without smoothing: every second row and column.

    Frequencies above the new Nyquist limit fold back as aliasing (shown
    beside ``pyramids.gaussian``).

    Parameters
    ----------
    image : Image
        Gray or colour, in [0, 1].
    levels : int
        Number of levels, the image itself included.

    Returns
    -------
    pyramid : Pyramid, finest first
    """
    result = [image.astype(np.float32)]
    for _ in range(levels - 1):
        if min(result[-1].shape[:2]) < 2:
            break
        result.append(np.ascontiguousarray(result[-1][::2, ::2]))
    return ImagePyramid(tuple(result), "naive")


@node("pyramids.laplacian", version=1)
def laplacian_pyramid(image: Image, *, levels: Levels = 4, sigma: Sigma = 1.0) -> Pyramid:
    r"""Laplacian pyramid: the band each Gaussian level adds to the next coarser one.

    .. math:: L_i = G_i - \operatorname{expand}(G_{i+1}), \qquad L_{n-1} = G_{n-1}

    so that :math:`G_i = L_i + \operatorname{expand}(G_{i+1})` rebuilds the
    image exactly (``pyramids.reconstruct``), whatever ``expand`` does.

    Parameters
    ----------
    image : Image
        Gray or colour, in [0, 1].
    levels : int
        Number of levels, the coarsest Gaussian level included.
    sigma : float
        Standard deviation of the Gaussian of REDUCE and EXPAND.

    Returns
    -------
    pyramid : Pyramid, band-pass levels finest first, then the coarsest Gaussian level

    References
    ----------
    .. [1] Burt & Adelson (1983).
    """
    gaussian = gaussian_levels(image, levels, sigma)
    bands = [
        fine - expand(coarse, fine.shape, sigma) for fine, coarse in itertools.pairwise(gaussian)
    ]
    return ImagePyramid((*bands, gaussian[-1]), f"laplacian:{sigma!r}")


@node("pyramids.reconstruct", version=1)
def reconstruct(pyramid: Pyramid) -> Image:
    r"""Collapse a Laplacian pyramid back into the image.

    .. math:: G_i = L_i + \operatorname{expand}(G_{i+1})

    Parameters
    ----------
    pyramid : Pyramid
        A pyramid made by ``pyramids.laplacian``.

    Returns
    -------
    image : Image, clipped to [0, 1] (float32 rounding only)
    """
    if not pyramid.kind.startswith("laplacian:"):
        raise ValueError(f"pyramid must be a Laplacian pyramid to reconstruct, got {pyramid.kind}")
    sigma = float(pyramid.kind.split(":", 1)[1])
    image = pyramid.levels[-1]
    for band in reversed(pyramid.levels[:-1]):
        image = band + expand(image, band.shape, sigma)
    return np.clip(image, 0.0, 1.0).astype(np.float32)


@node("pyramids.level", version=1)
def pyramid_level(pyramid: Pyramid, *, index: Annotated[int, Field(ge=0)] = 1) -> FloatImage:
    """One level of a pyramid (0 is the finest).

    Parameters
    ----------
    pyramid : Pyramid
        Any pyramid.
    index : int
        Which level.

    Returns
    -------
    level : float32 ndarray
    """
    if index >= len(pyramid.levels):
        raise ValueError(f"index {index} is past the pyramid's {len(pyramid.levels)} levels")
    return pyramid.levels[index]


@node("pyramids.mosaic", version=1)
def mosaic(pyramid: Pyramid) -> ColorImage:
    """All levels side by side on one canvas, finest on the left.

    Band-pass levels are shown as 0.5 + level (clipped), so zero is mid-gray.

    Parameters
    ----------
    pyramid : Pyramid
        Any pyramid.

    Returns
    -------
    drawing : (H, W_total, 3) float32 ndarray
    """
    band = pyramid.kind.startswith("laplacian")
    height = pyramid.levels[0].shape[0]
    width = sum(level.shape[1] for level in pyramid.levels)
    canvas = np.zeros((height, width, 3), dtype=np.float32)
    left = 0
    for index, level in enumerate(pyramid.levels):
        shown = level + 0.5 if band and index < len(pyramid.levels) - 1 else level
        rgb = shown if shown.ndim == 3 else np.repeat(shown[..., None], 3, axis=2)
        rows, cols = level.shape[:2]
        canvas[:rows, left : left + cols] = np.clip(rgb, 0.0, 1.0)
        left += cols
    return canvas


@node("pyramids.zone_plate", version=1)
def zone_plate(*, size: Annotated[int, Field(ge=8, le=4096)] = 256) -> GrayImage:
    r"""A zone plate (chirp) whose local frequency grows to the Nyquist limit.

    .. math:: I = \tfrac12 + \tfrac12\cos(\pi r^2 / N), \quad N = \text{size}

    The local frequency :math:`r / N` cycles per pixel grows linearly from
    the centre to the Nyquist limit ½ at the middle of each side, so every
    frequency is present once, at a known place: aliasing after subsampling
    shows as rings where there should be none.

    Parameters
    ----------
    size : int
        Side of the square image.

    Returns
    -------
    image : (size, size) float32 ndarray
    """
    centre = (size - 1) / 2
    y, x = np.mgrid[0:size, 0:size].astype(np.float64) - centre
    return (0.5 + 0.5 * np.cos(np.pi * (x * x + y * y) / size)).astype(np.float32)
