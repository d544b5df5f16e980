"""Detection by feature constellations (Lowe 2004, section 7): every instance of a model
image in a scene, from SIFT matches voting for the model's pose in a generalised Hough
space, each vote cluster verified by an affine then a homography fit.

The stages, each a function here:

0. **Model views** (:func:`model_views`): SIFT features of the model and of views of
   it simulated at larger tilts (:func:`simulate_view`; Morel & Yu's affine
   simulation, or Lowe's "multiple training views" of an object), each feature
   knowing its position in the model and its view's map to the model. A SIFT
   descriptor survives some 30° to 45° out of plane; the views carry the model to 60°.
1. **Match** (:func:`match_to_model`) every scene feature to its nearest model feature
   by the ratio test against the nearest one *from another place* of the model (Lowe's
   rule for several training views of one object). The direction matters: with several
   instances a model feature has several equally good scene neighbours, so the model →
   scene ratio test and a symmetric check (``matching.match``, the single-object
   recipe) would keep at most one of them.
2. **Vote** (:func:`pose_votes`): each match predicts the model's pose from its two
   keypoints' scales, orientations and positions, and votes in the 2 closest bins of
   each of the 4 dimensions (16 bins) of a hash table, one table per view.
3. **Verify** (:func:`verify_cluster`) each bin with at least ``min_votes`` votes,
   largest first: RANSAC on an affine map, matches gathered top-down from all the
   matches agreeing with it in position, orientation and scale, then RANSAC on a
   homography, gathered and refitted (DLT, then Levenberg-Marquardt) until the inlier
   set is stable.
4. **Accept** by Lowe's probability that the agreeing matches are not chance
   (:func:`pose_probability`) and suppress overlapping instances (polygon IoU).

Instances are the model's corners mapped by the homography (pixel centres (0, 0),
(w-1, 0), (w-1, h-1), (0, h-1), as ``synthetic.object_scenes`` draws them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Any, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import (
    Array,
    ColorImage,
    Float,
    FloatImage,
    GrayImage,
    Int,
    KeypointSet,
    PortValueError,
    RecordPort,
    node,
)

from ..features import sift
from ..fitting import ransac
from ..geometry import apply_homography, estimate_homography, refine_homography
from ..shared.draw import colour_canvas, draw_segment
from ..shared.params import Fraction, Probability, Seed
from ..synthetic import ObjectScenes, ObjectSceneSet

__all__ = [
    "ConstellationParams",
    "FoundInScenes",
    "FoundInstances",
    "InstanceSet",
    "Instances",
    "InstancesPort",
    "ModelViews",
    "PoseVotes",
    "convex_overlap",
    "draw_object_scenes",
    "find_instances",
    "find_instances_in_scenes",
    "locate_instances",
    "log_binomial_tail",
    "match_instances",
    "match_probability",
    "match_to_model",
    "model_views",
    "polygon_area",
    "pose_probability",
    "pose_votes",
    "quad_iou",
    "score_instances",
    "simulate_view",
    "verify_cluster",
    "view_directions",
    "vote_picture",
]


# --------------------------------------------------------------------------- instances


@dataclass(frozen=True, eq=False)
class InstanceSet:
    """K found instances of a model: ``quads`` (K, 4, 2) the model's corners in the scene,
    ``homographies`` (K, 3, 3) model → scene, ``inliers`` (K,) int64 the matches that
    support each, ``probability`` (K,) Lowe's :math:`P(m \\mid f)`, ``owner`` (K,) int64
    the scene each was found in, out of ``scenes`` scenes."""

    quads: np.ndarray
    homographies: np.ndarray
    inliers: np.ndarray
    probability: np.ndarray
    owner: np.ndarray
    scenes: int = 1

    def __len__(self) -> int:
        return len(self.quads)

    @classmethod
    def empty(cls, scenes: int = 1) -> InstanceSet:
        return cls(
            np.zeros((0, 4, 2)),
            np.zeros((0, 3, 3)),
            np.zeros(0, np.int64),
            np.zeros(0),
            np.zeros(0, np.int64),
            scenes,
        )

    @classmethod
    def concatenate(cls, parts: list[InstanceSet], scenes: int) -> InstanceSet:
        """One set from per-scene sets (their ``owner`` already set)."""
        if not parts:
            return cls.empty(scenes)
        return cls(
            np.concatenate([p.quads for p in parts]).reshape(-1, 4, 2),
            np.concatenate([p.homographies for p in parts]).reshape(-1, 3, 3),
            np.concatenate([p.inliers for p in parts]).astype(np.int64),
            np.concatenate([p.probability for p in parts]).astype(np.float64),
            np.concatenate([p.owner for p in parts]).astype(np.int64),
            scenes,
        )


class InstancesPort(RecordPort):
    """An :class:`InstanceSet`: quads float64 (K, 4, 2), homographies float64 (K, 3, 3),
    finite; inliers and owner int64 (K,), owner in [0, scenes); probability float64 (K,)."""

    value_class = InstanceSet

    @classmethod
    def validate(cls, value: Any) -> InstanceSet:
        value = super().validate(value)
        count = len(value.quads) if isinstance(value.quads, np.ndarray) else -1
        shapes = {
            "quads": (np.float64, (count, 4, 2)),
            "homographies": (np.float64, (count, 3, 3)),
            "inliers": (np.int64, (count,)),
            "probability": (np.float64, (count,)),
            "owner": (np.int64, (count,)),
        }
        for name, (dtype, shape) in shapes.items():
            column = getattr(value, name)
            if not isinstance(column, np.ndarray) or column.dtype != dtype or column.shape != shape:
                raise PortValueError(
                    f"Instances '{name}' must be {np.dtype(dtype).name} {shape}: one per instance"
                )
        if not (np.isfinite(value.quads).all() and np.isfinite(value.homographies).all()):
            raise PortValueError("Instances 'quads' and 'homographies' must be finite")
        if not isinstance(value.scenes, int) or value.scenes < 1:
            raise PortValueError(f"Instances 'scenes' must be a positive int, got {value.scenes!r}")
        if count > 0 and (value.owner.min() < 0 or value.owner.max() >= value.scenes):
            raise PortValueError(f"Instances 'owner' must index the {value.scenes} scenes")
        return value

    @classmethod
    def summary(cls, value: InstanceSet) -> str:
        return f"Instances {len(value)} in {value.scenes} scene(s)"


Instances = Annotated[InstanceSet, InstancesPort]


# --------------------------------------------------------------------------- polygons


def polygon_area(points: np.ndarray) -> float:
    r"""Signed area of a polygon ``(N, 2)`` by the shoelace formula,
    :math:`\tfrac12 \sum_i (x_i y_{i+1} - x_{i+1} y_i)` (positive when its vertices turn
    from +x towards +y, clockwise on the screen).

    >>> polygon_area(np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float))
    2.0
    """
    if len(points) < 3:
        return 0.0
    x, y = points[:, 0], points[:, 1]
    return float(0.5 * (x @ np.roll(y, -1) - np.roll(x, -1) @ y))


def _is_convex(quad: np.ndarray) -> bool:
    """Every turn of the closed polygon has the same, non-zero sign."""
    edges = np.roll(quad, -1, axis=0) - quad
    turns = (
        edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1]
        - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
    )
    return bool((turns > 0).all() or (turns < 0).all())


def _inside_convex(polygon: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Which ``points`` (N, 2) lie inside the convex ``polygon`` (on the same side of every
    edge)."""
    edges = np.roll(polygon, -1, axis=0) - polygon
    relative = points[:, None, :] - polygon[None, :, :]
    cross = edges[None, :, 0] * relative[:, :, 1] - edges[None, :, 1] * relative[:, :, 0]
    return (cross >= 0).all(axis=1) | (cross <= 0).all(axis=1)


def convex_overlap(a: np.ndarray, b: np.ndarray) -> float:
    """Area of the intersection of two convex polygons (Sutherland-Hodgman clipping of
    ``a`` by each edge of ``b``); either orientation.

    >>> square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], float)
    >>> convex_overlap(square, square + 1)
    1.0
    """
    if polygon_area(a) < 0:
        a = a[::-1]
    if polygon_area(b) < 0:
        b = b[::-1]
    out = [p for p in a]
    for start, end in zip(b, np.roll(b, -1, axis=0), strict=True):
        if not out:
            break
        edge = end - start

        def side(p: np.ndarray, start: np.ndarray = start, edge: np.ndarray = edge) -> float:
            return float(edge[0] * (p[1] - start[1]) - edge[1] * (p[0] - start[0]))

        clipped = []
        for i, p in enumerate(out):
            q = out[i - 1]
            sp, sq = side(p), side(q)
            if sp >= 0:
                if sq < 0:
                    clipped.append(q + (p - q) * (sq / (sq - sp)))
                clipped.append(p)
            elif sq >= 0:
                clipped.append(q + (p - q) * (sq / (sq - sp)))
        out = clipped
    return abs(polygon_area(np.array(out))) if len(out) >= 3 else 0.0


def quad_iou(a: np.ndarray, b: np.ndarray) -> float:
    r"""Intersection over union of two convex quadrilaterals,
    :math:`|a \cap b| / (|a| + |b| - |a \cap b|)`."""
    inter = convex_overlap(a, b)
    union = abs(polygon_area(a)) + abs(polygon_area(b)) - inter
    return inter / union if union > 0 else 0.0


# --------------------------------------------------------------------------- the model


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


# --------------------------------------------------------------------------- voting


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


# --------------------------------------------------------------------------- verification


def _affine(src: np.ndarray, dst: np.ndarray) -> np.ndarray | None:
    r"""Least-squares affine map :math:`dst = A\,[src;\ 1]` (Lowe's equation (5): the
    normal equations of the 6 parameters), as a 3×3 matrix, or None when the points are
    (nearly) collinear."""
    if len(src) < 3:
        return None
    centre = src.mean(axis=0)
    design = np.column_stack([src - centre, np.ones(len(src))])
    if len(src) == 3:
        if abs(np.linalg.det(design)) < 1.0:  # twice the triangle's area, in pixels
            return None
        solution = np.linalg.solve(design, dst)
    else:
        if np.linalg.eigvalsh((design[:, :2].T @ design[:, :2]) / len(src))[0] < 0.25:
            return None
        solution, *_ = np.linalg.lstsq(design, dst, rcond=None)
    affine = np.vstack([solution.T, [0.0, 0.0, 1.0]])
    return affine @ np.array([[1.0, 0.0, -centre[0]], [0.0, 1.0, -centre[1]], [0.0, 0.0, 1.0]])


def _residual(h: np.ndarray, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    error = np.linalg.norm(apply_homography(h, src) - dst, axis=1)
    return np.where(np.isfinite(error), error, np.inf)


def _consistent(
    h: np.ndarray,
    views: ModelViews,
    scene_keypoints: KeypointSet,
    pairs: np.ndarray,
    params: ConstellationParams,
    threshold: float,
) -> np.ndarray:
    r"""Matches that agree with ``h`` (a homography or an affine map): position within
    ``threshold`` px, orientation within
    ``orientation_tolerance`` degrees and scale within a factor ``scale_tolerance`` of
    what the local affine map predicts for the model keypoint, :math:`J = J_H(u) F`
    (:math:`J_H` the homography's Jacobian at the keypoint's model position :math:`u`,
    :math:`F` its view's map to the model): orientation :math:`\angle J (\cos\theta,
    \sin\theta)^T`, scale :math:`\sigma \sqrt{|\det J|}`."""
    model, scene = pairs[:, 1], pairs[:, 0]
    points = views.xy[model]
    w = points @ h[2, :2] + h[2, 2]
    mapped = apply_homography(h, points)
    jacobian = (h[None, :2, :2] - mapped[:, :, None] * h[None, 2:3, :2]) / w[:, None, None]
    jacobian = jacobian @ views.frame[model]
    close = np.linalg.norm(mapped - scene_keypoints.xy[scene], axis=1) < threshold
    theta = views.keypoints.orientation[model]
    direction = np.einsum("nij,nj->ni", jacobian, np.column_stack([np.cos(theta), np.sin(theta)]))
    predicted = np.arctan2(direction[:, 1], direction[:, 0])
    turn = np.angle(np.exp(1j * (scene_keypoints.orientation[scene] - predicted)))
    stretch = np.sqrt(np.abs(np.linalg.det(jacobian)))
    with np.errstate(divide="ignore", invalid="ignore"):
        size = np.log(scene_keypoints.scale[scene] / (views.keypoints.scale[model] * stretch))
        agree = (np.abs(np.degrees(turn)) < params.orientation_tolerance) & (
            np.abs(size) < math.log(params.scale_tolerance)
        )
    return close & agree & (w > 0)


def _corners(size: tuple[int, int]) -> np.ndarray:
    width, height = size
    return np.array([[0, 0], [width - 1, 0], [width - 1, height - 1], [0, height - 1]], float)


def _valid_quad(h: np.ndarray, size: tuple[int, int], scene_shape: tuple[int, int]) -> bool:
    """The model maps in front of the camera (w > 0 at every corner), unmirrored, to a
    convex quadrilateral of at least 8 × 8 px whose centre is inside the scene."""
    corners = _corners(size)
    w = corners @ h[2, :2] + h[2, 2]
    if not (w > 0).all():
        return False
    quad = apply_homography(h, corners)
    if not np.isfinite(quad).all() or not _is_convex(quad):
        return False
    area = polygon_area(quad)
    if np.sign(area) != np.sign(polygon_area(corners)) or abs(area) < 64:
        return False
    centre = quad.mean(axis=0)
    return bool(0 <= centre[0] < scene_shape[1] and 0 <= centre[1] < scene_shape[0])


def log_binomial_tail(k: int, n: int, p: float) -> float:
    r""":math:`\log P(X \ge k)` for :math:`X \sim B(n, p)`, summed in log space
    (:math:`\log \binom{n}{j}` from ``math.lgamma``) so that a tail far below the
    smallest float is still compared rightly with a small prior.

    >>> round(math.exp(log_binomial_tail(2, 3, 0.5)), 6)
    0.5
    """
    if k <= 0 or p >= 1.0:
        return 0.0
    if k > n or p <= 0.0:
        return -math.inf
    j = np.arange(k, n + 1)
    log_choose = np.array(
        [math.lgamma(n + 1) - math.lgamma(v + 1) - math.lgamma(n - v + 1) for v in j]
    )
    log_terms = log_choose + j * math.log(p) + (n - j) * math.log1p(-p)
    top = float(log_terms.max())
    return min(top + math.log(float(np.exp(log_terms - top).sum())), 0.0)


def match_probability(
    inliers: int, candidates: int, p: float, prior: float, sample: int = 4
) -> float:
    r"""Lowe's probability that ``inliers`` agreeing matches reveal the model (section 7.4).

    Of the :math:`n` = ``candidates`` scene features inside the projected model, each
    agrees with the pose by chance with probability :math:`p`; the chance of :math:`k`
    such agreements is the binomial tail

    .. math:: P(f \mid \neg m) = \sum_{j=k}^{n} \binom{n}{j} p^j (1 - p)^{n - j},

    and Bayes' rule with :math:`P(f \mid m) = 1` and the prior :math:`P(m)` gives

    .. math:: P(m \mid f) = \frac{P(m)}{P(m) + P(f \mid \neg m)\,(1 - P(m))}.

    The ``sample`` matches a homography passes through agree by construction, so
    :math:`k` and :math:`n` count the features beyond them.

    >>> round(match_probability(10, 100, 0.01, 0.01), 4)
    0.9592
    >>> match_probability(4, 100, 0.01, 0.01) == 0.01
    True
    """
    beyond = inliers - sample
    if beyond <= 0:
        return prior
    log_chance = log_binomial_tail(beyond, max(candidates - sample, beyond), p)
    odds = math.exp(min(log_chance - math.log(prior) + math.log1p(-prior), 700.0))
    return 1.0 / (1.0 + odds)


def _unique_positions(points: np.ndarray) -> int:
    return len(np.unique(np.round(points, 3), axis=0)) if len(points) else 0


def pose_probability(
    h: np.ndarray,
    inliers: np.ndarray,
    views: ModelViews,
    scene_keypoints: KeypointSet,
    pairs: np.ndarray,
    params: ConstellationParams,
) -> float:
    r""":func:`match_probability` of a pose. :math:`k`: the inliers' distinct scene
    positions; :math:`n`: the scene keypoints' distinct positions inside the projected
    model; :math:`p = d\,l\,r\,s` (Lowe's product): :math:`d` the fraction of scene
    keypoints matched to the model at all, :math:`l = \pi \tau^2 / A` the chance that a
    match lands within ``threshold`` :math:`\tau` of its prediction (:math:`A` the
    projected model's area), :math:`r = 2\,\Delta\theta / 360°` for the orientation
    tolerance and :math:`s = 0.5` for the scale (Lowe's value)."""
    quad = apply_homography(h, _corners(views.size))
    inside = _inside_convex(quad, scene_keypoints.xy)
    candidates = _unique_positions(scene_keypoints.xy[inside])
    k = _unique_positions(scene_keypoints.xy[pairs[inliers, 0]])
    d = len(np.unique(pairs[:, 0])) / max(len(scene_keypoints), 1)
    location = min(math.pi * params.threshold**2 / max(abs(polygon_area(quad)), 1e-9), 1.0)
    rotation = min(2 * params.orientation_tolerance / 360.0, 1.0)
    return match_probability(k, max(candidates, k), d * location * rotation * 0.5, params.prior)


class Hypothesis(NamedTuple):
    homography: np.ndarray
    inliers: np.ndarray  # match indices
    probability: float


def verify_cluster(
    cluster: np.ndarray,
    views: ModelViews,
    scene_keypoints: KeypointSet,
    pairs: np.ndarray,
    scene_shape: tuple[int, int],
    params: ConstellationParams,
) -> Hypothesis | None:
    r"""Verify one Hough cluster (match indices ``cluster``) by fitting its pose.

    1. RANSAC on an affine map (samples of 3) from the cluster's model positions to its
       scene positions, inliers within half a location bin (Lowe: half the error range
       of the Hough bins);
    2. top-down: every match (not only the cluster's) within that distance of the affine
       prediction, and agreeing with it in orientation and scale (:func:`_consistent`),
       joins; least squares again, twice (a mirroring map is refused);
    3. RANSAC on a homography (normalised DLT on samples of 4) over the gathered
       matches, inliers within ``threshold`` px;
    4. top-down again: all matches consistent with the homography in position,
       orientation and scale (:func:`_consistent`), refitted by DLT until the set is
       stable (at most 5 rounds), then by Levenberg-Marquardt.

    Returns None when a stage keeps too few matches or the pose is implausible (behind
    the camera, mirrored, not convex); else the homography, its inliers and
    :func:`pose_probability`.
    """
    if len(cluster) < 3:
        return None
    src_all = views.xy[pairs[:, 1]]
    dst_all = scene_keypoints.xy[pairs[:, 0]]
    src, dst = src_all[cluster], dst_all[cluster]
    ratio = scene_keypoints.scale[pairs[cluster, 0]] / views.keypoints.scale[pairs[cluster, 1]]
    loose = 0.5 * params.location_bin * max(views.size) * float(np.median(ratio))
    found = ransac(
        len(cluster),
        3,
        lambda s: _affine(src[s], dst[s]),
        lambda a: _residual(a, src, dst),
        loose,
        refit=lambda i: _affine(src[i], dst[i]),
        max_iterations=100,
        seed=params.seed,
    )
    if found.model is None or found.inliers.sum() < 3:
        return None
    affine = found.model
    for _ in range(2):
        if np.linalg.det(affine[:2, :2]) <= 0:
            return None  # a mirror image: not a view of the model
        members = np.flatnonzero(_consistent(affine, views, scene_keypoints, pairs, params, loose))
        if len(members) < max(params.min_inliers, 5):
            return None
        refit = _affine(src_all[members], dst_all[members])
        if refit is None:
            return None
        affine = refit
    a, b = src_all[members], dst_all[members]
    fit = ransac(
        len(members),
        4,
        lambda s: estimate_homography(a[s], b[s]),
        lambda h: _residual(h, a, b),
        params.threshold,
        refit=lambda i: estimate_homography(a[i], b[i]),
        confidence=0.995,
        max_iterations=200,
        seed=params.seed,
    )
    if fit.model is None:
        return None
    h, inliers = fit.model, members[fit.inliers]
    for _ in range(5):
        agree = np.flatnonzero(
            _consistent(h, views, scene_keypoints, pairs, params, params.threshold)
        )
        if len(agree) < 5:
            return None
        refit = estimate_homography(src_all[agree], dst_all[agree])
        if refit is None:
            return None
        stable = np.array_equal(agree, inliers)
        h, inliers = refit, agree
        if stable:
            break
    h = refine_homography(h, src_all[inliers], dst_all[inliers])
    if not _valid_quad(h, views.size, scene_shape):
        return None
    probability = pose_probability(h, inliers, views, scene_keypoints, pairs, params)
    return Hypothesis(h, inliers, probability)


def locate_instances(
    views: ModelViews,
    scene_keypoints: KeypointSet,
    pairs: np.ndarray,
    scene_shape: tuple[int, int],
    params: ConstellationParams,
) -> tuple[InstanceSet, PoseVotes]:
    """Every instance of the model (see the module): the Hough table (:func:`pose_votes`),
    each bin of at least ``min_votes`` votes verified (:func:`verify_cluster`), largest
    first (at most ``max_clusters``; a bin whose matches mostly support an accepted
    instance already, or were all tried in a rejected bin, is skipped), accepted when
    :math:`P(m \\mid f) \\ge` ``min_probability`` with at least ``min_inliers`` distinct
    inliers; then non-maximum suppression: of two instances whose quadrilaterals overlap
    by more than ``nms_iou``, the one with more inliers stays."""
    votes = pose_votes(views, scene_keypoints, pairs, params)
    order = np.argsort(-votes.counts, kind="stable")
    order = order[votes.counts[order] >= params.min_votes][: params.max_clusters]
    claimed = np.zeros(len(pairs), bool)
    tried: set[tuple[int, ...]] = set()
    accepted: list[Hypothesis] = []
    for b in order:
        cluster = votes.members[votes.starts[b] : votes.starts[b + 1]]
        if claimed[cluster].mean() > 0.5:
            continue
        signature = tuple(np.sort(cluster).tolist())
        if signature in tried:
            continue
        tried.add(signature)
        hypothesis = verify_cluster(cluster, views, scene_keypoints, pairs, scene_shape, params)
        if hypothesis is None:
            continue
        distinct = _unique_positions(scene_keypoints.xy[pairs[hypothesis.inliers, 0]])
        if distinct < params.min_inliers or hypothesis.probability < params.min_probability:
            continue
        accepted.append(hypothesis)
        claimed[hypothesis.inliers] = True
    accepted.sort(key=lambda one: -len(one.inliers))
    corners = _corners(views.size)
    kept: list[tuple[Hypothesis, np.ndarray]] = []
    for hypothesis in accepted:
        quad = apply_homography(hypothesis.homography, corners)
        if all(quad_iou(quad, other) <= params.nms_iou for _, other in kept):
            kept.append((hypothesis, quad))
    if not kept:
        return InstanceSet.empty(), votes
    instances = InstanceSet(
        np.array([quad for _, quad in kept], np.float64),
        np.array([one.homography for one, _ in kept], np.float64),
        np.array([len(one.inliers) for one, _ in kept], np.int64),
        np.array([one.probability for one, _ in kept], np.float64),
        np.zeros(len(kept), np.int64),
    )
    return instances, votes


# --------------------------------------------------------------------------- nodes

Tilts = Annotated[
    list[Annotated[float, Field(ge=1.0, le=8.0)]],
    Field(max_length=8, description="Tilts t = 1/cos θ of the simulated model views."),
]
Ratio = Annotated[float, Field(gt=0, le=1, description="Lowe's ratio of nearest distances.")]
SamePlace = Annotated[
    float, Field(ge=0, le=100, description="Model pixels within which two features are one place.")
]
OrientationBin = Annotated[float, Field(ge=1, le=180, description="Orientation bin, degrees.")]
ScaleBin = Annotated[float, Field(gt=1, le=8, description="Scale bin, a factor.")]
LocationBin = Annotated[
    float, Field(gt=0, le=4, description="Location bin, in model sides at the predicted scale.")
]
MinVotes = Annotated[
    int, Field(ge=3, le=1000, description="Fewest votes of a bin worth verifying.")
]
Threshold = Annotated[float, Field(gt=0, le=100, description="Inlier distance, scene pixels.")]
Tolerance = Annotated[float, Field(gt=0, le=180, description="Orientation agreement, degrees.")]
ScaleTolerance = Annotated[float, Field(gt=1, le=8, description="Scale agreement, a factor.")]
MinInliers = Annotated[
    int, Field(ge=5, le=10_000, description="Fewest distinct inliers of an instance.")
]
MaxClusters = Annotated[int, Field(ge=1, le=100_000, description="Most bins verified per scene.")]
VoteCell = Annotated[int, Field(ge=1, le=64, description="Pixels per cell of the vote picture.")]


def _params(**values: Any) -> ConstellationParams:
    return ConstellationParams(**values)


class FoundInstances(NamedTuple):
    instances: Instances
    votes: FloatImage


class FoundInScenes(NamedTuple):
    instances: Instances
    votes: Array


def _find(
    views: ModelViews, scene: np.ndarray, params: ConstellationParams, cell: int
) -> tuple[InstanceSet, np.ndarray]:
    found = sift(scene)
    pairs = match_to_model(found.descriptors, views, params.ratio, params.same_place)
    instances, votes = locate_instances(views, found.keypoints, pairs, scene.shape, params)
    return instances, vote_picture(votes, scene.shape, cell)


@node("matching.find_instances", version=1)
def find_instances(
    model: GrayImage,
    scene: GrayImage,
    *,
    tilts: Tilts = [1.414, 2.0],  # noqa: B006
    ratio: Ratio = 0.8,
    same_place: SamePlace = 3.0,
    orientation_bin: OrientationBin = 30.0,
    scale_bin: ScaleBin = 2.0,
    location_bin: LocationBin = 0.25,
    min_votes: MinVotes = 3,
    threshold: Threshold = 3.0,
    orientation_tolerance: Tolerance = 30.0,
    scale_tolerance: ScaleTolerance = 2.0,
    min_inliers: MinInliers = 8,
    min_probability: Probability = 0.98,
    prior: Probability = 0.01,
    nms_iou: Fraction = 0.2,
    max_clusters: MaxClusters = 300,
    vote_cell: VoteCell = 4,
    seed: Seed = 0,
) -> FoundInstances:
    r"""Every instance of ``model`` in ``scene``: detection by feature constellations
    (Lowe 2004, section 7).

    1. SIFT features (``features.sift``) of the model, of simulated views of it tilted
       by each of ``tilts`` (so that features survive 60° out of plane: Morel & Yu's
       affine simulation, Lowe's multiple training views) and of the scene;
    2. each scene feature matched to its nearest model feature by the ratio test against
       the nearest model feature from another place (section 7.1);
    3. each match votes for the pose :math:`(x, y, \log s, \phi)` of the model in its
       view, :math:`s = \sigma_i/\sigma_j`, :math:`\phi = \theta_i - \theta_j`,
       :math:`r = x_i + s R(\phi)(c - u_j)`, in the 2 closest bins of each dimension
       (section 7.3);
    4. each bin with at least ``min_votes`` votes is verified: RANSAC on an affine map,
       matches gathered top-down, RANSAC on a homography, outliers removed and the fit
       repeated (section 7.4's least squares, then Levenberg-Marquardt);
    5. accepted when :math:`P(m \mid f) = P(m) / (P(m) + P(f \mid \neg m)(1 - P(m)))`
       reaches ``min_probability``, :math:`P(f \mid \neg m)` the binomial tail of the
       inliers among the scene features inside the projected model (section 7.4); of
       overlapping instances the better supported stays.

    Parameters
    ----------
    model : GrayImage
        The object's picture (a planar object: its instances are homographies of it).
    scene : GrayImage
        The picture to search.
    tilts : list of float
        Tilts :math:`t = 1 / \cos\theta` of the simulated views of the model, each in
        ASIFT's directions (the model itself is always a view). [] is Lowe's single
        training view; [1.414, 2] adds 45° and 60° out of plane.
    ratio : float
        Lowe's ratio test, against the nearest model feature from another place.
    same_place : float
        Model pixels within which two model features count as one place.
    orientation_bin, scale_bin, location_bin : float
        Hough bins: degrees; a factor; model sides at the predicted scale (Lowe: 30°, 2,
        0.25).
    min_votes : int
        Fewest votes of a bin that is verified (Lowe: 3).
    threshold : float
        Inlier distance of the homography, scene pixels.
    orientation_tolerance, scale_tolerance : float
        An inlier's orientation and scale agree with the pose within these (degrees, a
        factor).
    min_inliers : int
        Fewest distinct inlier positions of an accepted instance.
    min_probability : float
        Least :math:`P(m \mid f)` of an accepted instance (Lowe: 0.98).
    prior : float
        :math:`P(m)`, the prior probability of a pose hypothesis.
    nms_iou : float
        Of two instances overlapping by more (polygon IoU), the one with fewer inliers
        is dropped.
    max_clusters : int
        Most Hough bins verified per scene, largest first.
    vote_cell : int
        Scene pixels per cell of the vote picture.
    seed : int
        Seed of the RANSAC samples.
    Returns
    -------
    instances : Instances
        One row per instance: the model's corners in the scene, the homography, the
        inlier count and :math:`P(m \mid f)`; best supported first.
    votes : FloatImage
        The Hough table seen from above: per ``vote_cell`` × ``vote_cell`` block of the
        scene, the most votes of a bin covering it (over view, scale and orientation).

    References
    ----------
    .. [1] D. G. Lowe, "Distinctive image features from scale-invariant keypoints",
       IJCV 60(2), 2004, section 7.
    .. [2] J.-M. Morel, G. Yu, "ASIFT: a new framework for fully affine invariant image
       comparison", SIAM J. Imaging Sciences 2(2), 2009 (simulated tilts).
    .. [3] D. H. Ballard, "Generalizing the Hough transform to detect arbitrary shapes",
       Pattern Recognition 13(2), 1981.
    """
    params = _params(
        ratio=ratio,
        same_place=same_place,
        orientation_bin=orientation_bin,
        scale_bin=scale_bin,
        location_bin=location_bin,
        min_votes=min_votes,
        threshold=threshold,
        orientation_tolerance=orientation_tolerance,
        scale_tolerance=scale_tolerance,
        min_inliers=min_inliers,
        min_probability=min_probability,
        prior=prior,
        nms_iou=nms_iou,
        max_clusters=max_clusters,
        seed=seed,
    )
    _check_model(model)
    views = model_views(model, tilts, {})
    instances, votes = _find(views, scene, params, vote_cell)
    return FoundInstances(instances, votes)


def _check_model(model: np.ndarray) -> None:
    if min(model.shape) < 16:
        raise ValueError(
            f"the model is {model.shape[1]}×{model.shape[0]} pixels: at least 16×16 is needed "
            "for SIFT to find features in it"
        )


@node("matching.find_instances_in_scenes", version=1)
def find_instances_in_scenes(
    model: GrayImage,
    scenes: ObjectScenes,
    *,
    tilts: Tilts = [1.414, 2.0],  # noqa: B006
    ratio: Ratio = 0.8,
    same_place: SamePlace = 3.0,
    orientation_bin: OrientationBin = 30.0,
    scale_bin: ScaleBin = 2.0,
    location_bin: LocationBin = 0.25,
    min_votes: MinVotes = 3,
    threshold: Threshold = 3.0,
    orientation_tolerance: Tolerance = 30.0,
    scale_tolerance: ScaleTolerance = 2.0,
    min_inliers: MinInliers = 8,
    min_probability: Probability = 0.98,
    prior: Probability = 0.01,
    nms_iou: Fraction = 0.2,
    max_clusters: MaxClusters = 300,
    vote_cell: VoteCell = 4,
    seed: Seed = 0,
) -> FoundInScenes:
    r"""``matching.find_instances`` in every scene of a set: the model's views are
    described once, each scene in turn.

    Parameters
    ----------
    model : GrayImage
        The object's picture.
    scenes : ObjectScenes
        The scenes to search (their true instances are not used).
    tilts : list of float
        Tilts :math:`t = 1 / \cos\theta` of the simulated views of the model, each in
        ASIFT's directions (the model itself is always a view). [] is Lowe's single
        training view; [1.414, 2] adds 45° and 60° out of plane.
    ratio : float
        Lowe's ratio test, against the nearest model feature from another place.
    same_place : float
        Model pixels within which two model features count as one place.
    orientation_bin, scale_bin, location_bin : float
        Hough bins: degrees; a factor; model sides at the predicted scale (Lowe: 30°, 2,
        0.25).
    min_votes : int
        Fewest votes of a bin that is verified (Lowe: 3).
    threshold : float
        Inlier distance of the homography, scene pixels.
    orientation_tolerance, scale_tolerance : float
        An inlier's orientation and scale agree with the pose within these (degrees, a
        factor).
    min_inliers : int
        Fewest distinct inlier positions of an accepted instance.
    min_probability : float
        Least :math:`P(m \mid f)` of an accepted instance (Lowe: 0.98).
    prior : float
        :math:`P(m)`, the prior probability of a pose hypothesis.
    nms_iou : float
        Of two instances overlapping by more (polygon IoU), the one with fewer inliers
        is dropped.
    max_clusters : int
        Most Hough bins verified per scene, largest first.
    vote_cell : int
        Scene pixels per cell of the vote picture.
    seed : int
        Seed of the RANSAC samples.
    Returns
    -------
    instances : Instances
        The instances of all scenes, ``owner`` the scene of each.
    votes : Array
        (N, ceil(H / vote_cell), ceil(W / vote_cell)) float32, each scene's vote picture.

    References
    ----------
    .. [1] D. G. Lowe, "Distinctive image features from scale-invariant keypoints",
       IJCV 60(2), 2004, section 7.
    """
    params = _params(
        ratio=ratio,
        same_place=same_place,
        orientation_bin=orientation_bin,
        scale_bin=scale_bin,
        location_bin=location_bin,
        min_votes=min_votes,
        threshold=threshold,
        orientation_tolerance=orientation_tolerance,
        scale_tolerance=scale_tolerance,
        min_inliers=min_inliers,
        min_probability=min_probability,
        prior=prior,
        nms_iou=nms_iou,
        max_clusters=max_clusters,
        seed=seed,
    )
    _check_model(model)
    views = model_views(model, tilts, {})
    parts, pictures = [], []
    for index, scene in enumerate(scenes.images):
        instances, picture = _find(views, scene, params, vote_cell)
        parts.append(
            InstanceSet(
                instances.quads,
                instances.homographies,
                instances.inliers,
                instances.probability,
                np.full(len(instances), index, np.int64),
                len(scenes),
            )
        )
        pictures.append(picture)
    return FoundInScenes(InstanceSet.concatenate(parts, len(scenes)), np.stack(pictures))


# --------------------------------------------------------------------------- scores


def match_instances(instances: InstanceSet, scenes: ObjectSceneSet, iou: float) -> np.ndarray:
    """For each found instance, the index of the true instance it finds, or -1: taken in
    decreasing inlier count, each takes the untaken true instance of its scene that it
    overlaps most, if their polygon IoU (:func:`quad_iou`) is at least ``iou``."""
    if instances.scenes != len(scenes):
        raise ValueError(
            f"the instances were found in {instances.scenes} scenes but {len(scenes)} scenes "
            "are given"
        )
    found = np.full(len(instances), -1, np.int64)
    taken = np.zeros(len(scenes.owner), bool)
    for index in np.argsort(-instances.inliers, kind="stable"):
        candidates = np.flatnonzero((scenes.owner == instances.owner[index]) & ~taken)
        if len(candidates) == 0:
            continue
        overlaps = [quad_iou(instances.quads[index], scenes.quads[j]) for j in candidates]
        best = int(np.argmax(overlaps))
        if overlaps[best] >= iou:
            found[index] = candidates[best]
            taken[candidates[best]] = True
    return found


class InstanceScores(NamedTuple):
    recall: Float
    precision: Float
    corner_error: Float
    found: Int
    missed: Int
    false_positives: Int


@node("matching.score_instances", version=1)
def score_instances(
    instances: Instances,
    scenes: ObjectScenes,
    *,
    iou: Annotated[float, Field(gt=0, le=1)] = 0.5,
) -> InstanceScores:
    r"""Found instances against the true quadrilaterals: recall, precision, corner error.

    A found instance is a true positive when its quadrilateral overlaps a true one of its
    scene by a polygon IoU :math:`|A \cap B| / |A \cup B| \ge` ``iou`` (each true instance
    found once, best supported first; :func:`match_instances`). Then

    .. math:: \text{recall} = \frac{TP}{TP + FN}, \qquad
              \text{precision} = \frac{TP}{TP + FP}, \qquad
              e = \operatorname{median}_{TP} \frac14 \sum_{c=1}^{4} \|\hat q_c - q_c\|

    where :math:`\hat q_c` and :math:`q_c` are the found and the true images of model
    corner :math:`c` (so a pose turned by 90° is found by IoU but has a large corner
    error). Recall is 1 when there is nothing to find, precision 1 when nothing is
    found, the corner error infinite when no instance is found.

    Parameters
    ----------
    instances : Instances
        What a detector found (``matching.find_instances_in_scenes``).
    scenes : ObjectScenes
        The scenes with their true instances.
    iou : float
        Least polygon IoU of a true positive (PASCAL VOC's 0.5).

    Returns
    -------
    recall, precision : float
    corner_error : float
        Median over true positives of the mean distance of the four corners, pixels.
    found, missed, false_positives : int
        True positives, false negatives, false positives.

    References
    ----------
    .. [1] M. Everingham et al., "The PASCAL visual object classes (VOC) challenge",
       IJCV 88(2), 2010 (overlap criterion).
    .. [2] D. DeTone, T. Malisiewicz, A. Rabinovich, "Deep image homography
       estimation", 2016 (mean corner error of a homography).
    """
    hits = match_instances(instances, scenes, iou)
    true_positive = hits >= 0
    tp = int(true_positive.sum())
    errors = [
        float(np.linalg.norm(instances.quads[i] - scenes.quads[hits[i]], axis=1).mean())
        for i in np.flatnonzero(true_positive)
    ]
    total = len(scenes.owner)
    return InstanceScores(
        tp / total if total else 1.0,
        tp / len(instances) if len(instances) else 1.0,
        float(np.median(errors)) if errors else math.inf,
        tp,
        total - tp,
        len(instances) - tp,
    )


# --------------------------------------------------------------------------- pictures

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
