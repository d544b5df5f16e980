"""Drawings of the lines and circles the Hough transforms find."""

from __future__ import annotations

import math

import numpy as np

from graphvision import ColorImage, Image, node

from ..shared.draw import colour_canvas, plot_points
from ._ports import Circles, Lines

__all__ = ["draw_circles", "draw_lines"]

RED = (0.95, 0.15, 0.1)
GREEN = (0.1, 0.95, 0.1)


@node("hough.draw_lines", version=1)
def draw_lines(image: Image, lines: Lines) -> ColorImage:
    r"""Each line in red across the whole image.

    A line is :math:`x\cos\theta + y\sin\theta = \rho`.

    Parameters
    ----------
    image : Image
        The image to draw on (gray is drawn in colour).
    lines : Lines
        ``(ρ, θ, votes)`` rows.

    Returns
    -------
    drawing : (H, W, 3) float32 ndarray
    """
    canvas = colour_canvas(image)
    reach = math.hypot(*image.shape[:2])
    t = np.arange(-reach, reach, 0.5)
    for rho, theta, _ in lines:
        normal = np.array([math.cos(theta), math.sin(theta)])
        plot_points(canvas, rho * normal[0] - t * normal[1], rho * normal[1] + t * normal[0], RED)
    return canvas.astype(np.float32)


@node("hough.draw_circles", version=1)
def draw_circles(image: Image, circles: Circles) -> ColorImage:
    """Each circle in green with its centre as a red cross.

    Parameters
    ----------
    image : Image
        The image to draw on (gray is drawn in colour).
    circles : Circles
        ``(x, y, r, score)`` rows.

    Returns
    -------
    drawing : (H, W, 3) float32 ndarray
    """
    canvas = colour_canvas(image)
    for x, y, r, _ in circles:
        angle = np.linspace(0.0, 2.0 * math.pi, max(16, int(8 * r)), endpoint=False)
        plot_points(canvas, x + r * np.cos(angle), y + r * np.sin(angle), GREEN)
        arm = np.arange(-3, 4)
        plot_points(canvas, x + arm, np.full(arm.size, y), RED)
        plot_points(canvas, np.full(arm.size, x), y + arm, RED)
    return canvas.astype(np.float32)
