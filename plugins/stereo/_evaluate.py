"""Disparity and depth against ground truth: the Middlebury error figures."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from graphvision import Float, node

from ..shared.params import Positive
from ._ports import Depth, Disparity

__all__ = ["DisparityError", "depth_rmse", "disparity_error"]


class DisparityError(NamedTuple):
    bad: Float
    bad_valid: Float
    density: Float
    mean_abs: Float


def _same_shape(estimate: np.ndarray, truth: np.ndarray, what: str) -> None:
    if estimate.shape != truth.shape:
        raise ValueError(
            f"the {what} is {estimate.shape[0]}×{estimate.shape[1]} (rows×columns) but the"
            f" truth is {truth.shape[0]}×{truth.shape[1]}"
        )


@node("stereo.disparity_error", version=1)
def disparity_error(
    disparity: Disparity, truth: Disparity, *, threshold: Positive = 2.0
) -> DisparityError:
    r"""Percent of bad pixels, over all ground-truth pixels and over those estimated too.

    A pixel with a ground-truth disparity is *bad* when the estimate is
    invalid (NaN) or off by more than ``threshold`` pixels (the Middlebury
    "bad 2.0" figure for ``threshold = 2``):

    .. math:: \text{bad} = 100\,\frac{|\{p \in T : \hat d(p) \text{ invalid or }
        |\hat d(p) - d(p)| > \tau\}|}{|T|}

    with :math:`T` the pixels whose truth is known; ``bad_valid`` counts only
    pixels valid in both, ``density`` is the percent of all pixels with an
    estimate.

    Parameters
    ----------
    disparity : Disparity
        The estimate (NaN where invalid).
    truth : Disparity
        The ground truth (NaN where unknown).
    threshold : float
        Largest error of a good pixel, pixels.

    Returns
    -------
    bad, bad_valid, density : float, percent
    mean_abs : float, mean absolute error over pixels valid in both
    """
    _same_shape(disparity, truth, "disparity")
    known = np.isfinite(truth)
    estimated = np.isfinite(disparity)
    if not known.any():
        raise ValueError("the ground truth has no valid pixel")
    error = np.abs(disparity.astype(np.float64) - truth)
    both = known & estimated
    bad_known = (~estimated | (error > threshold))[known]
    bad_valid = 100.0 * float(np.mean(error[both] > threshold)) if both.any() else 100.0
    mean_abs = float(error[both].mean()) if both.any() else float("nan")
    return DisparityError(
        100.0 * float(bad_known.mean()), bad_valid, 100.0 * float(estimated.mean()), mean_abs
    )


@node("stereo.depth_rmse", version=1)
def depth_rmse(depth: Depth, truth: Depth) -> Float:
    r"""Root-mean-square depth error over pixels valid in both maps.

    .. math:: \sqrt{\tfrac{1}{|V|} \sum_{p \in V} (\hat Z(p) - Z(p))^2}

    Parameters
    ----------
    depth : Depth
        The estimate.
    truth : Depth
        The true depth.
    """
    _same_shape(depth, truth, "depth map")
    both = np.isfinite(depth) & np.isfinite(truth)
    if not both.any():
        raise ValueError("no pixel has both an estimated and a true depth")
    difference = depth[both].astype(np.float64) - truth[both]
    return float(np.sqrt(np.mean(difference**2)))
