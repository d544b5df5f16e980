"""Histograms of oriented gradients (seed: "Handcrafted nonlinear transforms"), vectorised
over a stack of images: central differences, unsigned orientation bins per cell weighted
by magnitude, overlapping blocks normalised with L2-Hys (Dalal and Triggs)."""

from __future__ import annotations

import json
from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import GrayImage, node

from ..shared.params import Count
from ._types import Features, FeatureSet, Samples

__all__ = [
    "HOG_EPS",
    "hog",
    "hog_blocks",
    "hog_cells",
    "hog_features",
    "hog_picture",
    "normalise_blocks",
]

HOG_EPS = 1e-5
Pair = tuple[Count, Count]


def hog_cells(images: np.ndarray, orientations: int, cell: tuple[int, int]) -> np.ndarray:
    r"""Cell histograms (..., cells_row, cells_col, orientations) of gray images (..., H, W).

    Each pixel votes its gradient magnitude :math:`\sqrt{g_r^2 + g_c^2}` into the bin
    of its unsigned orientation :math:`\mathrm{atan2}(g_r, g_c) \bmod 180°`; bin i
    covers :math:`[i\,\delta, (i+1)\,\delta)` with :math:`\delta = 180° / n` (edges in
    single precision, as scikit-image's); a histogram is divided by the cell's pixel
    count. Cells that do not fit whole are dropped.
    """
    from ._hog_kernels import cell_histograms

    rows, cols = cell
    lead = images.shape[:-2]
    stack = images.reshape(-1, *images.shape[-2:])
    step = np.float32(180.0 / orientations)
    edges = (step * np.arange(orientations + 1, dtype=np.float32)).astype(np.float64)
    histogram = cell_histograms(np.ascontiguousarray(stack), orientations, rows, cols, edges)
    return histogram.reshape(*lead, *histogram.shape[1:]) / (rows * cols)


def normalise_blocks(cells: np.ndarray, block: tuple[int, int]) -> np.ndarray:
    r"""Overlapping blocks (..., blocks_row, blocks_col, b_r, b_c, n) normalised with L2-Hys:

    .. math:: v \leftarrow v / \sqrt{\|v\|^2 + \epsilon^2},\quad v \leftarrow \min(v, 0.2),
              \quad v \leftarrow v / \sqrt{\|v\|^2 + \epsilon^2}, \qquad \epsilon = 10^{-5}
    """
    from numpy.lib.stride_tricks import sliding_window_view

    cells_row, cells_col = cells.shape[-3:-1]
    if cells_row < block[0] or cells_col < block[1]:
        raise ValueError(
            f"a HOG block of {block[0]}×{block[1]} cells does not fit in {cells_row}×{cells_col} "
            "cells: use a larger image or smaller cells or blocks"
        )
    axes = (cells.ndim - 3, cells.ndim - 2)
    blocks = sliding_window_view(cells, block, axis=axes)  # (..., Br, Bc, n, b_r, b_c)
    blocks = np.moveaxis(blocks, -3, -1)  # (..., Br, Bc, b_r, b_c, n)
    energy = (blocks**2).sum(axis=(-3, -2, -1), keepdims=True)
    clipped = np.minimum(blocks / np.sqrt(energy + HOG_EPS**2), 0.2)
    energy = (clipped**2).sum(axis=(-3, -2, -1), keepdims=True)
    return clipped / np.sqrt(energy + HOG_EPS**2)


def hog_blocks(
    images: np.ndarray, orientations: int, cell: tuple[int, int], block: tuple[int, int]
) -> np.ndarray:
    """Normalised blocks (..., Br, Bc, b_r, b_c, n) of gray images (..., H, W)."""
    return normalise_blocks(hog_cells(images, orientations, cell), block)


def hog_features(
    images: np.ndarray, orientations: int, cell: tuple[int, int], block: tuple[int, int]
) -> np.ndarray:
    """One HOG vector per image of a stack (N, H, W): rows of (N, D) float64, in the order of
    ``skimage.feature.hog(..., feature_vector=True)``."""
    blocks = hog_blocks(images, orientations, cell, block)
    return blocks.reshape(len(images), -1)


@node("recognition.hog", version=1)
def hog(
    samples: Samples,
    *,
    orientations: Annotated[int, Field(ge=2, le=36)] = 9,
    pixels_per_cell: Pair = (6, 6),
    cells_per_block: Pair = (2, 2),
) -> Features:
    r"""HOG descriptor of each sample (Dalal–Triggs): orientation histograms of gradients
    weighted by magnitude in cells, normalised over overlapping blocks with L2-Hys.

    Equal (to round-off) to ``skimage.feature.hog(image, orientations, pixels_per_cell,
    cells_per_block, block_norm="L2-Hys")`` for each image.

    Parameters
    ----------
    samples : Samples (N, H, W)
    orientations : number of unsigned orientation bins over 180°
    pixels_per_cell : cell size (rows, columns) in pixels
    cells_per_block : block size (rows, columns) in cells

    Returns
    -------
    features : Features (N, D), D = blocks × cells per block × orientations

    References
    ----------
    N. Dalal and B. Triggs, "Histograms of oriented gradients for human detection",
    CVPR 2005.
    """
    features = hog_features(samples.images, orientations, pixels_per_cell, cells_per_block)
    recipe = {
        "kind": "hog",
        "window": list(samples.images.shape[1:]),
        "orientations": orientations,
        "pixels_per_cell": list(pixels_per_cell),
        "cells_per_block": list(cells_per_block),
    }
    return FeatureSet(features, samples.labels.copy(), json.dumps(recipe))


def _glyphs(orientations: int, cell: tuple[int, int]) -> np.ndarray:
    """(n, rows, cols) one line per bin through the cell centre, across the gradient (along
    the edge it stands for)."""
    rows, cols = cell
    centre = np.array([(rows - 1) / 2, (cols - 1) / 2])
    radius = min(rows, cols) / 2
    t = np.linspace(-radius, radius, 4 * max(rows, cols))
    glyphs = np.zeros((orientations, rows, cols))
    for i in range(orientations):
        theta = np.deg2rad((i + 0.5) * 180.0 / orientations)
        # the gradient points along (sin θ, cos θ) in (row, col); the edge is perpendicular
        r = np.round(centre[0] + t * np.cos(theta)).astype(int)
        c = np.round(centre[1] - t * np.sin(theta)).astype(int)
        inside = (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
        glyphs[i, r[inside], c[inside]] = 1.0
    return glyphs


@node("recognition.hog_picture", version=1)
def hog_picture(
    image: GrayImage,
    *,
    orientations: Annotated[int, Field(ge=2, le=36)] = 9,
    pixels_per_cell: Pair = (8, 8),
) -> GrayImage:
    """A picture of the cell histograms: in each cell, one line per orientation bin along the
    edge direction it stands for, as bright as the bin's share of the gradient magnitude.

    Parameters
    ----------
    image : (H, W) gray image
    orientations : number of orientation bins
    pixels_per_cell : cell size (rows, columns)

    Returns
    -------
    picture : (H, W) float32 in [0, 1] (cells that do not fit whole stay black)
    """
    cells = hog_cells(image, orientations, pixels_per_cell)
    rows, cols = pixels_per_cell
    drawn = np.einsum("ijn,nrc->irjc", cells, _glyphs(orientations, pixels_per_cell))
    drawn = drawn.reshape(cells.shape[0] * rows, cells.shape[1] * cols)
    picture = np.zeros(image.shape, np.float32)
    peak = drawn.max()
    picture[: drawn.shape[0], : drawn.shape[1]] = drawn / peak if peak > 0 else drawn
    return picture
