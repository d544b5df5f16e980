"""Drawings: keypoints on an image, matches between two images."""

from __future__ import annotations

import numpy as np

from graphvision import ColorImage, Image, Keypoints, Matches, node

from ..shared.draw import colour_canvas, draw_circle, draw_segment, draw_segments

__all__ = ["draw_keypoints", "draw_matches"]

GREEN = (0.1, 0.9, 0.1)
RED = (0.95, 0.15, 0.1)
YELLOW = (1.0, 0.85, 0.0)


@node("features.draw_keypoints", version=1)
def draw_keypoints(image: Image, keypoints: Keypoints) -> ColorImage:
    """Each keypoint as a circle of radius 3σ with a line showing its orientation.

    Parameters
    ----------
    image : Image
        The image to draw on (gray is drawn in colour).
    keypoints : Keypoints
        The keypoints to draw.

    Returns
    -------
    image : (H, W, 3) float32
    """
    canvas = colour_canvas(image)
    for (x, y), scale, angle in zip(
        keypoints.xy, keypoints.scale, keypoints.orientation, strict=True
    ):
        radius = max(2, int(round(3 * scale)))
        draw_circle(canvas, x, y, radius, YELLOW)
        tip = np.array([x + radius * np.cos(angle), y + radius * np.sin(angle)])
        draw_segment(canvas, np.array([x, y]), tip, YELLOW)
    return canvas


@node("features.draw_matches", version=1)
def draw_matches(
    a: Image,
    b: Image,
    keypoints_a: Keypoints,
    keypoints_b: Keypoints,
    matches: Matches,
    inliers: Matches | None = None,
) -> ColorImage:
    """The two images side by side with a line per match: green for inliers, red for the rest.

    Without ``inliers`` every match is drawn green.

    Parameters
    ----------
    a, b : Image
        The two images, drawn side by side.
    keypoints_a, keypoints_b : Keypoints
        Keypoints of ``a`` and of ``b``.
    matches : Matches
        Pairs (index in ``keypoints_a``, index in ``keypoints_b``).
    inliers : Matches, optional
        The matches to draw in green (the others in red); all green when absent.

    Returns
    -------
    image : (max(Ha, Hb), Wa + Wb, 3) float32
    """
    rows = max(a.shape[0], b.shape[0])
    canvas = np.zeros((rows, a.shape[1] + b.shape[1], 3), np.float32)
    canvas[: a.shape[0], : a.shape[1]] = colour_canvas(a)
    canvas[: b.shape[0], a.shape[1] :] = colour_canvas(b)
    good = set(map(tuple, inliers.pairs.tolist())) if inliers is not None else None
    pairs = matches.pairs
    green = [good is None or (int(i), int(j)) in good for i, j in pairs.tolist()]
    colours = np.where(np.array(green, bool).reshape(-1, 1), GREEN, RED)
    shift = np.array([a.shape[1], 0.0])
    draw_segments(canvas, keypoints_a.xy[pairs[:, 0]], keypoints_b.xy[pairs[:, 1]] + shift, colours)
    return canvas
