r"""Bayer colour filter arrays: mosaicking and demosaicking.

A Bayer sensor records one colour per pixel in a 2×2 tile with two greens on a
diagonal (seed: "Color perception", the eye's cones and the camera's CFA).
The four tiles are named by their first row then second row: ``RGGB`` has red
at (0, 0), greens at (0, 1) and (1, 0), blue at (1, 1).

**Bilinear.** Each missing value is the mean of its nearest neighbours of that
colour: green from the 4-neighbours (kernel ``[[0,1,0],[1,4,1],[0,1,0]]/4`` on
the green samples), red and blue from 2 or 4 neighbours (kernel
``[[1,2,1],[2,4,2],[1,2,1]]/4`` on their samples).

**Gradient-corrected (Malvar, He, Cutler).** The bilinear estimate is corrected
by the Laplacian of the colour that *is* sampled at the pixel, weighted
(α = 1/2, β = 5/8, γ = 3/4), which gives four fixed 5×5 kernels; e.g. green at a
red pixel is :math:`\hat g = g_{bilinear} + \alpha\, \Delta_R`.

References
----------
.. [1] B. E. Bayer, "Color imaging array", US patent 3,971,065, 1976.
.. [2] H. S. Malvar, L. He, R. Cutler, "High-quality linear interpolation for demosaicing
   of Bayer-patterned color images", IEEE ICASSP 2004.
"""

from __future__ import annotations

from functools import cache
from typing import Literal

import numpy as np

from graphvision import ColorImage, Conformance, GrayImage, node

__all__ = ["bayer_masks", "demosaic", "mosaic"]

Pattern = Literal["RGGB", "BGGR", "GRBG", "GBRG"]

_G_AT_RB = (
    np.array(
        [[0, 0, -1, 0, 0], [0, 0, 2, 0, 0], [-1, 2, 4, 2, -1], [0, 0, 2, 0, 0], [0, 0, -1, 0, 0]]
    )
    / 8.0
)
# red (blue) at a green pixel whose row holds red (blue) samples
_RB_AT_G_ROW = (
    np.array(
        [
            [0, 0, 0.5, 0, 0],
            [0, -1, 0, -1, 0],
            [-1, 4, 5, 4, -1],
            [0, -1, 0, -1, 0],
            [0, 0, 0.5, 0, 0],
        ]
    )
    / 8.0
)
_RB_AT_G_COLUMN = _RB_AT_G_ROW.T
_RB_AT_BR = np.array(
    [[0, 0, -1.5, 0, 0], [0, 2, 0, 2, 0], [-1.5, 0, 6, 0, -1.5], [0, 2, 0, 2, 0],
     [0, 0, -1.5, 0, 0]]
) / 8.0  # fmt: skip


def bayer_masks(shape: tuple[int, int], pattern: str) -> np.ndarray:
    """Boolean masks ``3×H×W``: where the sensor samples red, green and blue."""
    masks = np.zeros((3, *shape), bool)
    for index, letter in enumerate(pattern):
        dy, dx = divmod(index, 2)
        masks["RGB".index(letter), dy::2, dx::2] = True
    return masks


def _kernel_at(method: str, channel: int, letter: str, row_letters: str) -> np.ndarray | None:
    """The kernel giving ``channel`` at a tile place sampling ``letter`` (None: the sample)."""
    if "RGB"[channel] == letter:
        return None
    if method == "bilinear":
        cross = np.array([[0, 1, 0], [1, 4, 1], [0, 1, 0]]) / 4.0
        box = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]]) / 4.0
        return cross if channel == 1 else box
    if channel == 1:
        return _G_AT_RB
    if letter != "G":
        return _RB_AT_BR
    return _RB_AT_G_ROW if "RGB"[channel] in row_letters else _RB_AT_G_COLUMN


def _power_of_two(weight: float) -> bool:
    """Whether ``±weight`` is a power of two (a product by it is exact in any float)."""
    mantissa, _ = np.frexp(abs(weight))
    return bool(mantissa == 0.5)


@cache
def _tap_lists(pattern: str, method: str) -> tuple[np.ndarray, np.ndarray]:
    """Taps ``(dy, dx, weight, 1 if the weight is a power of two)`` per channel and tile
    place, in the order the array formulas added them (row-major over the kernel), and their
    counts (−1: copy the sample).

    Bilinear keeps only the taps on samples of the channel's colour (the others read a
    masked zero)."""
    taps = np.zeros((3, 4, 25, 4))
    counts = np.full((3, 4), -1, dtype=np.int64)
    for tile, letter in enumerate(pattern):
        ty, tx = divmod(tile, 2)
        row_letters = pattern[2 * ty : 2 * ty + 2]
        for channel in range(3):
            kernel = _kernel_at(method, channel, letter, row_letters)
            if kernel is None:
                continue
            half = kernel.shape[0] // 2
            kept = [
                (dy - half, dx - half, kernel[dy, dx], _power_of_two(kernel[dy, dx]))
                for dy, dx in zip(*np.nonzero(kernel), strict=True)
                if method != "bilinear"
                or pattern[2 * ((ty + dy - half) % 2) + (tx + dx - half) % 2] == "RGB"[channel]
            ]
            counts[channel, tile] = len(kept)
            taps[channel, tile, : len(kept)] = kept
    return taps, counts


@cache
def _malvar_kinds(pattern: str, method: str) -> np.ndarray:
    """Which of Malvar's kernels gives each channel at each tile place (1: ``_G_AT_RB``,
    2: ``_RB_AT_G_ROW``, 3: ``_RB_AT_G_COLUMN``, 4: ``_RB_AT_BR``; 0: none, or bilinear),
    for the kernel's written-out runs (``_malvar_kernels.malvar_run``)."""
    kinds = np.zeros((3, 4), dtype=np.int64)
    if method != "malvar":
        return kinds
    known = (_G_AT_RB, _RB_AT_G_ROW, _RB_AT_G_COLUMN, _RB_AT_BR)
    for tile, letter in enumerate(pattern):
        row_letters = pattern[2 * (tile // 2) : 2 * (tile // 2) + 2]
        for channel in range(3):
            kernel = _kernel_at(method, channel, letter, row_letters)
            if kernel is not None:
                kinds[channel, tile] = 1 + [k is kernel for k in known].index(True)
    return kinds


@node("formation.mosaic", version=1)
def mosaic(image: ColorImage, *, pattern: Pattern = "RGGB") -> GrayImage:
    """What a Bayer sensor records of an RGB scene: one colour sample per pixel.

    Parameters
    ----------
    image : ColorImage
        The scene, RGB.
    pattern : {"RGGB", "BGGR", "GRBG", "GBRG"}
        The 2×2 tile, first row then second row.
    """
    masks = bayer_masks(image.shape[:2], pattern)
    return (np.moveaxis(image, 2, 0) * masks).sum(axis=0).astype(np.float32)


@node(
    "formation.demosaic",
    version=1,
    conformance=Conformance(
        "max_abs",
        1e-4,
        margin=2,
        note=(
            "OpenCV's bilinear demosaicing copies the outermost two rows and columns from their "
            "neighbours; malvar has no OpenCV counterpart and runs the reference"
        ),
    ),
)
def demosaic(
    raw: GrayImage,
    *,
    pattern: Pattern = "RGGB",
    method: Literal["bilinear", "malvar"] = "malvar",
) -> ColorImage:
    """An RGB image from a Bayer mosaic, by bilinear or gradient-corrected interpolation.

    Parameters
    ----------
    raw : GrayImage
        The sensor's samples (``formation.mosaic``), one colour per pixel.
    pattern : {"RGGB", "BGGR", "GRBG", "GBRG"}
        The 2×2 tile the mosaic was taken with.
    method : {"bilinear", "malvar"}
        Bilinear interpolation per channel, or Malvar-He-Cutler's
        gradient-corrected linear filters (module docstring).

    Raises
    ------
    ValueError
        For a mosaic smaller than 5×5.
    """
    if min(raw.shape) < 5:
        raise ValueError(f"raw must be at least 5×5 to demosaic, got {raw.shape}")
    from ._bayer_kernels import demosaic_taps

    taps, counts = _tap_lists(pattern, method)
    out = np.empty((*raw.shape, 3), dtype=np.float32)
    samples = np.ascontiguousarray(raw, dtype=np.float32)
    demosaic_taps(samples, taps, counts, _malvar_kinds(pattern, method), out)
    return out
