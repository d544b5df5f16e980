"""Sliding-window detection over a scale pyramid, non-maximum suppression, and drawings
(seed: "use a sliding window, extract HOG and classify by linear SVM", "Issues with
sliding window object detection")."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated, NamedTuple

import numpy as np
from pydantic import AfterValidator, Field

from graphvision import (
    Boxes,
    BoxSet,
    ColorImage,
    Float,
    GrayImage,
    Image,
    Int,
    node,
)

from ..shared.boxes import iou_matrix, non_max_suppression
from ..shared.checks import ordered
from ..shared.draw import colour_canvas
from ..shared.params import Count, Fraction, Positive, ScaleFactor
from ._data import NON_FACE, FaceFree, face_free_image, pixel_features
from ._haar import (
    SIGMA_FLOOR,
    haar_corners,
    haar_values,
    integral_image,
    normalised_values,
    sample_haar_features,
    signed_areas,
    window_moments,
)
from ._hog import hog_blocks
from ._subspace import reconstruction_error
from ._types import (
    CascadeModel,
    Classifier,
    ClassifierModel,
    Samples,
    SampleSet,
    Subspace,
    SubspaceModel,
    recipe_of,
)

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
    "window_features",
]

HARD_NEGATIVE_SOURCES: tuple[FaceFree, ...] = (
    "brick", "coffee", "coins", "grass", "gravel", "hubble_deep_field",
    "immunohistochemistry", "moon", "page", "rocket", "text",
)  # fmt: skip
"""Face-free built-in images searched for hard negatives (no person in any of them)."""


class Windows(NamedTuple):
    """Feature rows of windows at one scale and their boxes (x0, y0, x1, y1) in that scale."""

    features: np.ndarray
    boxes: np.ndarray


def _hog_windows(image: np.ndarray, recipe: dict, step: int) -> Iterator[Windows]:
    from numpy.lib.stride_tricks import sliding_window_view

    cell = tuple(recipe["pixels_per_cell"])
    block = tuple(recipe["cells_per_block"])
    window = recipe["window"]
    cells = (window[0] // cell[0], window[1] // cell[1])
    span = (cells[0] - block[0] + 1, cells[1] - block[1] + 1)  # blocks per window
    for dy in range(0, cell[0], step):
        for dx in range(0, cell[1], step):
            part = image[dy:, dx:]
            if part.shape[0] < window[0] or part.shape[1] < window[1]:
                continue
            blocks = hog_blocks(part, recipe["orientations"], cell, block)
            views = sliding_window_view(blocks, span, axis=(0, 1))  # (R, C, b_r, b_c, n, sr, sc)
            views = np.moveaxis(views, (-2, -1), (2, 3))  # (R, C, sr, sc, b_r, b_c, n)
            rows, cols = np.meshgrid(
                np.arange(views.shape[0]), np.arange(views.shape[1]), indexing="ij"
            )
            y0, x0 = dy + rows.ravel() * cell[0], dx + cols.ravel() * cell[1]
            boxes = np.column_stack(
                [x0, y0, x0 + cells[1] * cell[1], y0 + cells[0] * cell[0]]
            ).astype(np.float64)
            yield Windows(views.reshape(len(boxes), -1), boxes)


def _pixel_windows(image: np.ndarray, recipe: dict, step: int) -> Iterator[Windows]:
    from numpy.lib.stride_tricks import sliding_window_view

    height, width = recipe["window"]
    views = sliding_window_view(image, (height, width))[::step, ::step]
    rows, cols = np.meshgrid(np.arange(views.shape[0]), np.arange(views.shape[1]), indexing="ij")
    y0, x0 = rows.ravel() * step, cols.ravel() * step
    boxes = np.column_stack([x0, y0, x0 + width, y0 + height]).astype(np.float64)
    rows = pixel_features(views.reshape(len(boxes), height, width), recipe.get("normalise", False))
    yield Windows(rows, boxes)


def _haar_windows(image: np.ndarray, recipe: dict, step: int) -> Iterator[Windows]:
    height, width = recipe["window"]
    table = sample_haar_features(
        (height, width), recipe["count"], recipe["seed"], tuple(recipe["types"])
    )
    level = np.asarray(image, np.float64)
    padded = integral_image(level)[None]
    squared = integral_image(level**2) if recipe.get("normalise") else None
    ys = np.arange(0, image.shape[0] - height + 1, step)
    xs = np.arange(0, image.shape[1] - width + 1, step)
    for y in ys:  # one row of windows at a time keeps the memory at (columns × features)
        shifted = np.repeat(table[None], len(xs), axis=0)
        shifted[:, :, 1] += y
        shifted[:, :, 2] += xs[:, None]
        values = haar_values(padded, shifted.reshape(-1, 5)).reshape(len(xs), len(table))
        if squared is not None:
            tops = np.full(len(xs), y)
            mean, sigma = window_moments(padded[0], squared, tops, xs, (height, width))
            values = normalised_values(values, table, mean, sigma)
        boxes = np.column_stack(
            [xs, np.full(len(xs), y), xs + width, np.full(len(xs), y + height)]
        ).astype(np.float64)
        yield Windows(values, boxes)


_WINDOWS = {"hog": _hog_windows, "pixels": _pixel_windows, "haar": _haar_windows}


def window_features(image: np.ndarray, recipe: dict, step: int) -> Iterator[Windows]:
    """The features of every window of ``image`` computed as ``recipe`` says."""
    kind = recipe.get("kind")
    if kind not in _WINDOWS or "projected" in recipe:
        raise ValueError(
            f"recognition.detect cannot compute '{kind}' features on windows "
            f"(it can: {', '.join(sorted(_WINDOWS))}, not projected onto a subspace)"
        )
    return _WINDOWS[kind](image, recipe, step)


def _pyramid(
    image: np.ndarray,
    window: tuple[int, int],
    scale_step: float,
    min_scale: float,
    max_scale: float,
) -> Iterator[tuple[float, np.ndarray]]:
    from skimage.transform import rescale

    scale = min_scale
    while scale <= max_scale:
        if image.shape[0] / scale < window[0] or image.shape[1] / scale < window[1]:
            break
        level = image if scale == 1 else rescale(image, 1 / scale, anti_aliasing=scale > 1)
        yield scale, np.clip(level, 0, 1).astype(np.float32)
        scale *= scale_step


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


def _window_of(classifier: ClassifierModel | SubspaceModel) -> tuple[int, int]:
    recipe = recipe_of(classifier.recipe)
    classes = getattr(classifier, "classes", np.arange(2))  # a subspace has none
    if len(classes) != 2 or "window" not in recipe:
        raise ValueError(
            "recognition.detect needs a two-class classifier trained on window features, "
            f"got classes {classes.tolist()} and features {recipe or 'unknown'}"
        )
    return int(recipe["window"][0]), int(recipe["window"][1])


def sliding_windows(
    image: np.ndarray,
    classifier: ClassifierModel | SubspaceModel,
    scale_step: float,
    min_scale: float,
    max_scale: float,
    step: int,
    threshold: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Boxes (N, 4) in input coordinates and decision values (N,) of the windows scoring
    above ``threshold`` (see :func:`detect`)."""
    recipe = recipe_of(classifier.recipe)
    window = _window_of(classifier)
    if image.shape[0] < window[0] * min_scale or image.shape[1] < window[1] * min_scale:
        raise ValueError(
            f"the detection window {window[0]}×{window[1]} (× min_scale {min_scale:g}) is "
            f"larger than the image {image.shape[0]}×{image.shape[1]}"
        )
    found_boxes, found_scores = [], []
    early = isinstance(classifier, CascadeModel) and recipe.get("kind") == "haar"
    for scale, level in _pyramid(image, window, scale_step, min_scale, max_scale):
        scored = (
            [_haar_cascade_windows(level, classifier, recipe, step)]  # type: ignore[arg-type]
            if early
            else (
                (windows.boxes, _score(classifier, windows.features))
                for windows in window_features(level, recipe, step)
            )
        )
        for boxes, score in scored:
            keep = score > threshold
            found_boxes.append(boxes[keep] * scale)
            found_scores.append(score[keep])
    if not found_boxes:
        return np.zeros((0, 4)), np.zeros(0)
    return np.concatenate(found_boxes), np.concatenate(found_scores).astype(np.float64)


def _haar_cascade_windows(
    image: np.ndarray, model: CascadeModel, recipe: dict, step: int
) -> tuple[np.ndarray, np.ndarray]:
    """Boxes (N, 4) and decisions (N,) of every window of one level under a cascade of
    Haar-like stumps, stage by stage with early rejection: only the features its stumps
    use are computed, and only until a window fails a stage. Equal to
    ``model.decision`` of the window's Haar-like features (``_haar_windows``)."""
    from ._cascade_kernels import scan_haar_cascade

    height, width = recipe["window"]
    table = sample_haar_features(
        (height, width), recipe["count"], recipe["seed"], tuple(recipe["types"])
    )
    order = np.argsort(model.stage, kind="stable")
    level = np.asarray(image, np.float64)
    padded = integral_image(level)
    normalise = bool(recipe.get("normalise", False))
    squared = integral_image(level**2) if normalise else np.zeros((1, 1))
    used = table[model.feature[order]]
    corners, signs = haar_corners(used, padded.shape[1])
    stages = len(model.stage_threshold)
    stage_end = np.cumsum(np.bincount(model.stage, minlength=stages)).astype(np.int64)
    found, decision = scan_haar_cascade(
        padded,
        squared,
        normalise,
        SIGMA_FLOOR,
        height,
        width,
        step,
        corners,
        signs,
        signed_areas(used),
        model.threshold[order],
        model.polarity[order].astype(np.float64),
        model.alpha[order].astype(np.float64),
        stage_end,
        model.stage_threshold.astype(np.float64),
    )
    top, left = found[:, 0].astype(np.float64), found[:, 1].astype(np.float64)
    return np.column_stack([left, top, left + width, top + height]), decision


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


def _score(classifier: ClassifierModel | SubspaceModel, features: np.ndarray) -> np.ndarray:
    """The classifier's decision value, or minus the distance from the subspace."""
    if len(features) == 0:
        return np.zeros(0)
    if isinstance(classifier, SubspaceModel):
        return -reconstruction_error(features, classifier.mean, classifier.basis)
    return np.asarray(classifier.decision(features), np.float64)


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
