"""OpenCV implementations of the Hough transforms: lines and circles."""

from __future__ import annotations

import numpy as np

from graphvision import implements

from .convert import EXTRA, REQUIRES, cv, lines_from_cv, to_u8

__all__ = ["cv_hough_lines"]


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
