"""The Hough transform for circles along the gradient: known radius or a range (3-D)."""

from __future__ import annotations

import math
from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import BinaryImage, Conformance, FloatImage, GrayImage, Int, node

from ..edges import gradient_images
from ..shared.checks import ordered
from ..shared.params import Count, Positive
from ._peaks import parabolic_offset, suppress_close
from ._ports import Circles

__all__ = ["HoughCircles", "circle_accumulator", "hough_circles"]

Polarity = Literal["both", "bright", "dark"]


def circle_accumulator(
    edges: np.ndarray, image: np.ndarray, radii: np.ndarray, sigma: float, polarity: str
) -> np.ndarray:
    r"""Votes ``(len(radii), H, W)``: each edge point votes at :math:`p \pm r u`, u its gradient.

    A bright disc's gradient points inwards, so ``bright`` votes at
    :math:`p + r u`, ``dark`` at :math:`p - r u`, ``both`` at both.
    """
    from ._circle_kernels import vote_circles

    rows, cols, ux, uy, signs = _voters(edges, image, sigma, polarity)
    radii = np.ascontiguousarray(radii, dtype=np.float64)
    return vote_circles(rows, cols, ux, uy, radii, signs, *edges.shape)


def _voters(
    edges: np.ndarray, image: np.ndarray, sigma: float, polarity: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rows, columns and unit gradients of the edge points with a gradient, and the signs
    they vote with."""
    rows, cols = np.nonzero(edges)
    dx, dy = gradient_images(image, "gaussian", sigma)
    gx, gy = dx[rows, cols].astype(np.float64), dy[rows, cols].astype(np.float64)
    norm = np.hypot(gx, gy)
    moving = norm > 0
    rows, cols = rows[moving], cols[moving]
    ux, uy = gx[moving] / norm[moving], gy[moving] / norm[moving]
    signs = {"both": (1.0, -1.0), "bright": (1.0,), "dark": (-1.0,)}[polarity]
    return rows, cols, ux, uy, np.array(signs)


def _best_over_radii(
    edges: np.ndarray,
    image: np.ndarray,
    radii: np.ndarray,
    sigma: float,
    polarity: str,
    vote_sigma: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Best score over radii at each pixel, its radius index and the scores of the radii
    either side: one radius at a time (votes, spread, score), never the whole stack, all
    in one compiled call (``_circle_kernels.best_over_radii``). The spreading equals
    ``smooth_gaussian(votes, vote_sigma, "constant")`` to the bit, computed only near
    the votes."""
    from ..shared.separable import _odd_length, gaussian_taps
    from ._circle_kernels import best_over_radii

    rows, cols, ux, uy, signs = _voters(edges, image, sigma, polarity)
    # symmetric: u and −u give the same exponent
    taps = _odd_length(gaussian_taps(vote_sigma, 4.0)) if vote_sigma > 0 else np.zeros(0)
    # spread each vote as a Gaussian of height 1 (so one vote still counts one)
    spread = 2.0 * math.pi * vote_sigma**2 if vote_sigma > 0 else 1.0
    radii = np.ascontiguousarray(radii, dtype=np.float64)
    voters = (rows.astype(np.int64), cols.astype(np.int64), ux, uy)
    return best_over_radii(voters, radii, signs, spread, edges.shape, taps)


class HoughCircles(NamedTuple):
    circles: Circles
    count: Int  # type: ignore[assignment]  # the port is named count in pipelines; hides tuple.count
    accumulator: FloatImage


@node(
    "hough.circles",
    version=1,
    check=ordered(("min_radius", "max_radius")),
    conformance=Conformance(
        "recall",
        1.0,
        radius=1.5,
        note=(
            "circles compared by (x, y, r) within 1.5 px; OpenCV votes from its own Canny "
            "edges of the 8-bit image on a 1-px grid (centres at half pixels, no sub-pixel "
            "peak), and its score is the share of the circumference on `edges` (about 1 for "
            "a whole circle, where the reference's fraction that voted is about 0.5), so one "
            "threshold keeps more circles; polarity is judged by the mean inside against a ring"
        ),
    ),
)
def hough_circles(
    edges: BinaryImage,
    image: GrayImage,
    *,
    min_radius: Positive = 10.0,
    max_radius: Positive = 30.0,
    radius_step: Positive = 1.0,
    polarity: Polarity = "both",
    sigma: Annotated[float, Field(gt=0, le=50)] = 1.0,
    vote_sigma: Annotated[float, Field(ge=0, le=20)] = 1.0,
    threshold: Annotated[float, Field(gt=0, le=1)] = 0.3,
    min_distance: Positive | None = None,
    max_circles: Count = 100,
) -> HoughCircles:
    r"""Circles by voting for centres along the gradient, over a range of radii.

    A circle :math:`(x - a)^2 + (y - b)^2 = r^2` through an edge point
    :math:`p` has its centre on the line of the gradient at :math:`p`: instead
    of a whole circle of candidate centres (the course's cone in the 3-D
    space :math:`(a, b, r)`), each point votes at :math:`p \pm r\,u` for every
    radius, :math:`u = \nabla I / \|\nabla I\|`. ``min_radius == max_radius``
    is the transform for a known radius. Votes at radius :math:`r` are spread
    by a Gaussian of ``vote_sigma`` pixels and height one and divided by the circumference
    :math:`2\pi r`, so a score is the fraction of the circle's edge that
    voted (1 for a complete, perfectly centred circle). A centre's radius is
    its best-scoring one; centres that are local maxima scoring at least
    ``threshold``, kept ``min_distance`` apart (strongest first), are refined
    to a fraction of a pixel and of a radius step by parabolas.

    Parameters
    ----------
    edges : (H, W) bool ndarray
        The edge points (e.g. ``edges.canny``).
    image : (H, W) float32 ndarray
        The gray image, for the gradient direction.
    min_radius, max_radius : float
        Radius range in pixels.
    radius_step : float
        Radius bin width in pixels.
    polarity : {"both", "bright", "dark"}
        Bright circles on dark (votes inwards along the gradient), dark on bright, or both.
    sigma : float
        Gaussian scale of the gradient.
    vote_sigma : float
        Spread of each vote in pixels (0: none).
    threshold : float
        Smallest score (fraction of the circumference that voted).
    min_distance : float, optional
        Least distance between two centres; ``min_radius`` by default.
    max_circles : int
        Most circles returned, strongest first.

    Returns
    -------
    circles : Circles, ``(x, y, r, score)`` rows, strongest first
    count : int
    accumulator : (H, W) float32, the best score over radii at each centre

    References
    ----------
    .. [1] D. H. Ballard, "Generalizing the Hough transform to detect arbitrary
       shapes", Pattern Recognition 13(2), 1981 (gradient-directed voting).
    .. [2] Szeliski (2022), section 7.4.2.
    """
    from ._circle_kernels import window_maxima

    if image.shape != edges.shape:
        raise ValueError(
            f"edges and image must have the same size, got {edges.shape} and {image.shape}"
        )
    radii = np.arange(min_radius, max_radius + radius_step / 2, radius_step)
    best, k_best, below_all, above_all = _best_over_radii(
        edges, image, radii, sigma, polarity, vote_sigma
    )
    distance = min_radius if min_distance is None else min_distance
    peaks = window_maxima(best, 2 * int(math.ceil(distance / 2)) + 1, 0.0)
    peaks = peaks[best[peaks[:, 0], peaks[:, 1]] >= threshold]
    height, width = best.shape
    peaks = peaks[
        (peaks[:, 0] > 0)
        & (peaks[:, 0] < height - 1)
        & (peaks[:, 1] > 0)
        & (peaks[:, 1] < width - 1)
    ]
    centre_scores = best[peaks[:, 0], peaks[:, 1]]
    kept = peaks[suppress_close(peaks.astype(np.float64), centre_scores, distance, max_circles)]
    y, x = kept[:, 0], kept[:, 1]
    k = k_best[y, x]
    centre = best[y, x]
    d_y = parabolic_offset(best[y - 1, x], best[y, x], best[y + 1, x])
    d_x = parabolic_offset(best[y, x - 1], best[y, x], best[y, x + 1])
    below, above = below_all[y, x], above_all[y, x]
    interior = (k > 0) & (k < len(radii) - 1)
    d_r = np.where(interior, parabolic_offset(below, centre, above), 0.0)
    circles = np.column_stack([x + d_x, y + d_y, radii[k] + d_r * radius_step, centre])
    return HoughCircles(circles.reshape(-1, 4), len(circles), best.astype(np.float32))
