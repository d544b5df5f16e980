"""Speckle filtering of a disparity map: small islands of disparity are mismatches."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import node

from ._ports import Disparity

__all__ = ["SpeckleRange", "SpeckleWindow", "filter_speckles", "speckles"]

SpeckleWindow = Annotated[int, Field(ge=0, le=1_000_000)]
"""Largest region, in pixels, that is a speckle (0: no filtering)."""

SpeckleRange = Annotated[float, Field(ge=0)]
"""Largest disparity difference, in pixels, between neighbours of one region."""


def speckles(disparity: np.ndarray, window: int, tolerance: float) -> np.ndarray:
    """``disparity`` with every speckle (see :func:`filter_speckles`) set to NaN."""
    from ._kernels import speckle_filter

    out: np.ndarray = speckle_filter(np.ascontiguousarray(disparity, np.float32), window, tolerance)
    return out


@node("stereo.filter_speckles", version=1)
def filter_speckles(
    disparity: Disparity,
    *,
    speckle_window: SpeckleWindow = 100,
    speckle_range: SpeckleRange = 2.0,
) -> Disparity:
    r"""Invalidate the small regions of similar disparity: the speckles of mismatches.

    Pixels are joined into regions by 4-connectivity, two neighbours
    :math:`p, q` belonging together when both are valid and

    .. math:: |d(p) - d(q)| \le \text{speckle\_range};

    every region of at most ``speckle_window`` pixels becomes NaN. A surface
    is a large region of slowly changing disparity; a mismatch on a flat or
    repetitive texture is an island that disagrees with all its neighbours.
    This is OpenCV's ``filterSpeckles`` (used by StereoSGBM with
    ``speckleWindowSize`` and ``speckleRange``), on sub-pixel disparities.

    Parameters
    ----------
    disparity : (H, W) Disparity
        float32, NaN where invalid.
    speckle_window : int
        Largest region, in pixels, that is invalidated (0: none).
    speckle_range : float
        Largest disparity step, in pixels, between neighbours of one region.

    Returns
    -------
    Disparity
        The map with the speckles set to NaN.

    References
    ----------
    .. [1] H. Hirschmüller, "Stereo processing by semiglobal matching and mutual
       information", IEEE TPAMI 30(2), 2008, section 4.1 (removal of peaks).
    """
    if speckle_window == 0:
        return disparity.copy()
    return speckles(disparity, speckle_window, speckle_range)
