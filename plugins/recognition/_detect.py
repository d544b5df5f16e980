"""Sliding-window detection over a scale pyramid, non-maximum suppression, and drawings
(seed: "use a sliding window, extract HOG and classify by linear SVM", "Issues with
sliding window object detection")."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import AfterValidator, Field

from graphvision import Boxes, BoxSet, ColorImage, Float, GrayImage, Image, Int, node

from ..shared.boxes import iou_matrix, non_max_suppression
from ..shared.checks import ordered
from ..shared.draw import colour_canvas
from ..shared.params import Count, Fraction, Positive, ScaleFactor
from ._data import NON_FACE, FaceFree, face_free_image
from ._models import Classifier
from ._types import Samples, SampleSet, Subspace, recipe_of
from ._windows import _window_of, sliding_windows

__all__ = [
    "box_count",
    "box_iou",
    "detect",
    "detect_subspace",
    "draw_boxes",
    "iou_matrix",
    "mine_negatives",
    "nms",
    "non_max_suppression",
]

HARD_NEGATIVE_SOURCES: tuple[FaceFree, ...] = (
    "brick", "coffee", "coins", "grass", "gravel", "hubble_deep_field",
    "immunohistochemistry", "moon", "page", "rocket", "text",
)  # fmt: skip
"""Face-free built-in images searched for hard negatives (no person in any of them)."""


@node("recognition.detect", version=1, check=ordered(("min_scale", "max_scale")))
def detect(
    image: GrayImage,
    classifier: Classifier,
    *,
    scale_step: Annotated[float, Field(gt=1, le=4)] = 1.2,
    min_scale: ScaleFactor = 1.0,
    max_scale: ScaleFactor = 64.0,
    step: Count = 3,
    threshold: float = 0.0,
) -> Boxes:
    """Every window the classifier accepts, over positions and a pyramid of scales.

    The image is shrunk by ``min_scale``, ``min_scale × scale_step``, ... up to
    ``max_scale``; at each level the training window slides by ``step`` pixels and
    the classifier's own features (its recipe: HOG, pixels or Haar-like) are computed
    on every window (HOG once per level and offset, Haar-like from one integral
    image, each window scaled to zero mean and unit variance when the features were).
    A cascade of Haar-like stumps runs stage by stage with early rejection: a window
    costs only the features of the stages it reaches, and its decision is the same.
    A window whose decision value exceeds ``threshold`` becomes a box in input
    coordinates scored by that value. Follow with ``recognition.nms``.

    Parameters
    ----------
    image : (H, W) gray image
    classifier : two-class Classifier trained on window features (the larger label is
        the object)
    scale_step : ratio between pyramid levels
    min_scale, max_scale : smallest and largest window scale, in multiples of the
        training window, 1/8 to 1,024 (below 1 the image is enlarged)
    step : window step in pixels of a level (HOG uses offsets 0, step, ... within a cell)
    threshold : least decision value of a detection

    Returns
    -------
    boxes : Boxes (x0, y0, x1, y1, score)

    References
    ----------
    N. Dalal and B. Triggs, CVPR 2005; P. Viola and M. Jones, IJCV 57(2), 2004.
    """
    boxes, scores = sliding_windows(
        image, classifier, scale_step, min_scale, max_scale, step, threshold
    )
    return BoxSet(boxes, scores)


@node("recognition.mine_negatives", version=1, check=ordered(("min_scale", "max_scale")))
def mine_negatives(
    classifier: Classifier,
    *,
    images: Annotated[tuple[FaceFree, ...], Field(min_length=1)] = HARD_NEGATIVE_SOURCES,
    count: Annotated[int, Field(ge=1, le=100_000)] = 400,
    scale_step: Annotated[float, Field(gt=1, le=4)] = 1.25,
    min_scale: ScaleFactor = 1.0,
    max_scale: ScaleFactor = 16.0,
    step: Count = 3,
) -> Samples:
    """Hard negatives (Dalal–Triggs): the windows of face-free images that the classifier
    scores highest, cut out and resized to its window; retraining with them removes the
    false positives a first classifier makes.

    Windows are gathered per image (at most ``count`` / images each, after NMS at IoU
    0.3 so that one false positive is not taken many times over), best first.

    Parameters
    ----------
    classifier : two-class Classifier trained on window features
    images : face-free sample images to search
    count : number of negatives returned (fewer if fewer windows exist)
    scale_step, min_scale, max_scale, step : the sliding window (see ``recognition.detect``)

    Returns
    -------
    negatives : Samples (≤ count, window), label 0
    """
    from skimage.transform import resize

    window = _window_of(classifier)
    share = -(-count // len(images))
    patches, scores = [], []
    for name in images:
        image = face_free_image(name)
        boxes, score = sliding_windows(
            image, classifier, scale_step, min_scale, max_scale, step, -np.inf
        )
        strongest = np.argsort(-score, kind="stable")[: 20 * share]
        keep = strongest[non_max_suppression(boxes[strongest], score[strongest], 0.3)[:share]]
        for (x0, y0, x1, y1), value in zip(boxes[keep], score[keep], strict=True):
            crop = image[int(y0) : int(np.ceil(y1)), int(x0) : int(np.ceil(x1))]
            patches.append(resize(crop, window, anti_aliasing=True, preserve_range=True))
            scores.append(value)
    best = np.argsort(-np.array(scores), kind="stable")[:count]
    stack = np.clip(np.stack(patches)[best], 0, 1).astype(np.float32)
    return SampleSet(stack, np.full(len(stack), NON_FACE, np.int64))


@node("recognition.detect_subspace", version=1, check=ordered(("min_scale", "max_scale")))
def detect_subspace(
    image: GrayImage,
    subspace: Subspace,
    *,
    scale_step: Annotated[float, Field(gt=1, le=4)] = 1.2,
    min_scale: ScaleFactor = 1.0,
    max_scale: ScaleFactor = 64.0,
    step: Count = 2,
    max_error: Positive = 0.2,
) -> Boxes:
    r"""Detection by distance from a subspace: windows that the subspace reconstructs well.

    Every window over positions and a scale pyramid (as ``recognition.detect``) is
    turned into the subspace's features (its recipe: pixels, normalised or not) and
    reconstructed, :math:`\hat x = U U^T (x - \mu) + \mu`; a window whose squared
    reconstruction error :math:`\|x - \hat x\|^2` is below ``max_error`` becomes a box
    scored by minus that error. Follow with ``recognition.nms``.

    Parameters
    ----------
    image : (H, W) gray image
    subspace : Subspace built on window pixels (``recognition.pixels`` → ``recognition.pca``)
    scale_step, min_scale, max_scale, step : the sliding window (see ``recognition.detect``)
    max_error : largest squared reconstruction error of a detection

    Returns
    -------
    boxes : Boxes scored by −error

    References
    ----------
    M. Turk and A. Pentland, "Eigenfaces for recognition", J. Cognitive Neuroscience
    3(1), 1991.
    """
    if recipe_of(subspace.recipe).get("kind") != "pixels":
        raise ValueError(
            "recognition.detect_subspace needs a subspace of window pixels "
            f"(recognition.pixels), got features {subspace.recipe}"
        )
    boxes, scores = sliding_windows(
        image, subspace, scale_step, min_scale, max_scale, step, -max_error
    )
    return BoxSet(boxes, scores)


@node("recognition.nms", version=1)
def nms(
    boxes: Boxes,
    *,
    iou: Fraction = 0.3,
    max_boxes: Annotated[int, Field(ge=0)] = 0,
) -> Boxes:
    """Non-maximum suppression: keep the best-scored box, drop the boxes that overlap it by
    intersection over union above ``iou``, repeat.

    Parameters
    ----------
    boxes : Boxes with scores
    iou : overlap above which the weaker box is dropped
    max_boxes : keep at most this many of the best (0: all)

    Returns
    -------
    boxes : Boxes, best first
    """
    keep = non_max_suppression(boxes.xyxy, boxes.score, iou)
    if max_boxes:
        keep = keep[:max_boxes]
    return boxes.take(keep)


@node("recognition.box_count", version=1)
def box_count(boxes: Boxes) -> Int:
    """The number of boxes.

    Parameters
    ----------
    boxes : Boxes

    Returns
    -------
    count : int
    """
    return len(boxes)


def _corners_ordered(box: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """``box`` itself when it is (x0, y0, x1, y1) with x0 < x1 and y0 < y1, else ValueError."""
    if not box[0] < box[2] or not box[1] < box[3]:
        raise ValueError(f"must be (x0, y0, x1, y1) with x0 < x1 and y0 < y1, got {list(box)}")
    return box


TrueBox = Annotated[tuple[float, float, float, float], AfterValidator(_corners_ordered)]
"""A box (x0, y0, x1, y1) with its corners in order, refused at validation otherwise."""


@node("recognition.box_iou", version=1)
def box_iou(boxes: Boxes, *, truth: TrueBox = (0.0, 0.0, 1.0, 1.0)) -> Float:
    """The best intersection over union of any box with a known box (x0, y0, x1, y1).

    Parameters
    ----------
    boxes : Boxes
    truth : the true box (x0, y0, x1, y1)

    Returns
    -------
    iou : float in [0, 1] (0 when there is no box)
    """
    if len(boxes) == 0:
        return 0.0
    return float(iou_matrix(boxes.xyxy, np.array([truth], np.float64)).max())


@node("recognition.draw_boxes", version=1)
def draw_boxes(image: Image, boxes: Boxes) -> ColorImage:
    """Each box as a rectangle, the best-scored (first after NMS) in green, the others in red.

    Parameters
    ----------
    image : gray or RGB image
    boxes : Boxes

    Returns
    -------
    image : (H, W, 3) float32
    """
    canvas = colour_canvas(image)
    height, width = canvas.shape[:2]
    best = int(np.argmax(boxes.score)) if len(boxes) else -1
    for index, box in enumerate(np.round(boxes.xyxy).astype(int)):
        colour = (0.1, 0.9, 0.1) if index == best else (0.95, 0.15, 0.1)
        x0, y0 = max(box[0], 0), max(box[1], 0)
        x1, y1 = min(box[2], width), min(box[3], height)
        if x0 >= x1 or y0 >= y1:
            continue
        thick = 2
        canvas[y0 : min(y0 + thick, y1), x0:x1] = colour
        canvas[max(y1 - thick, y0) : y1, x0:x1] = colour
        canvas[y0:y1, x0 : min(x0 + thick, x1)] = colour
        canvas[y0:y1, max(x1 - thick, x0) : x1] = colour
    return canvas.astype(np.float32)
