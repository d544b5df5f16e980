"""Nodes for object proposals: selective search, anchors, true boxes from regions, and
the recall of proposals against true boxes."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import AfterValidator, Field

from graphvision import Boxes, BoxSet, Float, Image, Table, node

from ..shared.boxes import anchor_boxes, iou_matrix
from ..shared.params import Count, Positive, Seed
from ._selective import SIMILARITIES, ColourSpace, Ranking, selective_search_boxes

__all__ = [
    "SimilarityText",
    "anchors",
    "check_scores",
    "propose",
    "recall",
    "recall_at",
    "recall_curve",
    "region_boxes",
    "selective_search",
]


def check_scores(boxes: BoxSet, what: str) -> None:
    """ValueError naming ``what`` and the first row when a box score is NaN."""
    nan = np.isnan(boxes.score)
    if nan.any():
        raise ValueError(f"{what}: box {int(np.flatnonzero(nan)[0])} has a NaN score")


def _similarity_set(text: str) -> tuple[str, ...]:
    measures = tuple(part.strip() for part in text.split("+"))
    unknown = [m for m in measures if m not in SIMILARITIES]
    if unknown:
        raise ValueError(
            f"similarity set '{text}' names {unknown}; use measures among {list(SIMILARITIES)} "
            "joined by '+'"
        )
    return measures


def _check_similarity_text(text: str) -> str:
    """``text`` itself when it names similarity measures joined by '+', else ValueError."""
    _similarity_set(text)
    return text


SimilarityText = Annotated[str, AfterValidator(_check_similarity_text)]
"""A similarity set: measures among colour, texture, size, fill joined by '+'."""
SimilaritySets = Annotated[list[SimilarityText], Field(min_length=1)]
"""One similarity set at least."""
ColourSpaces = Annotated[list[ColourSpace], Field(min_length=1)]
"""One colour space at least."""
PositiveList = Annotated[list[Positive], Field(min_length=1)]
"""One positive number at least (Felzenszwalb scales, anchor sizes and ratios)."""
COUNTS: list[int] = [10, 20, 50, 100, 200, 500, 1000]
"""The default numbers of proposals of a recall curve."""


@node("detection.selective_search", version=2)
def selective_search(
    image: Image,
    *,
    colour_spaces: ColourSpaces = ["hsv", "lab"],  # noqa: B006 (never mutated)
    similarities: SimilaritySets = ["colour+texture+size+fill", "texture+size+fill"],  # noqa: B006
    scales: PositiveList = [100.0, 300.0],  # noqa: B006
    sigma: Annotated[float, Field(ge=0)] = 0.8,
    max_area: Annotated[float, Field(gt=0, le=1)] = 0.9,
    max_boxes: Annotated[int, Field(ge=0)] = 1000,
    ranking: Ranking = "persistence",
    seed: Seed = 0,
) -> Boxes:
    r"""Selective search: over-segment (Felzenszwalb–Huttenlocher), group the two most
    similar neighbouring regions until one remains, and give one box per region ever
    formed, over diversified strategies, ranked and de-duplicated.

    Similarities of regions i, j (each in [0, 1], summed over the chosen set):
    colour and texture histogram intersection, size ``1 - (|r_i| + |r_j|) / |im|`` and
    fill ``1 - (|BB_ij| - |r_i| - |r_j|) / |im|``. Ranking ``"persistence"`` puts
    first the regions that last longest in their grouping: with :math:`\bar s` the
    similarity over the number of measures, a region formed at
    :math:`\bar s_\mathrm{born}` (the initial regions: the largest merge similarity)
    and absorbed at :math:`\bar s_\mathrm{died}` (the last: 0) has persistence
    :math:`\bar s_\mathrm{born} - \bar s_\mathrm{died}`, its score. Ranking
    ``"paper"`` is Uijlings et al.'s: position in the hierarchy (1: the last merge; the
    initial regions after every merge) times a seeded random number, sorted ascending,
    score minus that rank. An image without structure gives no proposal.

    Parameters
    ----------
    image : Image
        Gray or colour image.
    colour_spaces : list of {'rgb', 'hsv', 'lab', 'gray'}
        Colour spaces of the histograms and of the segmentation, one strategy each.
    similarities : list of str
        Similarity sets, each measures among colour, texture, size, fill joined by '+'.
    scales : list of float
        Felzenszwalb's k (and minimum region size) for each over-segmentation.
    sigma : float
        Gaussian smoothing before the over-segmentation.
    max_area : float
        Boxes covering more than this fraction of the image (the background) are dropped.
    max_boxes : int
        Keep the first ``max_boxes`` in the ranking (0: all).
    ranking : {"persistence", "paper"}
        Order of the proposals (above; module :mod:`._selective`).
    seed : int
        Seed of the paper's random ranking.

    Returns
    -------
    Boxes
        Proposals, best ranked first.

    References
    ----------
    J. R. R. Uijlings et al., "Selective search for object recognition", IJCV 104(2),
    2013; P. F. Felzenszwalb and D. P. Huttenlocher, "Efficient graph-based image
    segmentation", IJCV 59(2), 2004; P. Arbeláez et al., "Contour detection and
    hierarchical image segmentation", IEEE TPAMI 33(5), 2011 (regions of a hierarchy
    that live over a range of thresholds).
    """
    return propose(
        image,
        colour_spaces=colour_spaces,
        similarities=similarities,
        scales=scales,
        sigma=sigma,
        max_area=max_area,
        max_boxes=max_boxes,
        seed=seed,
        ranking=ranking,
    )


def propose(
    image: np.ndarray,
    *,
    colour_spaces: list[ColourSpace],
    similarities: list[SimilarityText],
    scales: list[float],
    sigma: float,
    max_area: float,
    max_boxes: int,
    seed: int,
    ranking: Ranking = "persistence",
) -> BoxSet:
    """Selective search proposals of one image (``detection.selective_search``)."""
    sets = tuple(_similarity_set(text) for text in similarities)
    if not colour_spaces or not sets or not scales:
        raise ValueError("colour_spaces, similarities and scales must each name one at least")
    boxes, scores = selective_search_boxes(
        image,
        colour_spaces=tuple(colour_spaces),
        similarity_sets=sets,
        scales=tuple(scales),
        sigma=sigma,
        seed=seed,
        ranking=ranking,
    )
    area = np.prod(boxes[:, 2:] - boxes[:, :2], axis=1)
    keep = area <= max_area * image.shape[0] * image.shape[1]
    boxes, scores = boxes[keep], scores[keep]
    if max_boxes:
        boxes, scores = boxes[:max_boxes], scores[:max_boxes]
    return BoxSet(np.ascontiguousarray(boxes), np.ascontiguousarray(scores))


@node("detection.anchors", version=1)
def anchors(
    image: Image,
    *,
    stride: Annotated[int, Field(ge=1, le=1024)] = 16,
    sizes: PositiveList = [32.0, 64.0, 128.0],  # noqa: B006
    ratios: PositiveList = [0.5, 1.0, 2.0],  # noqa: B006
) -> Boxes:
    """Faster R-CNN's anchors over the feature map of stride ``stride`` of an image: at
    each cell centre, one box of area s² per size s and aspect ratio r = h / w.

    Parameters
    ----------
    image : Image
        The image whose feature map the anchors cover (its size matters only).
    stride : int
        Pixels per feature-map cell.
    sizes : list of float
        Anchor sides s (pixels).
    ratios : list of float
        Aspect ratios h / w.

    Returns
    -------
    Boxes
        (rows · cols · sizes · ratios) anchors, score 0.

    References
    ----------
    S. Ren et al., "Faster R-CNN", NeurIPS 2015, section 3.1.1.
    """
    rows, cols = image.shape[0] // stride, image.shape[1] // stride
    boxes = anchor_boxes(rows, cols, stride, tuple(sizes), tuple(ratios))
    return BoxSet(boxes, np.zeros(len(boxes)))


@node("detection.region_boxes", version=1)
def region_boxes(table: Table) -> Boxes:
    """The bounding boxes of a region table (``regions.describe``): ``(x_min, y_min,
    x_max + 1, y_max + 1)``, the table's inclusive pixel boxes as boxes that cover them;
    score: the region's area.

    Parameters
    ----------
    table : Table
        Columns ``x_min``, ``y_min``, ``x_max``, ``y_max`` and ``area``.

    Returns
    -------
    Boxes
        One box per region.
    """
    missing = [c for c in ("x_min", "y_min", "x_max", "y_max", "area") if c not in table]
    if missing:
        raise ValueError(f"the region table has no column {missing} (give regions.describe's)")
    xyxy = np.column_stack(
        [table["x_min"], table["y_min"], table["x_max"] + 1, table["y_max"] + 1]
    ).astype(np.float64)
    return BoxSet(xyxy.reshape(-1, 4), np.asarray(table["area"], np.float64))


def recall_at(proposals: np.ndarray, truth: np.ndarray, iou: float) -> float:
    """The fraction of true boxes matched by a proposal with IoU ≥ ``iou`` (0 without
    proposals; NaN without true boxes)."""
    if len(truth) == 0:
        return float("nan")
    if len(proposals) == 0:
        return 0.0
    return float((iou_matrix(truth, proposals).max(axis=1) >= iou).mean())


@node("detection.recall", version=1)
def recall(
    proposals: Boxes, truth: Boxes, *, iou: Annotated[float, Field(gt=0, le=1)] = 0.5
) -> Float:
    """The fraction of true boxes that some proposal overlaps by IoU ≥ ``iou``.

    Parameters
    ----------
    proposals : Boxes
        Candidate boxes.
    truth : Boxes
        True object boxes (at least one).
    iou : float
        Overlap that counts as a match (0.5: PASCAL VOC).

    Returns
    -------
    float
        Recall in [0, 1].
    """
    if len(truth) == 0:
        raise ValueError("recall needs at least one true box, got none")
    check_scores(proposals, "detection.recall: proposals")
    return recall_at(proposals.xyxy, truth.xyxy, iou)


@node("detection.recall_curve", version=1)
def recall_curve(
    proposals: Boxes,
    truth: Boxes,
    *,
    iou: Annotated[float, Field(gt=0, le=1)] = 0.5,
    counts: Annotated[list[Count], Field(min_length=1)] = COUNTS,
) -> Table:
    """Recall of the first n proposals (in their ranking) for each n of ``counts``.

    Parameters
    ----------
    proposals : Boxes
        Ranked candidate boxes (best first).
    truth : Boxes
        True object boxes.
    iou : float
        Overlap that counts as a match.
    counts : list of int
        Numbers of proposals n.

    Returns
    -------
    Table
        Columns ``proposals`` (min(n, available)) and ``recall``.
    """
    check_scores(proposals, "detection.recall_curve: proposals")
    used = np.minimum(np.asarray(counts, np.int64), len(proposals))
    values = [recall_at(proposals.xyxy[:n], truth.xyxy, iou) for n in used]
    return {"proposals": used, "recall": np.array(values)}
