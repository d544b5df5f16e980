"""The windows of a sliding-window detector: feature rows of every window (HOG, pixels or
Haar-like) of each level of a scale pyramid, scored by a classifier (a Haar cascade with
early rejection), the boxes scoring above a threshold in input coordinates."""

from __future__ import annotations

from collections.abc import Iterator
from typing import NamedTuple

import numpy as np

from ._data import pixel_features
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
from ._models import CascadeModel, ClassifierModel
from ._subspace import reconstruction_error
from ._types import SubspaceModel, recipe_of

__all__ = [
    "window_features",
]


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


def _score(classifier: ClassifierModel | SubspaceModel, features: np.ndarray) -> np.ndarray:
    """The classifier's decision value, or minus the distance from the subspace."""
    if len(features) == 0:
        return np.zeros(0)
    if isinstance(classifier, SubspaceModel):
        return -reconstruction_error(features, classifier.mean, classifier.basis)
    return np.asarray(classifier.decision(features), np.float64)
