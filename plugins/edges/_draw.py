"""Drawing of edge maps over their image."""

from __future__ import annotations

import numpy as np

from graphvision import BinaryImage, ColorImage, Image, node

from ..shared.draw import colour_canvas

__all__ = ["draw_edges"]


@node("edges.draw", version=1)
def draw_edges(image: Image, edges: BinaryImage) -> ColorImage:
    """The edge pixels in green over a dimmed copy of the image.

    Parameters
    ----------
    image : Image
        The image the edges were found in (gray is drawn in colour).
    edges : BinaryImage
        The edge map, of the image's size.

    Returns
    -------
    drawing : (H, W, 3) float32 ndarray
    """
    if image.shape[:2] != edges.shape:
        raise ValueError(
            f"image and edges must have the same size, got {image.shape[:2]} and {edges.shape}"
        )
    canvas = 0.6 * colour_canvas(image)
    canvas[edges] = (0.1, 0.95, 0.1)
    return canvas.astype(np.float32)
