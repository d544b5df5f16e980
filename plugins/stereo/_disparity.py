"""Disparity of a rectified pair: block matching and semi-global matching (notes: "Stereo
geometry and scene reconstruction", disparity estimation with a window W)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import AfterValidator, Field

from graphvision import GrayImage, node

from .._params import odd
from ._cost import Cost, cost_volume, maximum_cost
from ._ports import Disparity

__all__ = ["MAX_VOLUME", "block_match", "check_pair", "left_right_check", "sgm"]

Window = Annotated[int, Field(ge=1, le=31), AfterValidator(odd)]

# The eight path directions (step_y, step_x) of semi-global matching; the first four
# (horizontal and vertical) are the 4-path variant.
PATHS = ((0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1))


MAX_VOLUME = 2**27
"""Most values of a cost volume (512 MB in float32): semi-global matching keeps a few of
them at once, so this is what this machine holds; a 500 × 741 pair with 64 disparities
(stereo.yaml) needs 23.7 million."""


def _sgm_params(**params: Any) -> None:
    """Parameters of semi-global matching valid together: P2 >= P1, census <= 7."""
    if params["p2"] < params["p1"]:
        raise ValueError(
            f"p2 ({params['p2']:g}) must be at least p1 ({params['p1']:g}): a jump costs more "
            "than a step"
        )
    if params["cost"] == "census" and params["window"] > 7:
        raise ValueError(
            f"a census window is at most 7 (48 bits in a 64-bit word), got {params['window']}"
        )


def check_pair(left: np.ndarray, right: np.ndarray, d_min: int, count: int, window: int) -> None:
    """Refuse a pair of different sizes, a range wider than the image, and a cost volume
    (rows × columns × disparities) beyond ``MAX_VOLUME`` values, saying what it needs."""
    if left.shape != right.shape:
        raise ValueError(
            f"the left image is {left.shape[0]}×{left.shape[1]} (rows×columns) but the right is"
            f" {right.shape[0]}×{right.shape[1]}: a rectified pair has one size"
        )
    cols = left.shape[1]
    if abs(d_min) + count > cols:
        raise ValueError(
            f"the disparity range [{d_min}, {d_min + count - 1}] does not fit in the image's "
            f"{cols} columns: lower num_disparities or min_disparity"
        )
    volume = left.shape[0] * cols * count
    if volume > MAX_VOLUME:
        raise ValueError(
            f"the cost volume {left.shape[0]}×{cols}×{count} would hold {volume:,} values "
            f"({volume * 4 / 2**30:.1f} GiB as float32, more again to aggregate it), at most "
            f"{MAX_VOLUME:,}: lower num_disparities or match smaller images"
        )


def left_right_check(
    disparity: np.ndarray, right_disparity: np.ndarray, tolerance: float
) -> np.ndarray:
    """NaN where the right image's disparity at ``x − d`` differs from ``d`` by more than
    ``tolerance`` pixels (occlusions and mismatches; Hirschmüller 2008, section 3.3)."""
    rows, cols = disparity.shape
    valid = np.isfinite(disparity)
    x_right = np.arange(cols)[None, :] - np.rint(np.where(valid, disparity, 0)).astype(np.int64)
    valid &= (x_right >= 0) & (x_right < cols)
    y = np.broadcast_to(np.arange(rows)[:, None], (rows, cols))
    seen = np.full(disparity.shape, np.nan, dtype=np.float32)
    seen[valid] = right_disparity[y[valid], x_right[valid]]
    keep = np.abs(disparity - seen) <= tolerance  # False for NaN
    return np.where(keep, disparity, np.float32(np.nan)).astype(np.float32)


def _select(
    volume: np.ndarray, d_min: int, uniqueness: float, subpixel: bool, lr_tolerance: float | None
) -> np.ndarray:
    """Winner-take-all with uniqueness and sub-pixel refinement, then the left-right check."""
    from ._kernels import right_disparity, winner_take_all

    disparity: np.ndarray = winner_take_all(volume, d_min, uniqueness, subpixel)
    if lr_tolerance is not None:
        disparity = left_right_check(disparity, right_disparity(volume, d_min), lr_tolerance)
    return disparity


@node("stereo.block_match", version=2)
def block_match(
    left: GrayImage,
    right: GrayImage,
    *,
    min_disparity: int = 0,
    num_disparities: Annotated[int, Field(ge=1, le=1024)] = 64,
    window: Window = 9,
    cost: Cost = "zncc",
    uniqueness: Annotated[float, Field(ge=0)] = 0.2,
    subpixel: bool = True,
    lr_tolerance: Annotated[float, Field(ge=0)] | None = 1.0,
) -> Disparity:
    r"""Disparity by block matching: the block along the same row of the right image
    that is most similar, winner take all.

    For each left pixel the ``window × window`` block is compared with the
    right blocks at :math:`x - d`, :math:`d \in [d_{min}, d_{min} + n)`, and the
    least cost wins. A small window keeps details but is noisy; a large one is
    smooth but loses details (the notes). Only disparities whose right pixel
    is inside the image compete, and a winner at either end of the range is
    refused (the true one may lie beyond it, or the pixel may be unseen by
    the right camera: search a range that holds the scene with a margin).
    A winner is kept only when every
    disparity more than one step away costs at least ``(1 + uniqueness)``
    times as much, refined to sub-pixel by the parabola through its
    neighbours' costs, and checked against the right image's own winner
    (left-right consistency).

    Parameters
    ----------
    left, right : GrayImage
        A rectified pair (corresponding pixels on the same row), one size.
    min_disparity : int
        The smallest disparity searched.
    num_disparities : int
        How many disparities are searched.
    window : int
        Side W of the block (odd).
    cost : {"zncc", "sad", "ssd", "census"}
        Block dissimilarity (see :func:`cost_volume`); zero-mean NCC ignores a
        gain and bias between the cameras (the default).
    uniqueness : float
        Margin by which the winner must beat every non-neighbouring disparity.
    subpixel : bool
        Refine by fitting a parabola to the costs around the winner.
    lr_tolerance : float or None
        Largest left-right disagreement in pixels; None skips the check.

    Returns
    -------
    Disparity
        float32, NaN where no estimate survived.

    References
    ----------
    .. [1] Scharstein & Szeliski, "A taxonomy and evaluation of dense two-frame
       stereo correspondence algorithms", IJCV 47, 2002.
    """
    check_pair(left, right, min_disparity, num_disparities, window)
    volume = cost_volume(left, right, min_disparity, num_disparities, cost, window)
    return _select(volume, min_disparity, uniqueness, subpixel, lr_tolerance)


@node("stereo.sgm", version=1, check=_sgm_params)
def sgm(
    left: GrayImage,
    right: GrayImage,
    *,
    min_disparity: int = 0,
    num_disparities: Annotated[int, Field(ge=1, le=1024)] = 64,
    window: Window = 7,
    cost: Cost = "census",
    p1: Annotated[float, Field(ge=0)] = 8.0,
    p2: Annotated[float, Field(ge=0)] = 32.0,
    paths: Literal[4, 8] = 8,
    uniqueness: Annotated[float, Field(ge=0)] = 0.05,
    subpixel: bool = True,
    lr_tolerance: Annotated[float, Field(ge=0)] | None = 1.0,
) -> Disparity:
    r"""Disparity by semi-global matching: pixel costs smoothed along 4 or 8 straight paths.

    Along each path direction :math:`r` the cost is aggregated as

    .. math::

        L_r(p, d) = C(p, d) + \min\big(L_r(p - r, d),\; L_r(p - r, d \pm 1) + P_1,\;
        \min_k L_r(p - r, k) + P_2\big) - \min_k L_r(p - r, k)

    so a change of one disparity step costs :math:`P_1` and a jump
    :math:`P_2` (:math:`P_2 \ge P_1`): a 1-D approximation of a global
    smoothness energy. The summed :math:`S(p, d) = \sum_r L_r(p, d)` is then
    resolved as in :func:`block_match` (winner take all, uniqueness,
    sub-pixel, left-right check with the right image's disparity read from
    the same volume).

    Parameters
    ----------
    left, right : GrayImage
        A rectified pair, one size.
    min_disparity : int
        The smallest disparity searched.
    num_disparities : int
        How many disparities are searched.
    window : int
        Side of the matching-cost block (odd; census: at most 7, 48 bits).
    cost : {"census", "sad", "ssd", "zncc"}
        Pixel matching cost; ``p1`` and ``p2`` are in its units (census: bits).
    p1 : float
        Penalty for a disparity change of one step between path neighbours.
    p2 : float
        Penalty for a larger change (at least ``p1``).
    paths : {4, 8}
        Horizontal and vertical paths, or these and the diagonals.
    uniqueness : float
        Margin by which the winner must beat every non-neighbouring disparity.
    subpixel : bool
        Parabola refinement of the winner.
    lr_tolerance : float or None
        Largest left-right disagreement in pixels; None skips the check.

    Returns
    -------
    Disparity
        float32, NaN where no estimate survived.

    References
    ----------
    .. [1] H. Hirschmüller, "Stereo processing by semiglobal matching and mutual
       information", IEEE TPAMI 30(2), 2008.
    """
    check_pair(left, right, min_disparity, num_disparities, window)
    from ._kernels import aggregate_path

    volume = cost_volume(left, right, min_disparity, num_disparities, cost, window)
    highest = maximum_cost(cost, window)
    integral = volume.dtype == np.uint16 and float(p1).is_integer() and float(p2).is_integer()
    penalty_small: np.number
    penalty_large: np.number
    if integral and paths * (highest + p2) <= np.iinfo(np.uint16).max:
        # each path's cost is at most C_max + P2, so the sum fits in 16 bits
        penalty_small, penalty_large = np.uint16(p1), np.uint16(p2)
    else:
        volume = volume.astype(np.float32)
        penalty_small, penalty_large = np.float32(p1), np.float32(p2)
    total = np.zeros_like(volume)
    for step_y, step_x in PATHS[:paths]:
        aggregate_path(volume, total, step_y, step_x, penalty_small, penalty_large)
    return _select(total, min_disparity, uniqueness, subpixel, lr_tolerance)
