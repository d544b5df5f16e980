"""The model's side of detection by feature constellations: its settings, its features
from the model and from simulated tilted views of it (Morel & Yu), and the match of scene
features to them by Lowe's ratio test against another place of the model."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from graphvision import KeypointSet

from ..features import sift

__all__ = [
    "ConstellationParams",
    "ModelViews",
    "match_to_model",
    "model_views",
    "simulate_view",
    "view_directions",
]


@dataclass(frozen=True)
class ConstellationParams:
    """The parameters of :func:`locate_instances` (defaults after Lowe 2004, section 7)."""

    ratio: float = 0.8
    same_place: float = 3.0
    orientation_bin: float = 30.0
    scale_bin: float = 2.0
    location_bin: float = 0.25
    min_votes: int = 3
    threshold: float = 3.0
    orientation_tolerance: float = 30.0
    scale_tolerance: float = 2.0
    min_inliers: int = 8
    min_probability: float = 0.98
    prior: float = 0.01
    nms_iou: float = 0.2
    max_clusters: int = 300
    seed: int = 0


@dataclass(frozen=True, eq=False)
class ModelViews:
    """The model's features, from the model itself and from simulated views of it.

    ``keypoints`` and ``descriptors`` are as SIFT found them in their own view (position,
    scale and orientation in that view's pixels); ``xy`` is each keypoint's position in
    model pixels, ``frame`` (N, 2, 2) the linear part of the map from its view to the
    model, ``view`` (N,) its view, ``centres`` (V, 2) the model's centre in each view, and
    ``size`` the model's (width, height)."""

    keypoints: KeypointSet
    descriptors: np.ndarray
    xy: np.ndarray
    frame: np.ndarray
    view: np.ndarray
    centres: np.ndarray
    size: tuple[int, int]

    def __len__(self) -> int:
        return len(self.xy)


def _view_affine(tilt: float, direction: float) -> np.ndarray:
    """The linear map of a view: turn by ``direction`` (radians), then shrink x by ``tilt``."""
    c, s = math.cos(direction), math.sin(direction)
    return np.diag([1.0 / tilt, 1.0]) @ np.array([[c, -s], [s, c]])


def view_directions(tilt: float, step: float = 72.0) -> list[float]:
    """ASIFT's sampling of the tilt's direction: every ``step / tilt`` degrees in [0, 180)
    (Morel & Yu 2009), in radians; one direction (0) for tilt 1.

    >>> [round(math.degrees(d)) for d in view_directions(2.0)]
    [0, 36, 72, 108, 144]
    """
    if tilt <= 1.0:
        return [0.0]
    spacing = step / tilt
    return [math.radians(k * spacing) for k in range(int(math.ceil(180.0 / spacing - 1e-9)))]


def simulate_view(
    model: np.ndarray, tilt: float, direction: float
) -> tuple[np.ndarray, np.ndarray]:
    r"""The model seen with a tilt :math:`t = 1 / \cos\theta` about the axis at
    ``direction``: turned by ``direction``, blurred along x by
    :math:`\sigma = 0.8 \sqrt{t^2 - 1}` (against aliasing), shrunk along x by :math:`t`
    (Morel & Yu's simulated tilt). Pixels outside the model are its mean value.

    Returns the view (float32) and the 3×3 affine map from model to view pixels.
    """
    import scipy.ndimage as ndi

    from ..geometry import sample_homography

    rows, cols = model.shape
    corners = _corners((cols, rows))
    turn = np.eye(3)
    turn[:2, :2] = _view_affine(1.0, direction)
    turned = corners @ turn[:2, :2].T
    low, high = np.floor(turned.min(axis=0)) - 1, np.ceil(turned.max(axis=0)) + 1
    turn[:2, 2] = -low
    size = (int(high[1] - low[1]) + 1, int(high[0] - low[0]) + 1)
    turned_image, inside = sample_homography(model, np.linalg.inv(turn), size)
    turned_image[~inside] = float(model.mean())
    if tilt <= 1.0:
        return turned_image.astype(np.float32), turn
    blurred = ndi.gaussian_filter1d(turned_image, 0.8 * math.sqrt(tilt**2 - 1.0), axis=1)
    shrink = np.diag([1.0 / tilt, 1.0, 1.0])
    width = int(math.floor((size[1] - 1) / tilt)) + 1
    view, _ = sample_homography(blurred, np.linalg.inv(shrink), (size[0], width))
    return view.astype(np.float32), shrink @ turn


def model_views(model: np.ndarray, tilts: list[float], sift_options: dict[str, Any]) -> ModelViews:
    """SIFT features of the model and of its simulated views (:func:`simulate_view`) for
    each tilt in ``tilts`` (1 is the model itself) and ASIFT's directions for it
    (:func:`view_directions`); a view's keypoints that fall outside the model are
    dropped (they describe its border with the filled background)."""
    rows, cols = model.shape
    centre = np.array([(cols - 1) / 2, (rows - 1) / 2])
    parts: list[tuple[KeypointSet, np.ndarray, np.ndarray, np.ndarray]] = []
    centres = []
    for tilt in sorted(set([1.0, *tilts])):
        for direction in view_directions(tilt):
            image, affine = simulate_view(model, tilt, direction)
            found = sift(image, **sift_options)
            back = np.linalg.inv(affine)
            xy = found.keypoints.xy @ back[:2, :2].T + back[:2, 2]
            keep = (
                (xy[:, 0] >= 0) & (xy[:, 0] <= cols - 1) & (xy[:, 1] >= 0) & (xy[:, 1] <= rows - 1)
            )
            parts.append(
                (found.keypoints.take(keep), found.descriptors[keep], xy[keep], back[:2, :2])
            )
            centres.append(centre @ affine[:2, :2].T + affine[:2, 2])
    keypoints = KeypointSet(
        np.concatenate([p[0].xy for p in parts]).reshape(-1, 2),
        np.concatenate([p[0].scale for p in parts]),
        np.concatenate([p[0].orientation for p in parts]),
        np.concatenate([p[0].response for p in parts]),
    )
    return ModelViews(
        keypoints,
        np.concatenate([p[1] for p in parts]).reshape(-1, parts[0][1].shape[1]),
        np.concatenate([p[2] for p in parts]).reshape(-1, 2),
        np.concatenate([np.broadcast_to(p[3], (len(p[2]), 2, 2)) for p in parts]).reshape(-1, 2, 2),
        np.concatenate([np.full(len(p[2]), v, np.int64) for v, p in enumerate(parts)]),
        np.asarray(centres, np.float64).reshape(-1, 2),
        (cols, rows),
    )


def match_to_model(
    scene_descriptors: np.ndarray, views: ModelViews, ratio: float, same_place: float
) -> np.ndarray:
    r"""(scene, model feature) pairs passing Lowe's ratio test against the nearest model
    feature *from another place* (section 7.1: with several training views of an
    object, the second-closest neighbour is the closest one known to come from a
    different object; here, one more than ``same_place`` model pixels away from the
    first, so that one point seen in two views does not fail its own test):

    .. math:: \|d - m_1\| < r\,\|d - m_2\|, \qquad \|u_{m_2} - u_{m_1}\| > \delta.

    Each scene feature matches the model, not the other way round, so every instance of
    the model keeps its matches. Rows sorted by scene index.
    """
    count = len(views)
    if count == 0 or len(scene_descriptors) == 0:
        return np.zeros((0, 2), np.int64)
    model = views.descriptors.astype(np.float32)
    model_norm = (model * model).sum(axis=1)
    from scipy.spatial import cKDTree

    same = np.eye(count, dtype=bool)  # (M, M): features within same_place of each other
    close = cKDTree(views.xy).query_pairs(same_place, output_type="ndarray")
    same[close[:, 0], close[:, 1]] = same[close[:, 1], close[:, 0]] = True
    pairs = []
    for start in range(0, len(scene_descriptors), 1024):
        block = scene_descriptors[start : start + 1024].astype(np.float32)
        squared = (block * block).sum(axis=1)[:, None] + model_norm[None, :] - 2.0 * block @ model.T
        nearest = np.argmin(squared, axis=1)
        rows = np.arange(len(block))
        first = squared[rows, nearest]
        squared[same[nearest]] = np.inf
        second = squared.min(axis=1)
        keep = np.sqrt(np.maximum(first, 0.0)) < ratio * np.sqrt(np.maximum(second, 0.0))
        pairs.append(np.column_stack([rows[keep] + start, nearest[keep]]))
    return np.concatenate(pairs).astype(np.int64).reshape(-1, 2)


def _corners(size: tuple[int, int]) -> np.ndarray:
    width, height = size
    return np.array([[0, 0], [width - 1, 0], [width - 1, height - 1], [0, height - 1]], float)
