"""OpenCV implementations of dense stereo: block matching (``StereoBM``) and semi-global
matching (``StereoSGBM``)."""

from __future__ import annotations

import numpy as np

from graphvision import implements

from .convert import EXTRA, REQUIRES, cv, disparity_from_cv, to_u8

__all__ = ["cv_block_match", "cv_sgm"]


def _side(window: int, block: int | None) -> int:
    """OpenCV's one block side: ``block`` when given and above 1, else ``window``."""
    return block if block is not None and block > 1 else window


def _finish(
    fixed: np.ndarray,
    min_disparity: int,
    num_disparities: int,
    subpixel: bool,
    speckle_window: int,
    speckle_range: float,
) -> np.ndarray:
    """OpenCV's 1/16-pixel disparity in graphvision's convention, rounded without
    ``subpixel``, speckles removed by the reference's filter."""
    from ..stereo._speckles import speckles

    disparity = disparity_from_cv(fixed, min_disparity, num_disparities)
    if not subpixel:
        disparity = np.rint(disparity)
    if speckle_window:
        disparity = speckles(disparity, speckle_window, speckle_range)
    return disparity.astype(np.float32)


@implements("stereo.block_match", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_block_match(
    left: np.ndarray,
    right: np.ndarray,
    *,
    min_disparity: int = 0,
    num_disparities: int = 64,
    window: int = 7,
    block: int | None = None,
    cost: str = "census",
    uniqueness: float = 0.1,
    subpixel: bool = True,
    lr_tolerance: float | None = 1.0,
    speckle_window: int = 100,
    speckle_range: float = 2.0,
) -> np.ndarray:
    """``cv2.StereoBM``: SAD of the x-Sobel-prefiltered 8-bit images over one
    ``block × block`` square (``window`` without ``block``; at least 5), the range
    rounded up to a multiple of 16 and cut back, uniqueness in whole percent, the
    left-right check in whole pixels (``disp12MaxDiff``), no texture threshold; the
    speckles are removed by the reference's filter. ``cost`` is the reference's alone."""
    from ..stereo._pair_checks import check_pair

    cv2 = cv()
    check_pair(left, right, min_disparity, num_disparities, window)
    matcher = cv2.StereoBM_create(
        numDisparities=16 * -(-num_disparities // 16), blockSize=max(5, _side(window, block))
    )
    matcher.setMinDisparity(min_disparity)
    matcher.setUniquenessRatio(round(100 * uniqueness))
    matcher.setTextureThreshold(0)
    matcher.setSpeckleWindowSize(0)
    matcher.setDisp12MaxDiff(-1 if lr_tolerance is None else int(np.ceil(lr_tolerance)))
    fixed = matcher.compute(to_u8(left), to_u8(right))
    return _finish(fixed, min_disparity, num_disparities, subpixel, speckle_window, speckle_range)


@implements("stereo.sgm", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_sgm(
    left: np.ndarray,
    right: np.ndarray,
    *,
    min_disparity: int = 0,
    num_disparities: int = 64,
    window: int = 7,
    block: int | None = None,
    cost: str = "census",
    p1: float = 12.0,
    p2: float = 128.0,
    edge: float | None = 0.02,
    paths: int = 8,
    uniqueness: float = 0.05,
    subpixel: bool = True,
    lr_tolerance: float | None = 1.0,
    speckle_window: int = 100,
    speckle_range: float = 2.0,
) -> np.ndarray:
    """``cv2.StereoSGBM``: Birchfield-Tomasi SAD of the prefiltered 8-bit images over
    one ``block × block`` square (``window`` without ``block``), its penalties OpenCV's
    advice ``8 b²`` and ``32 b²`` scaled by ``p1 / 12`` and ``p2 / 128`` (the
    reference's defaults: the two costs have other units), 8 paths (``MODE_HH``) or 5
    (``MODE_SGBM``, for ``paths=4``), no intensity-adaptive ``edge``; range, uniqueness,
    left-right check and speckles as in :func:`cv_block_match`. ``cost`` and ``edge``
    are the reference's alone."""
    from ..stereo._pair_checks import check_pair

    cv2 = cv()
    check_pair(left, right, min_disparity, num_disparities, window)
    side = _side(window, block)
    matcher = cv2.StereoSGBM_create(
        minDisparity=min_disparity,
        numDisparities=16 * -(-num_disparities // 16),
        blockSize=side,
        P1=round(8 * side * side * p1 / 12.0),
        P2=max(round(32 * side * side * p2 / 128.0), round(8 * side * side * p1 / 12.0) + 1),
        disp12MaxDiff=-1 if lr_tolerance is None else int(np.ceil(lr_tolerance)),
        uniquenessRatio=round(100 * uniqueness),
        speckleWindowSize=0,
        mode=cv2.STEREO_SGBM_MODE_HH if paths == 8 else cv2.STEREO_SGBM_MODE_SGBM,
    )
    fixed = matcher.compute(to_u8(left), to_u8(right))
    return _finish(fixed, min_disparity, num_disparities, subpixel, speckle_window, speckle_range)
