"""Drawing boxes: true boxes in green, proposals or detections in red."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import Boxes, ColorImage, Image, node

from ..shared.draw import colour_canvas
from ..shared.params import Count, Fraction
from ..synthetic._digit_scenes import Scenes
from ._types import Detections

__all__ = ["draw_boxes", "draw_rectangles", "draw_scenes"]

TRUE_COLOUR = (0.1, 0.9, 0.1)
FOUND_COLOUR = (0.95, 0.15, 0.1)


def draw_rectangles(
    canvas: np.ndarray, xyxy: np.ndarray, colour: tuple[float, float, float], thick: int
) -> None:
    """Draw the outline of each box (x0, y0, x1, y1), clipped to the canvas, in place."""
    height, width = canvas.shape[:2]
    for x0, y0, x1, y1 in np.round(xyxy).astype(int):
        x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, width), min(y1, height)
        if x0 >= x1 or y0 >= y1:
            continue
        canvas[y0 : min(y0 + thick, y1), x0:x1] = colour
        canvas[max(y1 - thick, y0) : y1, x0:x1] = colour
        canvas[y0:y1, x0 : min(x0 + thick, x1)] = colour
        canvas[y0:y1, max(x1 - thick, x0) : x1] = colour


@node("detection.draw_boxes", version=1)
def draw_boxes(
    image: Image,
    boxes: Boxes,
    truth: Boxes | None = None,
    *,
    count: Annotated[int, Field(ge=0)] = 0,
    thickness: Annotated[int, Field(ge=1, le=50)] = 1,
) -> ColorImage:
    """The image with the true boxes (if given) in green and the first ``count`` boxes
    (proposals or detections, best first) in red over them.

    Parameters
    ----------
    image : Image
        Gray or colour picture.
    boxes : Boxes
        Proposals or detections, best first.
    truth : Boxes, optional
        True boxes.
    count : int
        Draw only the first ``count`` boxes (0: all).
    thickness : int
        Line width in pixels.

    Returns
    -------
    ColorImage
        The drawing, (H, W, 3) float32.
    """
    canvas = colour_canvas(image)
    if truth is not None:
        draw_rectangles(canvas, truth.xyxy, TRUE_COLOUR, thickness)
    shown = boxes.xyxy[:count] if count else boxes.xyxy
    draw_rectangles(canvas, shown, FOUND_COLOUR, thickness)
    return canvas


@node("detection.draw_scenes", version=1)
def draw_scenes(
    scenes: Scenes,
    detections: Detections,
    *,
    count: Count = 8,
    columns: Count = 4,
    min_score: Fraction = 0.5,
) -> ColorImage:
    """The first ``count`` scenes in a grid, true boxes in green and detections scoring at
    least ``min_score`` in red.

    Parameters
    ----------
    scenes : Scenes
        Scenes with their true boxes.
    detections : Detections
        Detections (or proposals) over those scenes.
    count : int
        Scenes shown.
    columns : int
        Scenes per row.
    min_score : float
        Lowest score drawn.

    Returns
    -------
    ColorImage
        The grid, scenes two pixels apart.
    """
    shown = min(count, len(scenes))
    height, width = scenes.images.shape[1:]
    rows = -(-shown // columns)
    canvas = np.ones((rows * (height + 2), min(shown, columns) * (width + 2), 3), np.float32)
    for scene in range(shown):
        picture = colour_canvas(scenes.images[scene])
        truth, _ = scenes.boxes_of(scene)
        draw_rectangles(picture, truth, TRUE_COLOUR, 1)
        mine = (detections.owner == scene) & (detections.score >= min_score)
        draw_rectangles(picture, detections.xyxy[mine], FOUND_COLOUR, 1)
        r, c = divmod(scene, columns)
        canvas[
            r * (height + 2) : r * (height + 2) + height, c * (width + 2) : c * (width + 2) + width
        ] = picture
    return canvas
