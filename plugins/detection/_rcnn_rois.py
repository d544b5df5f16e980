"""R-CNN's regions (see :mod:`._rcnn`): proposals per scene, training ROIs labelled by
their overlap with the true boxes (background below IoU 0.3, a class at 0.5 or more) with
their box-regression targets, and the ROI samples, cropped and warped, that train the
backbone."""

from __future__ import annotations

from typing import Annotated, Any, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import node

from ..recognition._types import Samples, SampleSet
from ..shared.boxes import iou_matrix
from ..shared.params import Fraction, Positive, Seed
from ..synthetic._digit_scenes import Scenes, SceneSet
from ._proposals import ColourSpaces, PositiveList, SimilaritySets
from ._types import Detections, DetectionSet

__all__ = [
    "TrainingRois",
    "roi_samples",
    "scene_proposals",
    "training_rois",
]


BACKGROUND = -1
"""The label of background ROIs (below every class label)."""


PIXELS_PER_PROPOSAL = 32
"""With ``max_boxes=None``, a scene keeps one proposal per this many pixels (200 for the
80 × 80 scenes R-CNN trains on, 1800 for a 240 × 240 scene of 30 digits)."""


@node("detection.scene_proposals", version=2)
def scene_proposals(
    scenes: Scenes,
    *,
    colour_spaces: ColourSpaces = ["gray"],  # noqa: B006 (never mutated)
    similarities: SimilaritySets = ["colour+texture+size+fill", "texture+size+fill"],  # noqa: B006
    scales: PositiveList = [50.0],  # noqa: B006
    sigma: Annotated[float, Field(ge=0)] = 0.8,
    max_area: Annotated[float, Field(gt=0, le=1)] = 0.5,
    max_boxes: Annotated[int, Field(ge=0)] | None = None,
    seed: Seed = 0,
) -> Detections:
    """Selective search on every scene (``detection.selective_search`` with these
    parameters, ranked by persistence); label -1 (no class yet).

    Parameters
    ----------
    scenes : Scenes
        Gray scenes.
    colour_spaces : list of {'rgb', 'hsv', 'lab', 'gray'}
        Colour spaces of the strategies.
    similarities : list of str
        Similarity sets (measures among colour, texture, size, fill joined by '+').
    scales : list of float
        Felzenszwalb's k of each over-segmentation.
    sigma : float
        Smoothing before the over-segmentation.
    max_area : float
        Proposals covering more than this fraction of a scene are dropped.
    max_boxes : int, optional
        Most proposals per scene (0: all). None: one per ``PIXELS_PER_PROPOSAL``
        (32) pixels of the scene, so that a larger scene, which holds more objects,
        keeps more (a fixed 200 kept 0.925 of 30 digits in 240 × 240 scenes where all
        the proposals, about 470, keep 0.95).
    seed : int
        Seed of the ranking.

    Returns
    -------
    Detections
        Proposals of all scenes, each with its scene index.
    """
    from ._proposals import propose

    pieces = []
    for index, image in enumerate(scenes.images):
        boxes = propose(
            image,
            colour_spaces=colour_spaces,
            similarities=similarities,
            scales=scales,
            sigma=sigma,
            max_area=max_area,
            max_boxes=image.size // PIXELS_PER_PROPOSAL if max_boxes is None else max_boxes,
            seed=seed,
        )
        pieces.append((boxes.xyxy, boxes.score, np.full(len(boxes), index, np.int64)))
    xyxy = np.concatenate([p[0] for p in pieces]).reshape(-1, 4)
    score = np.concatenate([p[1] for p in pieces])
    owner = np.concatenate([p[2] for p in pieces])
    return DetectionSet(xyxy, score, np.full(len(xyxy), BACKGROUND, np.int64), owner, len(scenes))


class TrainingRois(NamedTuple):
    """ROIs to learn from: scene ``owner``, box ``xyxy``, ``label`` (-1: background) and the
    true box each positive should move to, ``target`` (its own box for background)."""

    owner: np.ndarray
    xyxy: np.ndarray
    label: np.ndarray
    target: np.ndarray


def training_rois(
    scenes: SceneSet,
    proposals: DetectionSet,
    *,
    positive_iou: float,
    negative_iou: float,
    jitter: int,
    negatives_per_positive: float,
    seed: int,
) -> TrainingRois:
    """The proposals, the true boxes and ``jitter`` seeded jittered copies of each (shifted
    and scaled by up to 15 % of its size, kept inside the scene), labelled by overlap:
    the class of the best-overlapping true box at IoU ≥ ``positive_iou``, background below
    ``negative_iou`` (a seeded subset of at most ``negatives_per_positive`` per positive),
    the rest left out."""
    rng = np.random.default_rng(seed)
    height, width = scenes.images.shape[1:]
    extra_owner = np.repeat(scenes.owner, jitter + 1)
    base = np.repeat(scenes.xyxy, jitter + 1, axis=0)
    size = np.tile(base[:, 2:] - base[:, :2], 2)
    noise = rng.uniform(-0.15, 0.15, base.shape) * size
    noise[:: jitter + 1] = 0  # the true box itself
    jittered = base + noise
    jittered[:, [0, 2]] = np.clip(jittered[:, [0, 2]], 0, width)
    jittered[:, [1, 3]] = np.clip(jittered[:, [1, 3]], 0, height)
    valid = (jittered[:, 2] - jittered[:, 0] >= 2) & (jittered[:, 3] - jittered[:, 1] >= 2)
    owner = np.concatenate([proposals.owner, extra_owner[valid]])
    xyxy = np.concatenate([proposals.xyxy, jittered[valid]])
    label = np.full(len(xyxy), -2, np.int64)  # -2: left out
    target = xyxy.copy()
    for scene in range(len(scenes)):
        mine = np.flatnonzero(owner == scene)
        truth, classes = scenes.boxes_of(scene)
        if len(mine) == 0:
            continue
        if len(truth) == 0:
            label[mine] = BACKGROUND
            continue
        overlap = iou_matrix(xyxy[mine], truth)
        best = overlap.argmax(axis=1)
        best_iou = overlap.max(axis=1)
        positive = best_iou >= positive_iou
        label[mine[positive]] = classes[best[positive]]
        target[mine[positive]] = truth[best[positive]]
        label[mine[best_iou < negative_iou]] = BACKGROUND
    negatives = np.flatnonzero(label == BACKGROUND)
    allowed = int(np.ceil(negatives_per_positive * max(int(np.sum(label >= 0)), 1)))
    if len(negatives) > allowed:
        label[rng.choice(negatives, len(negatives) - allowed, replace=False)] = -2
    kept = label >= BACKGROUND
    return TrainingRois(owner[kept], xyxy[kept], label[kept], target[kept])


def _crop(image: np.ndarray, box: np.ndarray, size: int) -> np.ndarray:
    """The box of the image warped to ``size`` × ``size`` by bilinear sampling at the
    centres of the output pixels."""
    from scipy import ndimage as ndi

    x0, y0, x1, y1 = box
    steps = (np.arange(size) + 0.5) / size
    ys = y0 + steps * (y1 - y0) - 0.5
    xs = x0 + steps * (x1 - x0) - 0.5
    grid = np.meshgrid(ys, xs, indexing="ij")
    return ndi.map_coordinates(image, grid, order=1, mode="nearest")


class _RoiOptions(NamedTuple):
    positive_iou: float
    negative_iou: float
    jitter: int
    negatives_per_positive: float
    seed: int


def iou_order(**params: Any) -> None:
    """Training parameters valid together: background below ``negative_iou`` cannot
    overlap objects more than ``positive_iou`` does."""
    if params["negative_iou"] > params["positive_iou"]:
        raise ValueError(
            f"negative_iou {params['negative_iou']} must not exceed positive_iou"
            f" {params['positive_iou']}"
        )


@node("detection.roi_samples", version=1, check=iou_order)
def roi_samples(
    scenes: Scenes,
    proposals: Detections,
    *,
    size: Annotated[int, Field(ge=4, le=64)] = 20,
    positive_iou: Annotated[float, Field(gt=0, le=1)] = 0.5,
    negative_iou: Fraction = 0.3,
    jitter: Annotated[int, Field(ge=0, le=32)] = 4,
    negatives_per_positive: Positive = 2.0,
    seed: Seed = 0,
) -> Samples:
    """Training crops for a CNN as in R-CNN: proposals, true boxes and jittered true boxes
    warped to ``size`` × ``size``, labelled with the class of the true box they overlap by
    IoU ≥ ``positive_iou``, or -1 (background) below ``negative_iou``.

    Parameters
    ----------
    scenes : Scenes
        Training scenes with their true boxes.
    proposals : Detections
        Proposals of those scenes.
    size : int
        Side of the warped crops (4 to 64: thousands of crops are made).
    positive_iou : float
        Overlap from which a crop takes the class of its true box.
    negative_iou : float
        Overlap below which a crop is background.
    jitter : int
        Jittered copies of each true box added.
    negatives_per_positive : float
        Most background crops per object crop (a seeded subset).
    seed : int
        Seed of the jitter and of the background subset.

    Returns
    -------
    Samples
        Crops (N, size, size) and labels (-1 background, else the class).

    References
    ----------
    R. Girshick et al., "Rich feature hierarchies for accurate object detection and
    semantic segmentation", CVPR 2014, section 2.3.
    """
    rois = training_rois(
        scenes,
        proposals,
        positive_iou=positive_iou,
        negative_iou=negative_iou,
        jitter=jitter,
        negatives_per_positive=negatives_per_positive,
        seed=seed,
    )
    crops = np.array(
        [_crop(scenes.images[o], box, size) for o, box in zip(rois.owner, rois.xyxy, strict=True)],
        np.float32,
    ).reshape(-1, size, size)
    return SampleSet(np.clip(crops, 0, 1), rois.label.astype(np.int64))
