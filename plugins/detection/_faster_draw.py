"""Pictures and curves of Faster R-CNN: the region proposal network's first proposals per
scene, and the joint training loss per epoch."""

from __future__ import annotations

import numpy as np

from graphvision import ColorImage, Table, node

from ..shared.params import Count
from ..synthetic._digit_scenes import Scenes
from ._draw import draw_scenes
from ._faster_types import FasterRcnn
from ._types import Detections, DetectionSet

__all__ = ["draw_proposals", "faster_rcnn_loss"]


def first_per_scene(proposals: DetectionSet, count: int) -> np.ndarray:
    """Indices of each scene's first ``count`` proposals (in their order)."""
    rank = np.zeros(len(proposals), np.int64)
    for scene in np.unique(proposals.owner):
        mine = np.flatnonzero(proposals.owner == scene)
        rank[mine] = np.arange(len(mine))
    return np.flatnonzero(rank < count)


@node("detection.draw_proposals", version=1)
def draw_proposals(
    scenes: Scenes,
    proposals: Detections,
    *,
    count: Count = 8,
    columns: Count = 4,
    per_scene: Count = 10,
) -> ColorImage:
    """The first ``count`` scenes in a grid, true boxes in green and each scene's first
    ``per_scene`` proposals (e.g. the region proposal network's best by objectness) in red.

    Parameters
    ----------
    scenes : Scenes
        Scenes with their true boxes.
    proposals : Detections
        Proposals over those scenes, each scene's best first.
    count : int
        Scenes shown.
    columns : int
        Scenes per row.
    per_scene : int
        Proposals drawn per scene.

    Returns
    -------
    ColorImage
        The grid, scenes two pixels apart.
    """
    if proposals.scenes != len(scenes):
        raise ValueError(
            f"the proposals cover {proposals.scenes} scenes but {len(scenes)} scenes are given"
        )
    shown = proposals.take(first_per_scene(proposals, per_scene))
    marked = DetectionSet(shown.xyxy, np.ones(len(shown)), shown.label, shown.owner, shown.scenes)
    return draw_scenes(scenes, marked, count=count, columns=columns, min_score=0.0)


@node("detection.faster_rcnn_loss", version=1)
def faster_rcnn_loss(model: FasterRcnn) -> Table:
    """The mean joint loss (RPN objectness and box codings, head classes and box codings)
    of each training epoch of a Faster R-CNN.

    Parameters
    ----------
    model : FasterRcnn
        A trained Faster R-CNN.

    Returns
    -------
    Table
        Columns ``epoch`` (from 1) and ``loss``.
    """
    return {"epoch": np.arange(1, len(model.history) + 1), "loss": model.history}
