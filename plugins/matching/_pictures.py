"""Pictures of found and true instances in the scenes, with the vote tables: the node
``matching.draw_object_scenes``."""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, ColorImage, node

from ..shared.draw import colour_canvas, draw_segment
from ..synthetic import ObjectScenes
from ._instances import Instances

__all__ = [
    "draw_object_scenes",
]


TRUE_COLOUR = (0.1, 0.9, 0.1)


FOUND_COLOUR = (0.95, 0.15, 0.1)


def _outline(
    canvas: np.ndarray, quad: np.ndarray, colour: tuple[float, float, float], width: int
) -> None:
    """The quadrilateral ``width`` px wide and a dot on its first corner (the model's top
    left, so that a turned pose shows)."""
    from ..shared.draw import draw_circle

    for dx in range(-(width // 2), width - width // 2):
        for dy in range(-(width // 2), width - width // 2):
            moved = quad + np.array([dx, dy], float)
            for k in range(4):
                draw_segment(canvas, moved[k], moved[(k + 1) % 4], colour)
    for radius in range(1, width + 3):
        draw_circle(canvas, float(quad[0, 0]), float(quad[0, 1]), radius, colour)


def _hot(values: np.ndarray) -> np.ndarray:
    """Black-red-yellow-white colour ramp of values in [0, 1], (..., 3) float32."""
    v = np.clip(values, 0.0, 1.0)[..., None] * 3.0
    return np.clip(np.concatenate([v, v - 1.0, v - 2.0], axis=-1), 0.0, 1.0).astype(np.float32)


def _grid(tiles: list[np.ndarray], columns: int) -> np.ndarray:
    """Tiles of one size in rows of ``columns``, 4 white pixels apart."""
    height, width = tiles[0].shape[:2]
    rows = -(-len(tiles) // columns)
    gap = 4
    canvas = np.ones((rows * (height + gap) - gap, columns * (width + gap) - gap, 3), np.float32)
    for index, tile in enumerate(tiles):
        r, c = divmod(index, columns)
        canvas[
            r * (height + gap) : r * (height + gap) + height,
            c * (width + gap) : c * (width + gap) + width,
        ] = tile
    return canvas


class ScenePictures(NamedTuple):
    outlines: ColorImage
    vote_space: ColorImage


@node("matching.draw_object_scenes", version=1)
def draw_object_scenes(
    scenes: ObjectScenes,
    instances: Instances,
    votes: Array | None = None,
    *,
    count: Annotated[int, Field(ge=1, le=64)] = 6,
    columns: Annotated[int, Field(ge=1, le=16)] = 3,
) -> ScenePictures:
    """The first ``count`` scenes in a grid of ``columns``: true instances outlined in
    broad green and found ones in thin red over them (a dot marks the model's top-left
    corner, so a turned pose shows), and beside them the Hough vote space of each scene.

    Parameters
    ----------
    scenes : ObjectScenes
        The scenes and their true instances.
    instances : Instances
        The instances found in them.
    votes : Array, optional
        (N, h, w) vote pictures (``matching.find_instances_in_scenes``): each scene
        dimmed, its vote picture over it in a black-red-yellow-white ramp (white: the
        most votes of any bin in the shown scenes).
    count : int
        Scenes shown.
    columns : int
        Scenes per row.

    Returns
    -------
    outlines : ColorImage
        The scenes with the outlines.
    vote_space : ColorImage
        The vote pictures over the scenes (the scenes alone when ``votes`` is not given).
    """
    if instances.scenes != len(scenes):
        raise ValueError(
            f"the instances were found in {instances.scenes} scenes but {len(scenes)} scenes "
            "are given"
        )
    shown = range(min(count, len(scenes)))
    outlines, spaces = [], []
    if votes is not None and (votes.ndim != 3 or len(votes) != len(scenes)):
        raise ValueError(
            f"votes must be (N, h, w) with one picture per scene ({len(scenes)}), got "
            f"shape {votes.shape}"
        )
    peak = max(float(votes[: len(shown)].max()), 1.0) if votes is not None and len(votes) else 1.0
    for index in shown:
        canvas = colour_canvas(scenes.images[index])
        for quad in scenes.quads_of(index):
            _outline(canvas, quad, TRUE_COLOUR, 6)
        for quad in instances.quads[instances.owner == index]:
            _outline(canvas, quad, FOUND_COLOUR, 2)
        outlines.append(canvas)
        space = colour_canvas(scenes.images[index]) * 0.35
        if votes is not None:
            picture = votes[index]
            cell = -(-scenes.images.shape[1] // picture.shape[0])
            grown = np.kron(picture, np.ones((cell, cell), np.float32))
            grown = grown[: space.shape[0], : space.shape[1]]
            heat = _hot(grown / peak)
            mask = grown > 0
            space[: grown.shape[0], : grown.shape[1]][mask] = (
                0.25 * space[: grown.shape[0], : grown.shape[1]][mask] + heat[mask]
            )
        spaces.append(np.clip(space, 0.0, 1.0))
    return ScenePictures(_grid(outlines, columns), _grid(spaces, columns))
