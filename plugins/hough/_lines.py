"""The Hough transform for lines in (ρ, θ), with the course's improvements."""

from __future__ import annotations

import functools
import math
import threading
from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import BinaryImage, Conformance, FloatImage, GrayImage, Int, node

from ..edges import gradient_images
from ..shared.params import Count
from ..shared.separable import gaussian_taps
from ._ports import Lines

__all__ = ["HoughLines", "hough_lines", "line_accumulator"]
SUPPORT_ORIENTATION = math.pi / 16  # a supporting point's gradient, at least this near the normal


def _rho_grid(shape: tuple[int, ...], step: float) -> tuple[int, float]:
    """Number of ρ bins and the ρ of bin 0: a grid symmetric about 0 covering the diagonal."""
    half = math.ceil(math.hypot(shape[0], shape[1]) / step) + 1
    return 2 * half + 1, -half * step


def _edge_points(
    edges: np.ndarray, image: np.ndarray | None, sigma: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Edge points ``x`` (column), ``y`` (row) and, with ``image``, their gradient ``gx, gy``."""
    from ._kernels import edge_points

    x, y = edge_points(np.ascontiguousarray(edges, dtype=np.bool_))
    if image is None:
        return x, y, None, None
    rows, cols = y.astype(np.intp), x.astype(np.intp)
    dx, dy = gradient_images(image, "gaussian", sigma)
    return x, y, dx[rows, cols].astype(np.float64), dy[rows, cols].astype(np.float64)


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
    x, y, gx, gy = _edge_points(edges, image, sigma)
    return _vote(edges.shape, x, y, gx, gy, theta_bins, rho_step, orientation_window, weighted, 0)


def _vote(
    shape: tuple[int, ...],
    x: np.ndarray,
    y: np.ndarray,
    gx: np.ndarray | None,
    gy: np.ndarray | None,
    theta_bins: int,
    rho_step: float,
    orientation_window: float,
    weighted: bool,
    pad: int,
    reuse: bool = False,
) -> np.ndarray:
    """The votes, extended by ``pad`` θ rows each way: θ + π is the line of θ with ρ
    negated, so row ``-1`` is the last row reversed along ρ. With ``reuse``, written into
    the thread's workspace (:func:`_workspace`), else into a new array."""
    n_rho, rho0 = _rho_grid(shape, rho_step)
    step = math.pi / theta_bins
    weights = np.ones(len(x))
    if gx is None or gy is None:
        first, width = np.zeros(len(x), dtype=np.intp), theta_bins
    else:
        if weighted:
            weights = np.hypot(gx, gy)
        centre = np.round(np.mod(np.arctan2(gy, gx), math.pi) / step).astype(np.intp)
        half = min(int(round(math.radians(orientation_window) / step)), theta_bins // 2)
        width = min(2 * half + 1, theta_bins)
        first = np.mod(centre - half, theta_bins) if width < theta_bins else np.zeros_like(centre)
    from ._kernels import vote_lines_into

    table = np.arange(theta_bins) * step
    cos, sin = np.cos(table) / rho_step, np.sin(table) / rho_step
    size = (theta_bins + 2 * pad, n_rho)
    extended = _workspace(size)[0] if reuse else np.empty(size)
    vote_lines_into(extended, x, y, weights, first, width, cos, sin, rho0 / rho_step, pad)
    return extended


_THREAD = threading.local()


def _workspace(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """The calling thread's two float64 arrays of ``shape`` (votes and smoothed votes),
    kept from its previous call of the same shape: a 512² image's pair is 2 × 2.3 MB, whose
    fresh pages (above glibc's mmap threshold) cost a third of the node's time in page
    faults. Nothing returned by a node refers to them."""
    held = getattr(_THREAD, "arrays", None)
    if held is None or held[0].shape != shape:
        held = (np.empty(shape), np.empty(shape))
        _THREAD.arrays = held
    return held


@functools.lru_cache(maxsize=16)
def _smoothing(
    sigma: float, rows: int, cols: int
) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
    """Gaussian taps of ``sigma``, their symmetry and the ``nearest`` boundary indices of
    ``rows`` and ``cols`` (``shared.separable.smooth_gaussian``'s, computed once)."""
    taps = gaussian_taps(sigma)
    half = taps.size // 2
    row_index = np.clip(np.arange(-half, rows + half), 0, rows - 1)
    column_index = np.clip(np.arange(-half, cols + half), 0, cols - 1)
    return taps, int(np.array_equal(taps, taps[::-1])), row_index, column_index


def _smooth_votes(votes: np.ndarray, sigma: float, out: np.ndarray) -> np.ndarray:
    """``shared.separable.smooth_gaussian(votes, sigma, "nearest")`` written into ``out``
    (the same compiled kernel on the same input: equal to the bit)."""
    from ..shared.separable_kernels import correlate_both

    taps, symmetry, row_index, column_index = _smoothing(sigma, *votes.shape)
    correlate_both(votes, taps, symmetry, row_index, taps, symmetry, column_index, out)
    return out


def _refined_peaks(
    extended: np.ndarray,
    t: np.ndarray,
    r: np.ndarray,
    pad: int,
    step: float,
    rho0: float,
    rho_step: float,
) -> tuple[np.ndarray, np.ndarray]:
    """θ and ρ of the peaks at bins ``(t, r)`` of ``extended``, refined by a quadratic fit."""
    from ._kernels import peak_offsets

    d_theta, d_rho = peak_offsets(extended, t, r, _quadratic_solve()).T
    theta = (t - pad + d_theta) * step
    rho = rho0 + (r + d_rho) * rho_step
    return theta, rho


def _by_orientation(
    x: np.ndarray, y: np.ndarray, orientation: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """The points and their orientations (zeros when there are none), sorted by orientation
    when there are, and whether there are."""
    check = orientation is not None
    angles = np.zeros(len(x))
    if orientation is not None:  # sorted by orientation, each line scans only its own
        by_angle = np.argsort(orientation, kind="stable")
        x, y, angles = x[by_angle], y[by_angle], orientation[by_angle]
    return x, y, angles, check


def _select_lines(
    extended: np.ndarray,
    raw: np.ndarray,
    pad: int,
    shape: tuple[int, ...],
    points: tuple[np.ndarray, np.ndarray, np.ndarray | None],
    theta_bins: int,
    rho_step: float,
    orientation_window: float,
    threshold: float,
    min_distance: int,
    max_lines: int,
) -> np.ndarray:
    """``(ρ, θ, support)`` rows of the lines kept (see :func:`hough_lines`), best first;
    ``raw`` is the unsmoothed ``extended``, bounding the support of unit votes."""
    from ._kernels import line_peaks
    from ._select_kernels import select_lines
    from ._support_kernels import line_support, pruned_support, support_bounds

    x, y, orientation = points
    peaks = line_peaks(extended, pad, theta_bins)  # every peak: one line can mask another's
    if len(peaks) == 0 or len(x) == 0:
        return np.zeros((0, 3))
    t, r = peaks[:, 0], peaks[:, 1]
    step = math.pi / theta_bins
    _, rho0 = _rho_grid(shape, rho_step)
    theta, rho = _refined_peaks(extended, t, r, pad, step, rho0, rho_step)
    x, y, angles, check = _by_orientation(x, y, orientation)
    window = max(SUPPORT_ORIENTATION, math.radians(orientation_window) + 0.5 * step)
    tolerance = max(1.0, rho_step)
    extent = math.hypot(shape[0], shape[1]) + 1.0
    index = _point_index(x, y, shape, check)
    if check:
        support = line_support(x, y, angles, check, rho, theta, tolerance, window, extent, index)
    else:  # unit votes bound the support: only the lines that can be kept are measured
        size = (rho0 / rho_step, rho_step, tolerance, shape[1] - 1.0, shape[0] - 1.0)
        bounds = support_bounds(raw, pad, rho, theta, *size)
        support = pruned_support(x, y, index, bounds, rho, theta, tolerance, extent, threshold)
    floor = threshold * float(support.max())
    if floor <= 0:
        return np.zeros((0, 3))
    order = np.lexsort((-extended[t, r], -support))  # most support first, then most votes
    order = order[support[order] >= floor]
    lines = select_lines(
        x,
        y,
        angles,
        check,
        rho,
        theta,
        order,
        floor,
        tolerance,
        window,
        extent,
        max_lines,
        float(min_distance),
        step,
        rho_step,
        index,
    )
    return lines[np.argsort(-lines[:, 2], kind="stable")]


def _point_index(x: np.ndarray, y: np.ndarray, shape: tuple[int, ...], check: bool) -> tuple:
    """The points by row and by column (``_kernels.points_by_row_and_column``) and the
    image's last column and row, for ``_kernels._band``; empty when ``check`` (the points
    are then scanned by orientation)."""
    from ._kernels import points_by_row_and_column

    if check:
        x = y = np.zeros(0)
    found = points_by_row_and_column(x, y, shape[0], shape[1])
    return (*found, float(shape[1] - 1), float(shape[0] - 1))


@functools.cache
def _quadratic_solve() -> np.ndarray:
    """The pseudo-inverse ``_peaks.quadratic_peak_2d`` fits a 3×3 patch with."""
    u, v = np.repeat([-1.0, 0.0, 1.0], 3), np.tile([-1.0, 0.0, 1.0], 3)
    return np.linalg.pinv(np.column_stack([np.ones(9), u, v, u * u, v * v, u * v]))


class HoughLines(NamedTuple):
    lines: Lines
    count: Int  # type: ignore[assignment]  # the port is named count in pipelines; hides tuple.count
    accumulator: FloatImage


@node(
    "hough.lines",
    version=2,
    conformance=Conformance(
        "recall",
        0.9,
        radius=1.5,
        note=(
            "lines compared by (ρ in pixels, θ in degrees) within 1.5 of each other; OpenCV's "
            "θ is the bin's (no sub-bin placement, no refit to the edge points), its votes are "
            "unweighted and unspread (image, orientation_window, weighted, vote_sigma are the "
            "reference's), ties of equal counts keep OpenCV's order, and its third column "
            "counts edge points where the reference's measures the length they cover"
        ),
    ),
)
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
    max_lines: Count = 1000,
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
    wraps with :math:`\rho \to -\rho`) and every local maximum (3×3) is a
    candidate, placed to a fraction of a bin by a quadratic through its 3×3
    cells.

    Which candidates are lines is decided by their *support*, not by their
    votes (which grow with contrast, and whose peaks are lower the further a
    short segment lies from the foot of the normal through the origin, because
    its ridge in (θ, ρ) is sheared by :math:`d\rho/d\theta` = that distance).
    A point supports a line when it lies within ``max(1, rho_step)`` pixels of
    it and, with ``image``, its gradient is within
    :math:`\max(\pi/16,` ``orientation_window`` + half a bin) of the line's
    normal; the support is the length of the line its points cover, in 1-px
    cells along it (so a thick or doubled edge does not count twice).
    Candidates are taken most supported first; each is refitted twice by total
    least squares to its free supporting points (a peak's θ is coarse for a
    short segment), and kept when those still cover at least ``threshold`` ×
    the largest support of any candidate and it lies ``min_distance`` bins from
    every line kept; its points are then claimed, so a ridge of the same
    segment at a neighbouring θ finds them gone. The default 0.5 is
    scikit-image's rule, threshold = 0.5 × the largest count of its
    accumulator, applied to what its count measures: edge points along a line.

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
        Smallest support of a line (length covered by its edge points), as a
        fraction of the largest support among the candidates.
    min_distance : int
        Least distance in bins, :math:`\sqrt{\Delta\theta^2 + \Delta\rho^2}`,
        between two lines.
    max_lines : int
        Most lines returned, best supported first.

    Returns
    -------
    lines : Lines, ``(ρ, θ, support)`` rows, best supported first; support in
        pixels of the line covered by its edge points
    count : int
    accumulator : (theta_bins, n_rho) float32, the smoothed votes

    References
    ----------
    .. [1] R. O. Duda, P. E. Hart, "Use of the Hough transformation to detect
       lines and curves in pictures", Comm. ACM 15(1), 1972.
    .. [2] Szeliski (2022), section 7.4.2 (refining each line by least
       squares on its edge points).
    .. [3] scikit-image, ``skimage.transform.hough_line_peaks`` (threshold
       0.5 × the accumulator's maximum).
    """
    if image is not None and image.shape != edges.shape:
        raise ValueError(
            f"edges and image must have the same size, got {edges.shape} and {image.shape}"
        )
    x, y, gx, gy = _edge_points(edges, image, sigma)
    pad = min(theta_bins, min_distance + 3 * math.ceil(vote_sigma) + 1)
    extended = _vote(
        edges.shape, x, y, gx, gy, theta_bins, rho_step, orientation_window, weighted, pad, True
    )
    raw = extended
    if vote_sigma > 0:
        extended = _smooth_votes(raw, vote_sigma, _workspace(raw.shape)[1])
    smoothed = extended[pad:-pad]
    orientation = None
    if gx is not None and gy is not None:
        moving = np.hypot(gx, gy) > 0  # a point without a gradient has no orientation
        x, y, gx, gy = x[moving], y[moving], gx[moving], gy[moving]
        orientation = np.mod(np.arctan2(gy, gx), math.pi)
    lines = _select_lines(
        extended,
        raw,
        pad,
        edges.shape,
        (x, y, orientation),
        theta_bins,
        rho_step,
        orientation_window,
        threshold,
        min_distance,
        max_lines,
    )
    return HoughLines(lines, len(lines), smoothed.astype(np.float32))
