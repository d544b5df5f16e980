"""The Hough transform for lines in (ρ, θ), with the course's improvements."""

from __future__ import annotations

import math
from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import BinaryImage, FloatImage, GrayImage, Int, node

from .._params import Count
from ..edges import gradient_images
from ._peaks import local_maxima, quadratic_peak_2d, suppress_close
from ._ports import Lines

__all__ = ["HoughLines", "hough_lines", "line_accumulator"]


def _rho_grid(shape: tuple[int, ...], step: float) -> tuple[int, float]:
    """Number of ρ bins and the ρ of bin 0: a grid symmetric about 0 covering the diagonal."""
    half = math.ceil(math.hypot(shape[0], shape[1]) / step) + 1
    return 2 * half + 1, -half * step


def line_accumulator(
    edges: np.ndarray,
    image: np.ndarray | None,
    theta_bins: int,
    rho_step: float,
    orientation_window: float,
    weighted: bool,
    sigma: float,
) -> np.ndarray:
    """The (θ, ρ) vote array (``theta_bins × n_rho``), votes split linearly between ρ bins."""
    rows, cols = np.nonzero(edges)
    x, y = cols.astype(np.float64), rows.astype(np.float64)
    n_rho, rho0 = _rho_grid(edges.shape, rho_step)
    step = math.pi / theta_bins
    weights = np.ones(len(x))
    if image is None:
        first, width = np.zeros(len(x), dtype=np.intp), theta_bins
    else:
        dx, dy = gradient_images(image, "gaussian", sigma)
        gx, gy = dx[rows, cols].astype(np.float64), dy[rows, cols].astype(np.float64)
        if weighted:
            weights = np.hypot(gx, gy)
        centre = np.round(np.mod(np.arctan2(gy, gx), math.pi) / step).astype(np.intp)
        half = min(int(round(math.radians(orientation_window) / step)), theta_bins // 2)
        width = min(2 * half + 1, theta_bins)
        first = np.mod(centre - half, theta_bins) if width < theta_bins else np.zeros_like(centre)
    from ._kernels import vote_lines

    table = np.arange(theta_bins) * step
    cos, sin = np.cos(table) / rho_step, np.sin(table) / rho_step
    return vote_lines(x, y, weights, first, width, cos, sin, rho0 / rho_step, n_rho)


def _wrap_theta(accumulator: np.ndarray, pad: int) -> np.ndarray:
    """Extend θ by ``pad`` bins each way: θ + π is the line of θ with ρ negated."""
    return np.concatenate([accumulator[-pad:, ::-1], accumulator, accumulator[:pad, ::-1]], axis=0)


class HoughLines(NamedTuple):
    lines: Lines
    count: Int  # type: ignore[assignment]  # the port is named count in pipelines; hides tuple.count
    accumulator: FloatImage


@node("hough.lines", version=1)
def hough_lines(
    edges: BinaryImage,
    image: GrayImage | None = None,
    *,
    theta_bins: Annotated[int, Field(ge=4, le=3600)] = 180,
    rho_step: Annotated[float, Field(gt=0, le=100)] = 1.0,
    orientation_window: Annotated[float, Field(ge=0, le=90)] = 5.0,
    weighted: bool = True,
    sigma: Annotated[float, Field(gt=0, le=50)] = 1.0,
    vote_sigma: Annotated[float, Field(ge=0, le=20)] = 1.0,
    threshold: Annotated[float, Field(gt=0, le=1)] = 0.5,
    min_distance: Annotated[int, Field(ge=1, le=1000)] = 5,
    max_lines: Count = 100,
) -> HoughLines:
    r"""Lines by voting in (ρ, θ), with the course's improvements.

    A line is :math:`x\cos\theta + y\sin\theta = \rho`.

    Each edge point votes for the lines through it: for every :math:`\theta`
    bin, :math:`H[\rho(\theta), \theta] \mathrel{+}= 1`, the vote split
    linearly between the two nearest :math:`\rho` bins. With ``image``
    connected, the course's improvements apply: a point votes only for
    :math:`\theta` within ``orientation_window`` degrees of its gradient
    orientation (the line's normal), with weight the gradient magnitude
    :math:`m(x, y)` when ``weighted``. The accumulator is smoothed by a
    Gaussian of ``vote_sigma`` bins (a vote spread to neighbouring cells; θ
    wraps with :math:`\rho \to -\rho`), peaks are local maxima of at least
    ``threshold`` × the strongest, kept ``min_distance`` bins apart
    (strongest first), and each is refined to a fraction of a bin by a
    parabola through its neighbours.

    ρ and θ follow OpenCV's and scikit-image's convention (the course writes
    :math:`x\cos\theta - y\sin\theta = d` with y up): x is the column, y the
    row, :math:`\theta \in [0, \pi)`.

    Parameters
    ----------
    edges : (H, W) bool ndarray
        The edge points (e.g. ``edges.canny``).
    image : (H, W) float32 ndarray, optional
        The gray image, for the gradient orientation and magnitude.
    theta_bins : int
        Bins over :math:`[0, \pi)`.
    rho_step : float
        Bin width of :math:`\rho` in pixels.
    orientation_window : float
        Half width in degrees of the θ range a point votes for (with ``image``).
    weighted : bool
        Weight votes by the gradient magnitude (with ``image``).
    sigma : float
        Gaussian scale of the gradient (with ``image``).
    vote_sigma : float
        Standard deviation in bins of the vote spreading (0: none).
    threshold : float
        Smallest peak, as a fraction of the strongest.
    min_distance : int
        Least distance in bins between two peaks.
    max_lines : int
        Most lines returned, strongest first.

    Returns
    -------
    lines : Lines, ``(ρ, θ, votes)`` rows, strongest first
    count : int
    accumulator : (theta_bins, n_rho) float32, the smoothed votes

    References
    ----------
    .. [1] R. O. Duda, P. E. Hart, "Use of the Hough transformation to detect
       lines and curves in pictures", Comm. ACM 15(1), 1972.
    .. [2] Szeliski (2022), section 7.4.2.
    """
    from .._separable import smooth_gaussian

    if image is not None and image.shape != edges.shape:
        raise ValueError(
            f"edges and image must have the same size, got {edges.shape} and {image.shape}"
        )
    votes = line_accumulator(
        edges, image, theta_bins, rho_step, orientation_window, weighted, sigma
    )
    pad = min(theta_bins, min_distance + 3 * math.ceil(vote_sigma) + 1)
    extended = _wrap_theta(votes, pad)
    if vote_sigma > 0:
        extended = smooth_gaussian(extended, vote_sigma, "nearest")
    smoothed = extended[pad:-pad]
    strongest = float(smoothed.max(initial=0.0))
    peaks = local_maxima(extended, 2 * min_distance + 1, threshold * strongest)
    peaks = peaks[(peaks[:, 0] >= pad) & (peaks[:, 0] < pad + theta_bins)]
    peaks = peaks[(peaks[:, 1] > 0) & (peaks[:, 1] < votes.shape[1] - 1)]
    scores = extended[peaks[:, 0], peaks[:, 1]]
    kept = peaks[suppress_close(peaks.astype(np.float64), scores, min_distance, max_lines)]
    t, r = kept[:, 0], kept[:, 1]
    centre = extended[t, r]
    d_theta, d_rho = quadratic_peak_2d(extended, t, r).T
    _, rho0 = _rho_grid(edges.shape, rho_step)
    theta = (t - pad + d_theta) * (math.pi / theta_bins)
    rho = rho0 + (r + d_rho) * rho_step
    flip = (theta < 0) | (theta >= math.pi)
    theta = np.where(flip, np.mod(theta, math.pi), theta)
    rho = np.where(flip, -rho, rho)
    lines = np.column_stack([rho, theta, centre]).astype(np.float64).reshape(-1, 3)
    return HoughLines(lines, len(lines), smoothed.astype(np.float32))
