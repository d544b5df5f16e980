"""OpenCV implementations of the Hough transforms: lines and circles."""

from __future__ import annotations

import numpy as np

from graphvision import implements

from .convert import EXTRA, REQUIRES, circles_from_cv, cv, lines_from_cv, to_u8

__all__ = ["cv_hough_circles", "cv_hough_lines"]


def _keep_apart(lines: np.ndarray, theta_step: float, rho_step: float, apart: float) -> np.ndarray:
    """Rows of ``lines`` (strongest first) at least ``apart`` bins from every row kept
    before them, :math:`\\sqrt{\\Delta\\theta^2 + \\Delta\\rho^2}` in bins, θ wrapping at π
    with ρ → −ρ."""
    kept: list[int] = []
    for i, (rho, theta, _) in enumerate(lines):
        near = False
        for j in kept:
            r, t = lines[j, 0], lines[j, 1]
            for dr, dt in ((rho - r, theta - t), (rho + r, theta - t - np.pi),
                           (rho + r, theta - t + np.pi)):  # fmt: skip
                if np.hypot(dt / theta_step, dr / rho_step) < apart:
                    near = True
        if not near:
            kept.append(i)
    return lines[kept]


@implements("hough.lines", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_hough_lines(
    edges: np.ndarray,
    image: np.ndarray | None = None,
    *,
    theta_bins: int = 180,
    rho_step: float = 1.0,
    orientation_window: float = 5.0,
    weighted: bool = True,
    sigma: float = 1.0,
    vote_sigma: float = 1.0,
    threshold: float = 0.5,
    min_distance: int = 5,
    max_lines: int = 1000,
) -> object:
    """``cv2.HoughLinesWithAccumulator`` (one unweighted vote per edge point and θ bin,
    peaks without sub-bin placement), then the reference's choice: lines with at least
    ``threshold`` × the largest count, ``min_distance`` bins apart, ``max_lines`` of
    them. The third column is OpenCV's count of edge points on the line (the reference's
    is the length they cover). OpenCV has no gradient votes: ``image``,
    ``orientation_window``, ``weighted``, ``sigma`` and ``vote_sigma`` are the
    reference's; ``accumulator`` is the reference's plain vote array."""
    from ..hough._lines import HoughLines, line_accumulator

    cv2 = cv()
    if image is not None and image.shape != edges.shape:
        raise ValueError(
            f"edges and image must have the same size, got {edges.shape} and {image.shape}"
        )
    theta_step = np.pi / theta_bins
    found = cv2.HoughLinesWithAccumulator(to_u8(edges), rho_step, theta_step, 1)
    lines = lines_from_cv(found)
    if len(lines):
        lines = lines[lines[:, 2] >= threshold * lines[:, 2].max()]
        lines = _keep_apart(lines, theta_step, rho_step, min_distance)[:max_lines]
    votes = line_accumulator(edges, None, theta_bins, rho_step, orientation_window, False, sigma)
    return HoughLines(lines, len(lines), votes.astype(np.float32))


def _coverage(edges: np.ndarray, circles: np.ndarray) -> np.ndarray:
    """The share of each circle's circumference, in 1-px steps, with an edge point
    within one pixel (8-neighbourhood) of it."""
    import scipy.ndimage as ndi

    near = ndi.binary_dilation(edges, ndi.generate_binary_structure(2, 1))
    rows, cols = edges.shape
    shares = np.zeros(len(circles))
    for i, (x, y, r) in enumerate(circles[:, :3]):
        angles = np.linspace(0.0, 2.0 * np.pi, max(8, int(np.ceil(2.0 * np.pi * r))), False)
        px = np.rint(x + r * np.cos(angles)).astype(int)
        py = np.rint(y + r * np.sin(angles)).astype(int)
        inside = (px >= 0) & (px < cols) & (py >= 0) & (py < rows)
        shares[i] = near[py[inside], px[inside]].sum() / len(angles)
    return shares


def _polarity(image: np.ndarray, circles: np.ndarray, polarity: str) -> np.ndarray:
    """Which circles are brighter (``bright``) or darker (``dark``) inside, by the mean
    inside ``0.7 r`` against the ring ``[1.2 r, 1.5 r]``; all with ``both``."""
    if polarity == "both" or not len(circles):
        return np.ones(len(circles), bool)
    y, x = np.mgrid[0 : image.shape[0], 0 : image.shape[1]]
    keep = np.zeros(len(circles), bool)
    for i, (cx, cy, r) in enumerate(circles[:, :3]):
        d = np.hypot(x - cx, y - cy)
        inner, ring = image[d < 0.7 * r], image[(d >= 1.2 * r) & (d <= 1.5 * r)]
        if inner.size and ring.size:
            keep[i] = (inner.mean() > ring.mean()) == (polarity == "bright")
    return keep


@implements("hough.circles", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_hough_circles(
    edges: np.ndarray,
    image: np.ndarray,
    *,
    min_radius: float = 10.0,
    max_radius: float = 30.0,
    radius_step: float = 1.0,
    polarity: str = "both",
    sigma: float = 1.0,
    vote_sigma: float = 1.0,
    threshold: float = 0.3,
    min_distance: float | None = None,
    max_circles: int = 100,
) -> object:
    """``cv2.HoughCirclesWithAccumulator(HOUGH_GRADIENT)`` on the 8-bit image (OpenCV
    finds its own Canny edges, high threshold 100 of 8-bit Sobel), centres
    ``min_distance`` apart, radii in ``[⌊min_radius⌋, ⌈max_radius⌉]``; each circle is
    scored as the reference scores it, by ``edges``: the share of its circumference
    with an edge point within a pixel, kept from ``threshold`` on (strongest first,
    ``max_circles``), ``polarity`` by the mean inside against a ring outside.
    ``radius_step``, ``sigma`` and ``vote_sigma`` are the reference's; ``accumulator``
    is zero (OpenCV does not return its own)."""
    from ..hough._circles import HoughCircles

    cv2 = cv()
    if image.shape != edges.shape:
        raise ValueError(
            f"edges and image must have the same size, got {edges.shape} and {image.shape}"
        )
    distance = min_radius if min_distance is None else min_distance
    found = cv2.HoughCirclesWithAccumulator(
        to_u8(image),
        cv2.HOUGH_GRADIENT,
        1,
        distance,
        param1=100,
        param2=max(1.0, threshold * np.pi * min_radius),
        minRadius=int(np.floor(min_radius)),
        maxRadius=int(np.ceil(max_radius)),
    )
    circles = circles_from_cv(found)
    circles[:, 3] = _coverage(edges, circles)
    circles = circles[(circles[:, 3] >= threshold) & _polarity(image, circles, polarity)]
    circles = circles[np.argsort(-circles[:, 3], kind="stable")][:max_circles]
    return HoughCircles(circles, len(circles), np.zeros(edges.shape, np.float32))
