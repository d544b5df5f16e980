"""Face detectors measured on scenes with known faces (``synthetic.face_scenes``): each
detector runs on every scene, its boxes are matched to the true faces as PASCAL VOC
matches them, and recall, false positives per image and the IoU of the found faces
come out, with a picture.

::

    SceneImages  N equally sized gray scenes, float32 (N, H, W) in [0, 1]
    SceneBoxes   xyxy (M, 4) float64, score (M,), owner (M,) int64 scene index,
                 scenes (how many scenes): the boxes found in the scenes, or their
                 true faces (score 1)

The types live here, below the synthetic family (which makes scenes of them), so that
no family imports one that imports it back.
"""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import ColorImage, Float, Table, node

from ..shared.boxes import iou_matrix, non_max_suppression
from ..shared.checks import ordered
from ..shared.draw import colour_canvas
from ..shared.params import Count, Fraction, ScaleFactor
from ._group_rectangles import group_rectangles
from ._lbp_cascade import MAX_SIDE, Neighbours, ScaleStep, ScanStep, WindowSide, detect_lbp
from ._lbp_model import LBPCascade
from ._models import Classifier
from ._scenes import SceneBoxes, SceneBoxSet, SceneImages
from ._windows import sliding_windows

__all__ = [
    "FaceScores",
    "detect_scenes",
    "draw_scenes",
    "face_scores",
    "lbp_detect_scenes",
    "match_faces",
]

TRUE_COLOUR = (0.1, 0.9, 0.1)
FOUND_COLOUR = (0.95, 0.15, 0.1)


def _per_scene(found: list[tuple[np.ndarray, np.ndarray]]) -> SceneBoxSet:
    owner = np.concatenate([np.full(len(b), i, np.int64) for i, (b, _) in enumerate(found)])
    return SceneBoxSet(
        np.concatenate([b for b, _ in found]).reshape(-1, 4).astype(np.float64),
        np.concatenate([s for _, s in found]).astype(np.float64),
        owner,
        len(found),
    )


@node("recognition.lbp_detect_scenes", version=1, check=ordered(("min_size", "max_size")))
def lbp_detect_scenes(
    images: SceneImages,
    cascade: LBPCascade,
    *,
    scale_factor: ScaleStep = 1.1,
    step: ScanStep = 1,
    min_size: WindowSide = 24.0,
    max_size: WindowSide = float(MAX_SIDE),
    min_neighbours: Neighbours = 8,
    eps: Fraction = 0.2,
) -> SceneBoxes:
    """``recognition.lbp_detect`` on every scene of a set: a cascade of multi-block LBP
    stumps with early rejection, over positions and scales, then OpenCV's grouping.

    Parameters
    ----------
    images : SceneImages
        Gray scenes (``synthetic.face_scenes``).
    cascade : LBPCascade
        A trained cascade (``recognition.lbp_cascade``).
    scale_factor, step, min_size, max_size, min_neighbours, eps
        As ``recognition.lbp_detect``.

    Returns
    -------
    SceneBoxes
        Each scene's groups, scored by their number of windows.

    References
    ----------
    P. Viola and M. Jones, CVPR 2001; S. Liao et al., "Learning multi-scale block local
    binary patterns for face recognition", ICB 2007.
    """
    found = []
    for image in images:
        boxes = detect_lbp(
            image,
            cascade,
            scale_factor=scale_factor,
            step=step,
            min_size=min_size,
            max_size=max_size,
            min_neighbours=min_neighbours,
            eps=eps,
        )
        found.append((boxes.xyxy, boxes.score))
    return _per_scene(found)


@node("recognition.detect_scenes", version=1, check=ordered(("min_scale", "max_scale")))
def detect_scenes(
    images: SceneImages,
    classifier: Classifier,
    *,
    scale_step: Annotated[float, Field(gt=1, le=4)] = 1.2,
    min_scale: ScaleFactor = 1.0,
    max_scale: ScaleFactor = 64.0,
    step: Count = 3,
    threshold: float = 0.0,
    min_neighbours: Neighbours = 0,
    iou: Fraction = 0.2,
) -> SceneBoxes:
    """``recognition.detect`` on every scene of a set: the windows a trained classifier
    accepts over positions and a pyramid of scales (a cascade of Haar-like stumps stage
    by stage with early rejection), then either non-maximum suppression at ``iou``
    (``min_neighbours`` 0) or, as Viola and Jones merge overlapping detections,
    OpenCV's grouping: groups of more than ``min_neighbours`` windows become their
    mean box (see ``recognition.lbp_detect``).

    Parameters
    ----------
    images : SceneImages
        Gray scenes (``synthetic.face_scenes``).
    classifier : Classifier
        Two-class classifier trained on window features (``recognition.cascade`` over
        ``recognition.haar``, or a linear SVM over ``recognition.hog``).
    scale_step, min_scale, max_scale, step, threshold
        As ``recognition.detect``.
    min_neighbours : int
        0 for NMS, else the windows a group needs more than.
    iou : float
        Overlap above which NMS drops the weaker box (with ``min_neighbours`` 0), or
        the grouping's relative tolerance.

    Returns
    -------
    SceneBoxes
        Each scene's boxes, scored by the decision value (NMS) or their number of
        windows (grouping).

    References
    ----------
    P. Viola and M. Jones, "Robust real-time face detection", IJCV 57(2), 2004.
    """
    found = []
    for image in images:
        boxes, score = sliding_windows(
            image, classifier, scale_step, min_scale, max_scale, step, threshold
        )
        if min_neighbours:
            found.append(group_rectangles(boxes, min_neighbours, iou))
        else:
            keep = non_max_suppression(boxes, score, iou)
            found.append((boxes[keep], score[keep]))
    return _per_scene(found)


def match_faces(
    found: SceneBoxSet, truth: SceneBoxSet, iou: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """PASCAL matching, scene by scene: boxes taken best score first each claim the
    unclaimed true face they overlap most if that IoU reaches ``iou``. Returns per box
    whether it is a true positive and its IoU with the face it claimed (0 otherwise),
    and per true face whether it was found."""
    if found.scenes != truth.scenes:
        raise ValueError(
            f"the boxes were found in {found.scenes} scenes but the truth covers "
            f"{truth.scenes} scenes"
        )
    hit = np.zeros(len(found), bool)
    overlap = np.zeros(len(found))
    claimed = np.zeros(len(truth), bool)
    for index in np.argsort(-found.score, kind="stable"):
        faces = np.flatnonzero(truth.owner == found.owner[index])
        if len(faces) == 0:
            continue
        ious = iou_matrix(found.xyxy[index : index + 1], truth.xyxy[faces])[0]
        ious[claimed[faces]] = -1.0
        best = int(np.argmax(ious))
        if ious[best] >= iou:
            claimed[faces[best]] = True
            hit[index] = True
            overlap[index] = ious[best]
    return hit, overlap, claimed


class FaceScores(NamedTuple):
    recall: Float
    false_positives: Float
    face_iou: Float
    table: Table


@node("recognition.face_scores", version=1)
def face_scores(
    found: SceneBoxes, truth: SceneBoxes, *, iou: Annotated[float, Field(gt=0, le=1)] = 0.5
) -> FaceScores:
    r"""A face detector against the true faces of its scenes: a box is a true positive
    when it claims an unclaimed true face at IoU ≥ ``iou`` (boxes taken best score
    first, as PASCAL VOC matches them), otherwise a false positive.

    .. math:: \mathrm{recall} = \frac{TP}{\#\,\mathrm{faces}}, \qquad
              \mathrm{FP/image} = \frac{FP}{\#\,\mathrm{scenes}}, \qquad
              \mathrm{face\_iou} = \frac{1}{TP}\sum_{TP} \mathrm{IoU}

    Parameters
    ----------
    found : SceneBoxes
        The detector's boxes in each scene.
    truth : SceneBoxes
        The true faces of the same scenes (``synthetic.face_scenes``).
    iou : float
        Overlap of a true positive (0.5: PASCAL's criterion).

    Returns
    -------
    recall : float
        Share of the true faces found, in [0, 1].
    false_positives : float
        False positives per scene.
    face_iou : float
        Mean IoU of the true positives with their faces (NaN when none).
    table : Table
        Per scene: scene, faces, found, false_positives, mean_iou (NaN when none found).

    References
    ----------
    M. Everingham, L. Van Gool, C. K. I. Williams, J. Winn and A. Zisserman, "The PASCAL
    visual object classes (VOC) challenge", IJCV 88(2), 2010.
    """
    if len(truth) == 0:
        raise ValueError("the scenes hold no true face: recall is undefined")
    hit, overlap, claimed = match_faces(found, truth, iou)
    count = truth.scenes
    faces = np.bincount(truth.owner, minlength=count)
    found_faces = np.bincount(truth.owner[claimed], minlength=count)
    false = np.bincount(found.owner[~hit], minlength=count)
    iou_sum = np.bincount(found.owner[hit], weights=overlap[hit], minlength=count)
    hits = np.bincount(found.owner[hit], minlength=count)
    mean_iou = np.divide(iou_sum, hits, out=np.full(count, np.nan), where=hits > 0)
    table = {
        "scene": np.arange(count, dtype=np.int64),
        "faces": faces.astype(np.int64),
        "found": found_faces.astype(np.int64),
        "false_positives": false.astype(np.int64),
        "mean_iou": mean_iou,
    }
    return FaceScores(
        float(claimed.mean()),
        float((~hit).sum() / count),
        float(overlap[hit].mean()) if hit.any() else float("nan"),
        table,
    )


@node("recognition.draw_scenes", version=1)
def draw_scenes(
    images: SceneImages,
    truth: SceneBoxes,
    found: SceneBoxes,
    *,
    count: Count = 6,
    columns: Count = 3,
    size: Annotated[int, Field(ge=16, le=1024)] = 256,
) -> ColorImage:
    """The first ``count`` scenes in a grid, each reduced to ``size`` pixels a side, the
    true faces in green and the boxes found in red (drawn over the green).

    Parameters
    ----------
    images : SceneImages
        The scenes.
    truth : SceneBoxes
        Their true faces.
    found : SceneBoxes
        Boxes found in them.
    count : int
        Scenes shown.
    columns : int
        Scenes per row.
    size : int
        Side of a shown scene (its longer side), in pixels.

    Returns
    -------
    ColorImage
        The grid, scenes four white pixels apart.
    """
    from skimage.transform import resize

    for what, boxes in (("found", found), ("truth", truth)):
        if boxes.scenes != len(images):
            raise ValueError(
                f"the {what} boxes cover {boxes.scenes} scenes but {len(images)} scenes are given"
            )
    shown = min(count, len(images))
    height, width = images.shape[1:]
    scale = size / max(height, width)
    h, w = max(1, round(height * scale)), max(1, round(width * scale))
    rows = -(-shown // columns)
    gap = 4
    canvas = np.ones((rows * (h + gap) - gap, min(shown, columns) * (w + gap) - gap, 3))
    for scene in range(shown):
        small = resize(images[scene], (h, w), order=1, anti_aliasing=scale < 1)
        picture = colour_canvas(small)
        for xyxy, colour in (
            (truth.boxes_of(scene)[0], TRUE_COLOUR),
            (found.boxes_of(scene)[0], FOUND_COLOUR),
        ):
            for x0, y0, x1, y1 in np.round(xyxy * scale).astype(int):
                _rectangle(picture, x0, y0, x1, y1, colour)
        r, c = divmod(scene, columns)
        canvas[r * (h + gap) : r * (h + gap) + h, c * (w + gap) : c * (w + gap) + w] = picture
    return canvas.astype(np.float32)


def _rectangle(canvas: np.ndarray, x0: int, y0: int, x1: int, y1: int, colour: tuple) -> None:
    height, width = canvas.shape[:2]
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, width), min(y1, height)
    if x0 >= x1 or y0 >= y1:
        return
    canvas[y0 : min(y0 + 2, y1), x0:x1] = colour
    canvas[max(y1 - 2, y0) : y1, x0:x1] = colour
    canvas[y0:y1, x0 : min(x0 + 2, x1)] = colour
    canvas[y0:y1, max(x1 - 2, x0) : x1] = colour
