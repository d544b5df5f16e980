"""Pictures of a segmentation: scenes above their true and predicted label maps in class
colours with a legend, and the training curve of a network.

Text (class names, axis numbers) is drawn with Pillow's built-in font
(``ImageFont.load_default``), which ships inside Pillow: nothing is read from the system
or downloaded.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import ColorImage, node

from ..shared.draw import colour_canvas, draw_segment
from ..synthetic._shape_scenes import LabelledScenes
from ._model import Segmenter

__all__ = ["PALETTE", "class_colours", "draw_curve", "draw_labels"]

PALETTE = np.array(
    [
        [0.12, 0.12, 0.12],  # background: near black
        [0.90, 0.10, 0.29],
        [0.24, 0.71, 0.29],
        [0.26, 0.39, 0.85],
        [1.00, 0.88, 0.10],
        [0.96, 0.51, 0.19],
        [0.57, 0.12, 0.71],
        [0.27, 0.94, 0.94],
        [0.94, 0.20, 0.90],
        [0.82, 0.96, 0.24],
    ],
    np.float32,
)
"""Class colours (Sasha Trubetskoy's distinct colours), the background's first; more
classes than colours take hues spread by the golden ratio."""
MARGIN = 4
"""White pixels between two panels of a picture."""


def class_colours(count: int) -> np.ndarray:
    """``count`` RGB colours (float32, count × 3), the background's first."""
    if count <= len(PALETTE):
        return PALETTE[:count]
    hue = (np.arange(count - len(PALETTE)) * 0.618033988749895) % 1.0
    extra = np.stack([hue, 1 - hue, 0.5 + 0.5 * np.sin(6.28 * hue)], axis=1) * 0.8 + 0.1
    return np.vstack([PALETTE, extra.astype(np.float32)])


def _text(canvas: np.ndarray, xy: tuple[int, int], text: str, colour=(0, 0, 0)) -> None:
    """Write ``text`` on the float RGB ``canvas`` at ``xy`` (x, y of its top-left), in
    Pillow's built-in font (anti-aliased: blended by its coverage), clipped to the canvas;
    the pixels it does not touch keep their exact values."""
    from PIL import Image, ImageDraw, ImageFont

    mask = Image.new("L", (canvas.shape[1], canvas.shape[0]), 0)
    ImageDraw.Draw(mask).text(xy, text, fill=255, font=ImageFont.load_default(size=11))
    ink = np.asarray(mask, np.float32)[..., None] / 255
    canvas[:] = canvas * (1 - ink) + np.asarray(colour, np.float32) * ink


def _legend(names: list[str], colours: np.ndarray, width: int) -> np.ndarray:
    """A white strip with one colour swatch (outlined in gray) and name per class,
    wrapped to ``width``."""
    cell = 12 + 7 * max(len(name) for name in names) + 12
    per_row = max(width // cell, 1)
    rows = -(-len(names) // per_row)
    strip = np.ones((rows * 16 + 4, width, 3), np.float32)
    for index, name in enumerate(names):
        top, left = 4 + (index // per_row) * 16, 4 + (index % per_row) * cell
        strip[top : top + 10, left : left + 10] = 0.5
        strip[top + 1 : top + 9, left + 1 : left + 9] = colours[index]
        _text(strip, (left + 14, top - 1), name)
    return strip


@node("segmentation.draw_labels", version=1)
def draw_labels(
    scenes: LabelledScenes,
    predicted: LabelledScenes,
    *,
    count: Annotated[int, Field(ge=1, le=64)] = 6,
) -> ColorImage:
    """The first ``count`` scenes in a row, their true label maps below them and the
    predicted ones below those (each class in its colour, the background near black),
    the pixels labelled wrong outlined in white in the bottom row, and a legend naming
    each colour's class.

    Parameters
    ----------
    scenes : LabelledScenes
        The scenes with their true labels.
    predicted : LabelledScenes
        The same scenes labelled (e.g. by ``segmentation.predict``).
    count : int
        Scenes shown.

    Returns
    -------
    image : (H, W, 3) float32 ndarray
        Rows: scenes, truth, prediction, legend (and a line naming the rows).

    References
    ----------
    J. Long, E. Shelhamer, T. Darrell, "Fully convolutional networks for semantic
    segmentation", CVPR 2015 (figure 6: image, ground truth, prediction).
    """
    if scenes.images.shape != predicted.images.shape:
        raise ValueError(
            f"scenes {scenes.images.shape} and predicted {predicted.images.shape} must be "
            "the same scenes"
        )
    names = scenes.class_names
    colours = class_colours(max(len(names), len(predicted.class_names)))
    shown = min(count, len(scenes))
    height, width = scenes.images.shape[1:]
    canvas = np.ones((3 * (height + MARGIN), shown * (width + MARGIN) + MARGIN, 3), np.float32)
    for k in range(shown):
        left = MARGIN + k * (width + MARGIN)
        wrong = predicted.labels[k] != scenes.labels[k]
        panels = [
            colour_canvas(scenes.images[k]),
            colours[scenes.labels[k]],
            np.where(_outline(wrong)[..., None], 1.0, colours[predicted.labels[k]]),
        ]
        for row, panel in enumerate(panels):
            top = MARGIN + row * (height + MARGIN)
            canvas[top : top + height, left : left + width] = panel
    keys = np.vstack([colours[: len(names)], np.ones((1, 3), np.float32)])
    legend = _legend([*names, "wrong (outline)"], keys, canvas.shape[1])
    note = np.ones((16, canvas.shape[1], 3), np.float32)
    _text(note, (4, 2), "rows: scene, true labels, predicted labels")
    legend = np.concatenate([legend, note], axis=0)
    return np.concatenate([canvas, legend], axis=0)


def _outline(mask: np.ndarray) -> np.ndarray:
    """The pixels of ``mask`` with a 4-neighbour outside it."""
    padded = np.pad(mask, 1)
    inner = padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:]
    return mask & ~inner


@node("segmentation.draw_curve", version=1)
def draw_curve(
    network: Segmenter,
    *,
    width: Annotated[int, Field(ge=120, le=2048)] = 360,
    height: Annotated[int, Field(ge=80, le=2048)] = 200,
) -> ColorImage:
    """The training curve: the mean loss (red, left scale) and the training pixel
    accuracy (blue, right scale from 0 to 1) of each epoch, on axes labelled with their
    ranges.

    Parameters
    ----------
    network : Segmenter
        A trained network (its ``history`` and ``accuracy``).
    width, height : int
        Size of the picture in pixels.

    Returns
    -------
    image : (height, width, 3) float32 ndarray

    References
    ----------
    Y. LeCun et al., "Efficient BackProp", 1998 (the loss per epoch as the measure of
    convergence).
    """
    canvas = np.ones((height, width, 3), np.float32)
    left, right, top, bottom = 40, width - 36, 16, height - 22
    black = (0.0, 0.0, 0.0)
    draw_segment(canvas, np.array([left, bottom]), np.array([right, bottom]), black)
    draw_segment(canvas, np.array([left, top]), np.array([left, bottom]), black)
    draw_segment(canvas, np.array([right, top]), np.array([right, bottom]), black)
    loss, accuracy = network.history, network.accuracy
    epochs = len(loss)
    high = float(loss.max()) if epochs else 1.0
    x = left + (right - left) * (np.arange(epochs) / max(epochs - 1, 1))
    for values, scale, colour in (
        (loss, high, (0.85, 0.1, 0.1)),
        (accuracy, 1.0, (0.1, 0.3, 0.85)),
    ):
        y = bottom - (bottom - top) * values / max(scale, 1e-12)
        for k in range(epochs - 1):
            draw_segment(canvas, np.array([x[k], y[k]]), np.array([x[k + 1], y[k + 1]]), colour)
    _text(canvas, (2, top - 6), f"{high:.2f}", (0.85, 0.1, 0.1))
    _text(canvas, (2, bottom - 10), "0", (0.85, 0.1, 0.1))
    _text(canvas, (right + 4, top - 6), "1.0", (0.1, 0.3, 0.85))
    _text(canvas, (right + 4, bottom - 10), "0", (0.1, 0.3, 0.85))
    _text(canvas, (left, bottom + 4), "1", black)
    _text(canvas, (right - 14, bottom + 4), f"{epochs}", black)
    _text(canvas, ((left + right) // 2 - 16, bottom + 4), "epoch", black)
    _text(canvas, (left + 6, 1), "loss", (0.85, 0.1, 0.1))
    _text(canvas, (left + 40, 1), "pixel accuracy", (0.1, 0.3, 0.85))
    return canvas
