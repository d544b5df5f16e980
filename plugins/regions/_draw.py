"""Drawings of label images: colour-coded regions, outlines and centroids."""

from __future__ import annotations

import numpy as np

from graphvision import ColorImage, Image, LabelImage, Table, node

from ..shared.draw import colour_canvas

__all__ = ["colorize", "overlay"]


def _palette(count: int) -> np.ndarray:
    """``count + 1`` colours, black first; hues spread by the golden ratio (no randomness)."""
    hue = (np.arange(count) * 0.618033988749895) % 1.0
    sector = hue * 6.0
    x = 1.0 - np.abs(sector % 2.0 - 1.0)
    index = sector.astype(int) % 6
    ones, zeros = np.ones(count), np.zeros(count)
    choices = [
        (ones, x, zeros),
        (x, ones, zeros),
        (zeros, ones, x),
        (zeros, x, ones),
        (x, zeros, ones),
        (ones, zeros, x),
    ]
    rgb = np.zeros((count, 3))
    for k, (r, g, b) in enumerate(choices):
        chosen = index == k
        rgb[chosen] = np.stack([r, g, b], axis=1)[chosen]
    return np.vstack([[0.0, 0.0, 0.0], 0.25 + 0.75 * rgb]).astype(np.float32)


@node("regions.colorize", version=1)
def colorize(labels: LabelImage) -> ColorImage:
    """Each region in its own colour (background black); colours follow the label, no seed needed.

    Parameters
    ----------
    labels : LabelImage
        Regions 1..N, 0 the background.

    Returns
    -------
    image : (H, W, 3) float32 ndarray
    """
    return _palette(int(labels.max()))[labels]


@node("regions.overlay", version=1)
def overlay(image: Image, labels: LabelImage, table: Table | None = None) -> ColorImage:
    """Region outlines in their colours and centroids as red crosses, drawn on the image.

    Outline pixels are region pixels with a 4-neighbour in another region or
    the background. Centroids come from ``table`` (``centroid_x``,
    ``centroid_y``) when it is connected.

    Parameters
    ----------
    image : Image
        The image to draw on.
    labels : LabelImage
        Regions whose outlines are drawn.
    table : Table, optional
        Their descriptors; when given, centroids are marked.

    Returns
    -------
    image : (H, W, 3) float32 ndarray
    """
    if image.shape[:2] != labels.shape:
        raise ValueError(
            f"image and labels must have the same size, got {image.shape[:2]} and {labels.shape}"
        )
    canvas = colour_canvas(image)
    padded = np.pad(labels, 1, mode="edge")
    edge = np.zeros(labels.shape, dtype=bool)
    for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        edge |= (
            padded[1 + dy : padded.shape[0] - 1 + dy, 1 + dx : padded.shape[1] - 1 + dx] != labels
        )
    edge &= labels > 0
    canvas[edge] = _palette(int(labels.max()))[labels[edge]]
    if table is not None and "centroid_x" in table:
        for x, y in zip(
            np.round(table["centroid_x"]).astype(int),
            np.round(table["centroid_y"]).astype(int),
            strict=True,
        ):
            canvas[max(y - 3, 0) : y + 4, x] = (1.0, 0.0, 0.0)
            canvas[y, max(x - 3, 0) : x + 4] = (1.0, 0.0, 0.0)
    return canvas.astype(np.float32)
