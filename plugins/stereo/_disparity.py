"""Disparity of a rectified pair: block matching and semi-global matching (notes: "Stereo
geometry and scene reconstruction", disparity estimation with a window W)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import AfterValidator, Field

from graphvision import Conformance, GrayImage, node

from ..shared.params import odd
from ._census import census_block_match, census_sgm
from ._cost import Cost, maximum_cost
from ._pair_checks import check_pair
from ._ports import Disparity
from ._selection import _checked, _select, _volume
from ._speckles import SpeckleRange, SpeckleWindow

__all__ = [
    "block_match",
    "sgm",
]

Window = Annotated[int, Field(ge=1, le=31), AfterValidator(odd)]

# The eight path directions (step_y, step_x) of semi-global matching; the first four
# (horizontal and vertical) are the 4-path variant.
PATHS = ((0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1))


def _census_window(**params: Any) -> None:
    """A census window of at most 7 (its bits fill a 64-bit word)."""
    if params["cost"] == "census" and params["window"] > 7:
        raise ValueError(
            f"a census window is at most 7 (48 bits in a 64-bit word), got {params['window']}"
        )


def _sgm_params(**params: Any) -> None:
    """Parameters of semi-global matching valid together: P2 >= P1, census <= 7."""
    if params["p2"] < params["p1"]:
        raise ValueError(
            f"p2 ({params['p2']:g}) must be at least p1 ({params['p1']:g}): a jump costs more "
            "than a step"
        )
    _census_window(**params)


@node(
    "stereo.block_match",
    version=3,
    check=_census_window,
    conformance=Conformance(
        "disparity",
        0.01,
        radius=1.0,
        mismatch=0.25,
        note=(
            "OpenCV returns 1/16-pixel fixed point (divided by 16 here, NaN where invalid), "
            "matches by SAD of x-Sobel-prefiltered 8-bit images over one block of at least 5 "
            "(cost is the reference's), leaves invalid the first min_disparity + 16⌈n/16⌉ + "
            "block/2 columns and block/2 rows at the top and bottom, and takes uniqueness in "
            "whole percent and lr_tolerance in whole pixels; at most 1 % of the pixels valid "
            "in both differ by more than 1 px"
        ),
    ),
)
def block_match(
    left: GrayImage,
    right: GrayImage,
    *,
    min_disparity: int = 0,
    num_disparities: Annotated[int, Field(ge=1, le=1024)] = 64,
    window: Window = 7,
    block: Window | None = None,
    cost: Cost = "census",
    uniqueness: Annotated[float, Field(ge=0)] = 0.1,
    subpixel: bool = True,
    lr_tolerance: Annotated[float, Field(ge=0)] | None = 1.0,
    speckle_window: SpeckleWindow = 100,
    speckle_range: SpeckleRange = 2.0,
) -> Disparity:
    r"""Disparity by block matching: the block along the same row of the right image
    that is most similar, winner take all.

    Each left pixel's matching cost with the right pixel at :math:`x - d`,
    :math:`d \in [d_{min}, d_{min} + n)` (census over a ``window × window``
    neighbourhood by default: the Hamming distance of the signatures), is
    summed over the ``block × block`` square around it,

    .. math:: C_B(p, d) = \sum_{q \in B(p)} C(q, d),

    and the least summed cost wins. A small block keeps details but is
    noisy; a large one is smooth but loses details (the notes). Only
    disparities whose right pixel is inside the image compete, and a winner
    at either end of the range is refused (the true one may lie beyond it,
    or the pixel may be unseen by the right camera: search a range that
    holds the scene with a margin). A winner is kept only when every
    disparity more than one step away costs at least ``(1 + uniqueness)``
    times as much; it is refined to sub-pixel by the parabola through its
    neighbours' costs, checked against the right image's own winner
    (left-right consistency, :func:`left_right_check`), and the speckles
    (small islands of disparity, :func:`filter_speckles`) are removed.

    The defaults were chosen on rendered piecewise-planar scenes textured
    with photographs (``synthetic.planar_stereo_scene``; see
    ``bench/bench_stereo.py``): census summed over 9 × 9 is about twice as
    accurate on the pixels it keeps as zero-mean NCC over 9 × 9 and as
    OpenCV's StereoBM, with more pixels kept.

    Parameters
    ----------
    left, right : GrayImage
        A rectified pair (corresponding pixels on the same row), one size.
    min_disparity : int
        The smallest disparity searched.
    num_disparities : int
        How many disparities are searched.
    window : int
        Side of the cost's neighbourhood (odd): the census window (at most
        7), or the SAD, SSD or NCC block.
    block : int or None
        Side of the square the pixel costs are summed over (odd; 1 keeps each
        pixel's cost). None: 9 for census, 1 for SAD, SSD and NCC (already
        means over the window: the classic single window).
    cost : {"census", "zncc", "sad", "ssd"}
        Dissimilarity (see :func:`cost_volume`); census and zero-mean NCC
        ignore a gain and bias between the cameras.
    uniqueness : float
        Margin by which the winner must beat every non-neighbouring disparity.
    subpixel : bool
        Refine by fitting a parabola to the costs around the winner.
    lr_tolerance : float or None
        Largest left-right disagreement in pixels; None skips the check.
    speckle_window : int
        Largest region of similar disparity that is invalidated as a speckle
        (0: no filtering).
    speckle_range : float
        Largest disparity step between neighbours of one region, pixels.

    Returns
    -------
    Disparity
        float32, NaN where no estimate survived.

    References
    ----------
    .. [1] Scharstein & Szeliski, "A taxonomy and evaluation of dense two-frame
       stereo correspondence algorithms", IJCV 47, 2002.
    .. [2] R. Zabih & J. Woodfill, "Non-parametric local transforms for computing
       visual correspondence", ECCV 1994 (census).
    """
    check_pair(left, right, min_disparity, num_disparities, window)
    block = (9 if cost == "census" else 1) if block is None else block
    if cost == "census":  # by running sums, row by row: no volume
        found = census_block_match(
            left, right, min_disparity, num_disparities, window, block, uniqueness, subpixel
        )
        return _checked(*found, lr_tolerance, speckle_window, speckle_range)
    volume = _volume(left, right, min_disparity, num_disparities, cost, window, block)
    return _select(
        volume, min_disparity, uniqueness, subpixel, lr_tolerance, speckle_window, speckle_range
    )


def _jumps(
    image: np.ndarray, step_y: int, step_x: int, p1: float, p2: float, edge: float | None
) -> np.ndarray:
    r"""The jump penalty of each pixel for the path along ``(step_y, step_x)``:
    :math:`\max(P_1, P_2 / (1 + |I(p) - I(p - r)| / \text{edge}))` (``edge`` None: P2)."""
    if edge is None:
        return np.full(image.shape, p2, dtype=np.float64)
    rows, cols = image.shape
    padded = np.pad(image.astype(np.float64), 1, mode="edge")
    before = padded[1 - step_y : 1 - step_y + rows, 1 - step_x : 1 - step_x + cols]
    change = np.abs(image - before)
    jumps: np.ndarray = np.maximum(p1, p2 / (1.0 + change / edge))
    return jumps


@node(
    "stereo.sgm",
    version=2,
    check=_sgm_params,
    conformance=Conformance(
        "disparity",
        0.01,
        radius=1.0,
        mismatch=0.15,
        note=(
            "OpenCV returns 1/16-pixel fixed point (divided by 16 here, NaN where invalid), "
            "matches by Birchfield-Tomasi SAD of 8-bit images (cost is the reference's), its "
            "penalties 8b² and 32b² are scaled by p1/12 and p2/128 (other units: with "
            "cost='sad' the two disagree on 16 % of the pixels), paths=4 runs its 5-path "
            "mode, edge has no counterpart, and it leaves the first min_disparity + 16⌈n/16⌉ "
            "columns invalid; with census, at most 1 % of the pixels valid in both differ by "
            "more than 1 px"
        ),
    ),
)
def sgm(
    left: GrayImage,
    right: GrayImage,
    *,
    min_disparity: int = 0,
    num_disparities: Annotated[int, Field(ge=1, le=1024)] = 64,
    window: Window = 7,
    block: Window | None = None,
    cost: Cost = "census",
    p1: Annotated[float, Field(ge=0)] = 12.0,
    p2: Annotated[float, Field(ge=0)] = 128.0,
    edge: Annotated[float, Field(gt=0)] | None = 0.02,
    paths: Literal[4, 8] = 8,
    uniqueness: Annotated[float, Field(ge=0)] = 0.05,
    subpixel: bool = True,
    lr_tolerance: Annotated[float, Field(ge=0)] | None = 1.0,
    speckle_window: SpeckleWindow = 100,
    speckle_range: SpeckleRange = 2.0,
) -> Disparity:
    r"""Disparity by semi-global matching: pixel costs smoothed along 4 or 8 straight paths.

    The matching cost :math:`C(p, d)` of each pixel (census over a
    ``window × window`` neighbourhood by default) is summed over the
    ``block × block`` square around it. Along each path direction :math:`r`
    it is then aggregated as

    .. math::

        L_r(p, d) = C(p, d) + \min\big(L_r(p - r, d),\; L_r(p - r, d \pm 1) + P_1,\;
        \min_k L_r(p - r, k) + P_2(p, r)\big) - \min_k L_r(p - r, k)

    so a change of one disparity step costs :math:`P_1` and a jump
    :math:`P_2` (:math:`P_2 \ge P_1`): a 1-D approximation of a global
    smoothness energy. Depth jumps come with intensity edges, so the jump
    penalty falls where the left image changes along the path
    (Hirschmüller's :math:`P_2 / |\Delta I|`, bounded):

    .. math:: P_2(p, r) = \max\big(P_1,\ P_2 / (1 + |I(p) - I(p - r)| / \text{edge})\big).

    The summed :math:`S(p, d) = \sum_r L_r(p, d)` is then resolved as in
    :func:`block_match`: winner take all, uniqueness, sub-pixel parabola,
    left-right check against the right image's disparity read from the same
    volume, and the speckle filter (:func:`filter_speckles`).

    The defaults were chosen on rendered piecewise-planar scenes textured
    with photographs (``synthetic.planar_stereo_scene``: the camera, clock,
    coins, grass, moon, page and text images, seeds 100–105, and the
    default images, seeds 0–3; some with another exposure of the right
    camera) so as to keep or improve the Middlebury Motorcycle figures, and
    checked on other scenes: see ``bench/bench_stereo.py``.

    Parameters
    ----------
    left, right : GrayImage
        A rectified pair, one size.
    min_disparity : int
        The smallest disparity searched.
    num_disparities : int
        How many disparities are searched.
    window : int
        Side of the matching-cost neighbourhood (odd; census: at most 7, 48 bits).
    block : int or None
        Side of the square the pixel costs are summed over before the paths
        (odd; 1 keeps each pixel's own cost). None: 5 for census, 1 for SAD,
        SSD and NCC (already means over the window).
    cost : {"census", "sad", "ssd", "zncc"}
        Pixel matching cost; ``p1`` and ``p2`` are in its units per pixel
        (census: bits), whatever ``block`` is.
    p1 : float
        Penalty for a disparity change of one step between path neighbours.
    p2 : float
        Penalty for a larger change on a flat image (at least ``p1``).
    edge : float or None
        Intensity change along a path (image units) that halves ``p2``; None
        keeps ``p2`` everywhere.
    paths : {4, 8}
        Horizontal and vertical paths, or these and the diagonals.
    uniqueness : float
        Margin by which the winner must beat every non-neighbouring disparity.
    subpixel : bool
        Parabola refinement of the winner.
    lr_tolerance : float or None
        Largest left-right disagreement in pixels; None skips the check.
    speckle_window : int
        Largest region of similar disparity that is invalidated as a speckle
        (0: no filtering).
    speckle_range : float
        Largest disparity step between neighbours of one region, pixels.

    Returns
    -------
    Disparity
        float32, NaN where no estimate survived.

    References
    ----------
    .. [1] H. Hirschmüller, "Stereo processing by semiglobal matching and mutual
       information", IEEE TPAMI 30(2), 2008.
    .. [2] R. Zabih & J. Woodfill, "Non-parametric local transforms for computing
       visual correspondence", ECCV 1994 (census).
    """
    check_pair(left, right, min_disparity, num_disparities, window)
    from ._kernels import aggregate_path

    block = (5 if cost == "census" else 1) if block is None else block
    area = block * block
    scaled_p1, scaled_p2 = p1 * area, p2 * area
    highest = maximum_cost(cost, window) * area
    integral = cost == "census" and float(scaled_p1).is_integer() and float(scaled_p2).is_integer()
    if integral and paths * (highest + scaled_p2) <= np.iinfo(np.uint16).max:
        # each path's cost is at most C_max + P2, so the sum fits in 16 bits: two sweeps
        found = census_sgm(
            left,
            right,
            (min_disparity, num_disparities, window, block),
            (int(scaled_p1), int(scaled_p2), edge),
            paths,
            (uniqueness, subpixel),
        )
        return _checked(*found, lr_tolerance, speckle_window, speckle_range)
    volume = _volume(left, right, min_disparity, num_disparities, cost, window, block)
    volume = volume.astype(np.float32)
    total = np.zeros_like(volume)
    for step_y, step_x in PATHS[:paths]:
        jumps = _jumps(left, step_y, step_x, scaled_p1, scaled_p2, edge).astype(np.float32)
        aggregate_path(volume, total, step_y, step_x, np.float32(scaled_p1), jumps)
    return _select(
        total,
        min_disparity,
        uniqueness,
        subpixel,
        lr_tolerance,
        speckle_window,
        speckle_range,
    )
