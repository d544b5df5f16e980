"""Selective search: object proposals from a hierarchical grouping of an over-segmentation
(seed: "Selective search": over-segment, merge the two most similar regions, continue
until one region remains, one box per region ever formed).

The over-segmentation is scikit-image's ``felzenszwalb`` (the graph-based method of
Felzenszwalb and Huttenlocher, in compiled code and tested there: writing our own would
add a union-find over sorted edges that it already does well). The grouping is ours:
regions carry a colour histogram (25 bins per channel), a texture histogram (gradient
orientation in 8 bins × magnitude in 10 bins per channel), a size and a bounding box;
neighbours are merged greedily by a sum of similarities (Uijlings et al., section 3):

.. math::
    s_\\mathrm{colour} = \\sum_k \\min(c_i^k, c_j^k),\\quad
    s_\\mathrm{texture} = \\sum_k \\min(t_i^k, t_j^k),\\quad
    s_\\mathrm{size} = 1 - \\frac{|r_i| + |r_j|}{|im|},\\quad
    s_\\mathrm{fill} = 1 - \\frac{|BB_{ij}| - |r_i| - |r_j|}{|im|}

The merged region's histograms are the size-weighted means of its parts. Diversified
strategies (colour spaces × similarity sets × segmentation scales) are run one after
another, and their boxes ranked in one of two ways, duplicates dropped after ranking:

* ``"persistence"`` (the default): by how long a region lasts in its hierarchy. With
  :math:`\\bar s` a similarity divided by the number of measures summed (so in [0, 1]
  for every set), region r is formed by a merge at :math:`\\bar s_\\mathrm{born}(r)` (the
  initial regions: the hierarchy's largest merge similarity, since they exist from the
  start) and absorbed at :math:`\\bar s_\\mathrm{died}(r)` (the last region: 0); its
  persistence is :math:`\\bar s_\\mathrm{born} - \\bar s_\\mathrm{died}`, the range of
  similarity over which it is a region of the grouping, as a region of an ultrametric
  contour map lives over a range of thresholds (Arbeláez et al. 2011). A region whose
  parts are alike and which is unlike everything around it, an object, lasts long;
  a patch of an object, or a union of unrelated regions, does not. Boxes are sorted by
  persistence, highest first; the score is the persistence.
* ``"paper"``: the paper's pseudo-random ranking (section 3.4), as the authors' code
  does it (``Image2HierarchicalGrouping.m``): in each hierarchy the region formed by
  the last merge has position 1, the one before 2, and so on, and the initial regions
  (counted once per segmentation) position M + 1 after M merges; each box's rank is its
  position times a seeded random number in [0, 1), sorted ascending; the score is
  minus the rank. It favours the large regions at the top of every hierarchy: on
  scenes of many objects, the first proposals miss most of them (issue 24).
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass
from typing import Literal

import numpy as np

__all__ = [
    "RANKINGS",
    "SIMILARITIES",
    "ColourSpace",
    "Hierarchy",
    "Ranking",
    "grouping_hierarchy",
    "hierarchical_grouping",
    "selective_search_boxes",
]

ColourSpace = Literal["rgb", "hsv", "lab", "gray"]
Ranking = Literal["persistence", "paper"]
RANKINGS: tuple[str, ...] = ("persistence", "paper")
SIMILARITIES = ("colour", "texture", "size", "fill")
COLOUR_BINS = 25
ORIENTATION_BINS = 8
MAGNITUDE_BINS = 10


def _channels(image: np.ndarray, space: ColourSpace) -> np.ndarray:
    """The image in ``space`` as (H, W, C) float64 with every channel scaled to [0, 1]."""
    from skimage import color

    rgb = np.repeat(image[..., None], 3, axis=2) if image.ndim == 2 else image
    rgb = rgb.astype(np.float64)
    if space == "rgb":
        return rgb
    if space == "gray":
        return rgb.mean(axis=2, keepdims=True)
    if space == "hsv":
        return color.rgb2hsv(rgb)
    lab = color.rgb2lab(rgb)
    return np.clip((lab - [0, -128, -128]) / [100, 255, 255], 0, 1)


def _histograms(labels: np.ndarray, values: np.ndarray, bins: int, count: int) -> np.ndarray:
    """Per-region histograms (count, bins) of integer bin ``values`` (H, W), L1-normalised."""
    flat = labels.ravel() * bins + values.ravel()
    hist = np.bincount(flat, minlength=count * bins).reshape(count, bins).astype(np.float64)
    return hist


def _region_features(
    labels: np.ndarray, channels: np.ndarray, count: int
) -> tuple[np.ndarray, np.ndarray]:
    """Colour (count, 25·C) and texture (count, 80·C) histograms of each region,
    L1-normalised."""
    from scipy import ndimage as ndi

    colour, texture = [], []
    for c in range(channels.shape[2]):
        channel = channels[..., c]
        level = np.minimum((channel * COLOUR_BINS).astype(np.int64), COLOUR_BINS - 1)
        colour.append(_histograms(labels, level, COLOUR_BINS, count))
        gy = ndi.gaussian_filter(channel, 1.0, order=(1, 0))
        gx = ndi.gaussian_filter(channel, 1.0, order=(0, 1))
        angle = np.mod(np.arctan2(gy, gx), 2 * np.pi)
        direction = np.minimum((angle / (2 * np.pi) * ORIENTATION_BINS).astype(np.int64), 7)
        magnitude = np.hypot(gx, gy)
        top = max(float(magnitude.max()), 1e-12)
        strength = np.minimum((magnitude / top * MAGNITUDE_BINS).astype(np.int64), 9)
        texture.append(
            _histograms(labels, direction * MAGNITUDE_BINS + strength, ORIENTATION_BINS * 10, count)
        )
    sizes = np.bincount(labels.ravel(), minlength=count).astype(np.float64)[:, None]
    return np.hstack(colour) / sizes, np.hstack(texture) / sizes


def _neighbour_pairs(labels: np.ndarray) -> np.ndarray:
    """Unique pairs (i < j) of labels that touch horizontally, vertically or diagonally."""
    pairs = [
        (labels[:, :-1], labels[:, 1:]),
        (labels[:-1, :], labels[1:, :]),
        (labels[:-1, :-1], labels[1:, 1:]),
        (labels[:-1, 1:], labels[1:, :-1]),
    ]
    a = np.concatenate([p[0].ravel() for p in pairs])
    b = np.concatenate([p[1].ravel() for p in pairs])
    differ = a != b
    both = np.sort(np.column_stack([a[differ], b[differ]]), axis=1)
    return np.unique(both, axis=0)


@dataclass
class _Regions:
    """Growing arrays of region properties (initial regions first, merged ones after)."""

    colour: list[np.ndarray]
    texture: list[np.ndarray]
    size: list[float]
    box: list[np.ndarray]


def _union(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The bounding box of two boxes (x0, y0, x1, y1)."""
    return np.concatenate([np.minimum(a[:2], b[:2]), np.maximum(a[2:], b[2:])])


def _similarity(
    regions: _Regions, i: int, j: int, measures: tuple[str, ...], image_size: float
) -> float:
    total = 0.0
    if "colour" in measures:
        total += float(np.minimum(regions.colour[i], regions.colour[j]).sum())
    if "texture" in measures:
        total += float(np.minimum(regions.texture[i], regions.texture[j]).sum())
    if "size" in measures:
        total += 1.0 - (regions.size[i] + regions.size[j]) / image_size
    if "fill" in measures:
        box = _union(regions.box[i], regions.box[j])
        box_area = float(np.prod(box[2:] - box[:2]))
        total += 1.0 - (box_area - regions.size[i] - regions.size[j]) / image_size
    return total


@dataclass(frozen=True)
class Hierarchy:
    """The regions one grouping forms: ``boxes`` (x0, y0, x1, y1) in creation order (the
    ``initial`` regions of the over-segmentation first, then one per merge) and the
    ``persistence`` of each (module docstring)."""

    boxes: np.ndarray
    persistence: np.ndarray
    initial: int


def grouping_hierarchy(
    labels: np.ndarray, channels: np.ndarray, measures: tuple[str, ...]
) -> Hierarchy:
    """Greedy grouping of an over-segmentation: merge the two most similar neighbours
    until one region remains (module docstring), recording every region's box and the
    (mean) similarities at which it is formed and absorbed."""
    count = int(labels.max()) + 1
    colour, texture = _region_features(labels, channels, count)
    rows, cols = np.indices(labels.shape)
    flat = labels.ravel()
    x0 = np.full(count, np.inf)
    y0 = np.full(count, np.inf)
    x1 = np.full(count, -np.inf)
    y1 = np.full(count, -np.inf)
    np.minimum.at(x0, flat, cols.ravel())
    np.minimum.at(y0, flat, rows.ravel())
    np.maximum.at(x1, flat, cols.ravel() + 1)
    np.maximum.at(y1, flat, rows.ravel() + 1)
    boxes = np.column_stack([x0, y0, x1, y1])
    sizes = np.bincount(flat, minlength=count).astype(np.float64)
    regions = _Regions(list(colour), list(texture), sizes.tolist(), list(boxes))
    image_size = float(labels.size)
    scale = float(len(measures))
    born = [np.nan] * count  # the initial regions': the largest merge similarity, below
    died = [0.0] * count
    neighbours: dict[int, set[int]] = {r: set() for r in range(count)}
    heap: list[tuple[float, int, int]] = []
    for i, j in _neighbour_pairs(labels).tolist():
        neighbours[i].add(j)
        neighbours[j].add(i)
        heap.append((-_similarity(regions, i, j, measures, image_size), i, j))
    heapq.heapify(heap)
    alive = set(range(count))
    while heap:
        negative, i, j = heapq.heappop(heap)
        if i not in alive or j not in alive:
            continue  # a pair whose region was merged away since it was pushed
        t = len(regions.size)
        si, sj = regions.size[i], regions.size[j]
        regions.colour.append((si * regions.colour[i] + sj * regions.colour[j]) / (si + sj))
        regions.texture.append((si * regions.texture[i] + sj * regions.texture[j]) / (si + sj))
        regions.size.append(si + sj)
        regions.box.append(_union(regions.box[i], regions.box[j]))
        born.append(-negative / scale)
        died.append(0.0)
        died[i] = died[j] = -negative / scale
        alive -= {i, j}
        around = (neighbours.pop(i) | neighbours.pop(j)) - {i, j}
        neighbours[t] = around
        for k in around:
            neighbours[k] -= {i, j}
            neighbours[k].add(t)
            heapq.heappush(heap, (-_similarity(regions, t, k, measures, image_size), k, t))
        alive.add(t)
    formed = np.array(born, np.float64)
    first = float(np.nanmax(formed)) if len(formed) > count else 1.0
    formed[:count] = first
    persistence = formed - np.array(died, np.float64)
    return Hierarchy(np.array(regions.box, np.float64).reshape(-1, 4), persistence, count)


def hierarchical_grouping(
    labels: np.ndarray, channels: np.ndarray, measures: tuple[str, ...]
) -> np.ndarray:
    """Boxes (x0, y0, x1, y1) of every region the grouping forms, in creation order: the
    initial regions, then each merge (the last is the whole connected image)."""
    return grouping_hierarchy(labels, channels, measures).boxes


def _paper_ranks(hierarchy: Hierarchy, with_initial: bool, rng: np.random.Generator) -> np.ndarray:
    """The paper's ranks of one hierarchy's boxes (module docstring); inf drops a box."""
    merges = len(hierarchy.boxes) - hierarchy.initial
    position = np.concatenate(
        [np.full(hierarchy.initial, merges + 1.0), np.arange(merges, 0, -1, dtype=np.float64)]
    )
    ranks = position * rng.random(len(position))
    if not with_initial:
        ranks[: hierarchy.initial] = np.inf  # the segmentation's regions count once
    return ranks


def selective_search_boxes(
    image: np.ndarray,
    *,
    colour_spaces: tuple[ColourSpace, ...],
    similarity_sets: tuple[tuple[str, ...], ...],
    scales: tuple[float, ...],
    sigma: float,
    seed: int,
    ranking: Ranking = "persistence",
) -> tuple[np.ndarray, np.ndarray]:
    """Boxes of every diversified strategy, ranked (module docstring) and de-duplicated,
    with their scores (higher is earlier in the ranking): ((P, 4), (P,))."""
    from skimage.segmentation import felzenszwalb

    rng = np.random.default_rng(seed)
    all_boxes, all_keys = [], []
    for space in colour_spaces:
        channels = _channels(image, space)
        for scale in scales:
            labels = felzenszwalb(channels, scale=scale, sigma=sigma, min_size=int(scale))
            for number, measures in enumerate(similarity_sets):
                hierarchy = grouping_hierarchy(labels, channels, measures)
                all_boxes.append(hierarchy.boxes)
                if ranking == "paper":
                    all_keys.append(_paper_ranks(hierarchy, number == 0, rng))
                else:
                    all_keys.append(-hierarchy.persistence)
    boxes = np.concatenate(all_boxes)
    keys = np.concatenate(all_keys)
    order = np.argsort(keys, kind="stable")
    boxes, keys = boxes[order], keys[order]
    kept = np.isfinite(keys)
    boxes, keys = boxes[kept], keys[kept]
    _, first = np.unique(boxes, axis=0, return_index=True)
    first = np.sort(first)
    return boxes[first], -keys[first]
