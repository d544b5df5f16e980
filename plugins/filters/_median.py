"""The median filter: selection networks over sorted columns, compiled with numba."""

from __future__ import annotations

from functools import lru_cache
from typing import Annotated, Literal

import numpy as np
from pydantic import AfterValidator, Field

from graphvision import Conformance, ImageT, node

from ..shared.checks import check_window
from ..shared.params import odd
from ._boundary import Boundary
from ._median_network import median_network, sort_network

__all__ = ["median"]


_NUMPY_PAD: dict[str, Literal["wrap", "edge", "symmetric"]] = {
    "wrap": "wrap",
    "replicate": "edge",
    "mirror": "symmetric",
}
_BLOCK = 512  # columns per pass of the selection network: its wires stay in L2
# from this window side, an image of 8-bit levels takes the sliding histogram (2·size
# updates a pixel) instead of the network (205 comparators a pixel at 7×7; 5×5's 82 are
# faster than the histogram's walk)
_HISTOGRAM_FROM = 7


MedianSize = Annotated[int, Field(ge=1, le=31), AfterValidator(odd)]


@lru_cache(maxsize=64)
def _padded_index(length: int, half: int, boundary: str) -> np.ndarray:
    """Source index of each padded position along an axis (−1: zero; crop: no padding); kept
    for the next call of the same size (read-only)."""
    positions = np.arange(length, dtype=np.int64)
    if boundary == "crop":
        return positions
    if boundary == "zero":
        return np.pad(positions, half, mode="constant", constant_values=-1)
    return np.pad(positions, half, mode=_NUMPY_PAD[boundary])


def _boundary_index(length: int, half: int, boundary: str) -> np.ndarray:
    """The cached index, read-only (it is shared between calls)."""
    index = _padded_index(length, half, boundary)
    index.flags.writeable = False
    return index


def _median_of_levels(
    image: np.ndarray, rows: np.ndarray, columns: np.ndarray, out: np.ndarray
) -> bool:
    """The median by the sliding histogram if every value of ``image`` is an 8-bit level
    (False, nothing written to ``out``, if one is not)."""
    from ._median_histogram import LEVELS, level_codes, median_by_histogram

    codes = np.empty(image.shape, dtype=np.uint8)
    if not level_codes(image, LEVELS, codes):
        return False
    median_by_histogram(codes, rows, columns, LEVELS, out)
    return True


def _median_2d(plane: np.ndarray, size: int, boundary: str, out: np.ndarray) -> None:
    """Median of every ``size × size`` window of ``plane`` (padded as read) into ``out``."""
    from ._median_kernels import median_3x3, median_by_network

    half = size // 2
    image = np.ascontiguousarray(plane, dtype=np.float32)
    rows = _boundary_index(image.shape[0], half, boundary)
    columns = _boundary_index(image.shape[1], half, boundary)
    if size == 1:
        out[:] = image
    elif size == 3:
        median_3x3(image, rows, columns, out)
    elif size == 5:
        from ._median_select5 import median_5x5

        median_5x5(image, rows, columns, out, _BLOCK)
    elif size >= _HISTOGRAM_FROM and _median_of_levels(image, rows, columns, out):
        pass  # an image of 8-bit levels: the sliding histogram, same medians
    else:
        selection, median_wire = median_network(size)
        median_by_network(
            image, rows, columns, sort_network(size), selection, median_wire, out, _BLOCK
        )


@node(
    "filters.median",
    version=1,
    conformance=Conformance(
        "max_abs",
        0.002,
        note=(
            "OpenCV takes float32 medians up to 5×5 only: larger windows run on 8-bit levels, "
            "at most half a level (0.002) away"
        ),
    ),
)
def median(image: ImageT, *, size: MedianSize = 3, boundary: Boundary = "mirror") -> ImageT:
    """Median filter: each pixel becomes the median of its ``size × size`` window.

    A nonlinear filter: it adds no new gray levels and discards outliers, so
    it removes impulse and salt-and-pepper noise that a Gaussian only smears.
    Only comparisons are used, so the result is exactly one of the window's
    values (equal to ``scipy.ndimage.median_filter``). Each column of ``size``
    values is sorted once and shared by the ``size`` windows that contain it;
    the median of a window's sorted columns is then selected by Batcher's
    odd-even merge pruned to the comparators the middle rank depends on
    (14 for 3×3, 82 for 5×5, 205 for 7×7), each run over a block of pixels
    as min/max vector instructions. 3×3 runs Paeth's network (max of the
    column minima, median of the medians, min of the maxima) on a vector of
    pixels at a time, reading the three rows where they lie in the image (no
    padded copy; the border columns through the boundary rule). From 7×7 up, an
    image of 8-bit levels (every value :math:`k/255`, as read from an 8-bit
    file) takes Huang's sliding histogram over the 256 levels instead:
    ``2 · size`` counter updates a pixel and a short walk from the
    neighbour's median [4]_, the same median. Colour images are filtered per
    channel.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
    size : int
        Odd window side.
    boundary : {"mirror", "replicate", "wrap", "zero", "crop"}

    Returns
    -------
    filtered : float32 ndarray, same kind as ``image``; smaller by ``size - 1``
        with ``boundary="crop"``.

    References
    ----------
    .. [1] A. Adams, "Fast median filters using separable sorting networks",
       ACM Trans. Graph. 40(4), 2021.
    .. [2] A. W. Paeth, "Median finding on a 3×3 grid", Graphics Gems, 1990.
    .. [3] Szeliski (2022), section 3.3.1.
    .. [4] T. S. Huang, G. J. Yang, G. Y. Tang, "A fast two-dimensional median
       filtering algorithm", IEEE Trans. ASSP 27(1), 1979.
    """
    half = size // 2
    shape = image.shape
    if boundary == "crop":
        check_window(image, (size, size), "median window")
        shape = (image.shape[0] - 2 * half, image.shape[1] - 2 * half, *image.shape[2:])
    out = np.empty(shape, dtype=np.float32)
    if image.ndim == 2:
        _median_2d(image, size, boundary, out)
    else:
        for channel in range(image.shape[2]):
            plane = np.empty(shape[:2], dtype=np.float32)
            _median_2d(image[..., channel], size, boundary, plane)
            out[..., channel] = plane
    return out
