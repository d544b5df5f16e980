"""Pose votes of matches (Lowe 2004, section 7.3): each match predicts the model's pose and
votes in the 2 closest bins of each of the 4 dimensions of a hash table, one per view."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from graphvision import KeypointSet

from ._model_views import ConstellationParams, ModelViews

__all__ = [
    "PoseVotes",
    "pose_votes",
    "vote_picture",
]


class PoseVotes(NamedTuple):
    """The Hough table: ``keys`` (B, 5) int64 bins (view, log-scale, orientation, x, y)
    with ``counts`` (B,), the matches in each bin (``members[starts[b]:starts[b + 1]]``,
    match indices), and the location bin width of each bin in scene pixels (``widths``)."""

    keys: np.ndarray
    counts: np.ndarray
    members: np.ndarray
    starts: np.ndarray
    widths: np.ndarray


def _two_closest(value: np.ndarray) -> np.ndarray:
    """The bin holding each ``value`` (in units of bins) and the next closest, (M, 2)."""
    low = np.floor(value)
    other = np.where(value - low >= 0.5, low + 1, low - 1)
    return np.column_stack([low, other]).astype(np.int64)


def pose_votes(
    views: ModelViews, scene_keypoints: KeypointSet, pairs: np.ndarray, params: ConstellationParams
) -> PoseVotes:
    r"""Lowe's generalised Hough transform of the pose (section 7.3).

    Match :math:`k` pairs scene keypoint :math:`i` (position :math:`x_i`, scale
    :math:`\sigma_i`, orientation :math:`\theta_i`) with model keypoint :math:`j` of view
    :math:`v` (:math:`u_j, \sigma_j, \theta_j` in the view); it predicts the scale,
    rotation and position of the model's centre :math:`c_v` seen in that view:

    .. math:: s_k = \sigma_i / \sigma_j, \quad \phi_k = \theta_i - \theta_j, \quad
              r_k = x_i + s_k R(\phi_k)\,(c_v - u_j).

    The bins are ``orientation_bin`` degrees wide, a factor ``scale_bin`` in scale, and
    ``location_bin`` × the model's larger side × the scale bin's (geometric) centre in
    position; each match votes in the 2 closest bins of each dimension (16 in all), so a
    prediction near a bin's edge still meets the others. Views have separate tables.
    ``pairs`` are (scene, model feature) index pairs.
    """
    if len(pairs) == 0:
        empty = np.zeros(0, np.int64)
        return PoseVotes(
            np.zeros((0, 5), np.int64), empty, empty, np.zeros(1, np.int64), np.zeros(0)
        )
    scene, model = pairs[:, 0], pairs[:, 1]
    ratio = scene_keypoints.scale[scene] / views.keypoints.scale[model]
    turn = np.mod(
        scene_keypoints.orientation[scene] - views.keypoints.orientation[model], 2 * math.pi
    )
    offset = views.centres[views.view[model]] - views.keypoints.xy[model]
    cos, sin = np.cos(turn), np.sin(turn)
    reference = scene_keypoints.xy[scene] + ratio[:, None] * np.column_stack(
        [cos * offset[:, 0] - sin * offset[:, 1], sin * offset[:, 0] + cos * offset[:, 1]]
    )
    scale_bins = _two_closest(np.log(ratio) / math.log(params.scale_bin))  # (M, 2)
    orientation_count = max(int(round(360.0 / params.orientation_bin)), 1)
    orientation_bins = _two_closest(turn / (2 * math.pi) * orientation_count) % orientation_count
    side = max(views.size)
    width = params.location_bin * side * params.scale_bin ** (scale_bins + 0.5)  # (M, 2)
    x_bins = np.stack([_two_closest(reference[:, 0] / width[:, a]) for a in range(2)], axis=1)
    y_bins = np.stack([_two_closest(reference[:, 1] / width[:, a]) for a in range(2)], axis=1)
    index = np.indices((2, 2, 2, 2)).reshape(4, -1)  # (scale, orientation, x, y) choices
    keys = np.stack(
        [
            np.broadcast_to(views.view[model][:, None], (len(pairs), 16)),
            scale_bins[:, index[0]],
            orientation_bins[:, index[1]],
            x_bins[:, index[0], index[2]],
            y_bins[:, index[0], index[3]],
        ],
        axis=2,
    ).reshape(-1, 5)
    voter = np.repeat(np.arange(len(pairs)), 16)
    bins, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    order = np.argsort(inverse.ravel(), kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    widths = params.location_bin * side * params.scale_bin ** (bins[:, 1] + 0.5)
    return PoseVotes(bins, counts.astype(np.int64), voter[order], starts, widths)


def vote_picture(votes: PoseVotes, shape: tuple[int, int], cell: int) -> np.ndarray:
    """The Hough table seen from above: each ``cell`` × ``cell`` block of the scene holds
    the most votes of a bin whose location cell covers it (the maximum over view, scale
    and orientation), float32 (ceil(H / cell), ceil(W / cell))."""
    rows, cols = -(-shape[0] // cell), -(-shape[1] // cell)
    picture = np.zeros((rows, cols), np.float32)
    for b in np.flatnonzero(votes.counts >= 2):
        step = votes.widths[b] / cell
        x0, y0 = votes.keys[b, 3] * step, votes.keys[b, 4] * step
        c0, r0 = max(int(math.floor(x0)), 0), max(int(math.floor(y0)), 0)
        c1, r1 = min(int(math.ceil(x0 + step)), cols), min(int(math.ceil(y0 + step)), rows)
        if c0 < c1 and r0 < r1:
            window = picture[r0:r1, c0:c1]
            np.maximum(window, votes.counts[b], out=window)
    return picture
