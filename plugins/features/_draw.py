"""Drawings: keypoints on an image, matches between two images."""

from __future__ import annotations

import numpy as np

from graphvision import ColorImage, Image, Keypoints, Matches, node

__all__ = ["draw_keypoints", "draw_matches"]

GREEN = (0.1, 0.9, 0.1)
RED = (0.95, 0.15, 0.1)
YELLOW = (1.0, 0.85, 0.0)


def _rgb(image: np.ndarray) -> np.ndarray:
    return np.repeat(image[..., None], 3, axis=2).copy() if image.ndim == 2 else image.copy()


def _line(canvas: np.ndarray, p: np.ndarray, q: np.ndarray, colour: tuple) -> None:
    from skimage.draw import line

    rr, cc = line(int(round(p[1])), int(round(p[0])), int(round(q[1])), int(round(q[0])))
    inside = (rr >= 0) & (rr < canvas.shape[0]) & (cc >= 0) & (cc < canvas.shape[1])
    canvas[rr[inside], cc[inside]] = colour


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
    from skimage.draw import circle_perimeter

    canvas = _rgb(image)
    for (x, y), scale, angle in zip(
        keypoints.xy, keypoints.scale, keypoints.orientation, strict=True
    ):
        radius = max(2, int(round(3 * scale)))
        rr, cc = circle_perimeter(int(round(y)), int(round(x)), radius, shape=canvas.shape[:2])
        canvas[rr, cc] = YELLOW
        tip = np.array([x + radius * np.cos(angle), y + radius * np.sin(angle)])
        _line(canvas, np.array([x, y]), tip, YELLOW)
    return canvas.astype(np.float32)


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
    canvas[: a.shape[0], : a.shape[1]] = _rgb(a)
    canvas[: b.shape[0], a.shape[1] :] = _rgb(b)
    good = set(map(tuple, inliers.pairs.tolist())) if inliers is not None else None
    shift = np.array([a.shape[1], 0.0])
    for i, j in matches.pairs:
        colour = GREEN if good is None or (int(i), int(j)) in good else RED
        _line(canvas, keypoints_a.xy[i], keypoints_b.xy[j] + shift, colour)
    return canvas
