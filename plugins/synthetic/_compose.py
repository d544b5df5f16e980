"""Composing a scene: pasting a warped picture (blended by its bilinear coverage), random
crops of photographs as background, quadrilateral masks, and occluders."""

from __future__ import annotations

import math

import numpy as np

from ._object_pose import _map, _translation
from ._object_scene_set import model_corners

__all__: list[str] = []  # its helpers are private to ``_object_scenes``


def _paste(
    canvas: np.ndarray, source: np.ndarray, h: np.ndarray, coverage: np.ndarray | None = None
) -> np.ndarray:
    """Blend ``source`` warped by ``h`` (source pixels → canvas pixels) into ``canvas`` in
    place, bilinearly, its edge weighted by its bilinear coverage; returns the coverage
    (canvas-sized, float32). ``coverage`` (the source's own alpha) defaults to ones."""
    import scipy.ndimage as ndi

    rows, cols = source.shape
    corners = _map(h, model_corners(cols, rows))
    low = np.floor(corners.min(axis=0) - 1).astype(int)
    high = np.ceil(corners.max(axis=0) + 2).astype(int)
    x0, y0 = max(low[0], 0), max(low[1], 0)
    x1, y1 = min(high[0], canvas.shape[1]), min(high[1], canvas.shape[0])
    alpha_full = np.zeros(canvas.shape, np.float32)
    if x0 >= x1 or y0 >= y1:
        return alpha_full
    ys, xs = np.mgrid[y0:y1, x0:x1].astype(np.float64)
    back = _map(np.linalg.inv(h), np.column_stack([xs.ravel(), ys.ravel()]))
    where = [back[:, 1].reshape(xs.shape), back[:, 0].reshape(xs.shape)]
    alpha_source = np.ones_like(source) if coverage is None else coverage
    alpha = ndi.map_coordinates(alpha_source, where, order=1, mode="constant", cval=0.0)
    colour = ndi.map_coordinates(source * alpha_source, where, order=1, mode="constant", cval=0.0)
    window = canvas[y0:y1, x0:x1]
    canvas[y0:y1, x0:x1] = window * (1.0 - alpha) + colour
    alpha_full[y0:y1, x0:x1] = alpha
    return alpha_full


def _random_crop(
    photographs: list[np.ndarray], side: tuple[int, int], rng: np.random.Generator
) -> np.ndarray:
    """A crop of a random photograph of ``side`` (rows, cols) or smaller when it is smaller,
    its contrast stretched to a random range inside [0, 1]."""
    photo = photographs[int(rng.integers(len(photographs)))]
    rows, cols = min(side[0], photo.shape[0]), min(side[1], photo.shape[1])
    top = int(rng.integers(0, photo.shape[0] - rows + 1))
    left = int(rng.integers(0, photo.shape[1] - cols + 1))
    crop = photo[top : top + rows, left : left + cols]
    low, high = float(crop.min()), float(crop.max())
    floor = rng.uniform(0.0, 0.3)
    span = rng.uniform(0.5, 1.0 - floor)
    return (floor + span * (crop - low) / max(high - low, 1e-6)).astype(np.float32)


def _background(
    photographs: list[np.ndarray], shape: tuple[int, int], rng: np.random.Generator
) -> np.ndarray:
    """A crop of half the scene's size of a random photograph, enlarged twice (bilinear) and
    padded by reflection when the photograph is smaller."""
    import scipy.ndimage as ndi

    crop = _random_crop(photographs, (shape[0] // 2 + 1, shape[1] // 2 + 1), rng)
    grown = ndi.zoom(crop, 2.0, order=1)[: shape[0], : shape[1]]
    pad = ((0, shape[0] - grown.shape[0]), (0, shape[1] - grown.shape[1]))
    return np.ascontiguousarray(np.pad(grown, pad, mode="reflect"), dtype=np.float32)


def _quad_mask(quad: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The pixels whose centres lie inside the convex quadrilateral (either orientation)."""
    mask = np.zeros(shape, bool)
    low = np.maximum(np.floor(quad.min(axis=0)).astype(int), 0)
    high = np.minimum(np.ceil(quad.max(axis=0)).astype(int) + 1, [shape[1], shape[0]])
    if (high <= low).any():
        return mask
    ys, xs = np.mgrid[low[1] : high[1], low[0] : high[0]]
    edges = np.roll(quad, -1, axis=0) - quad
    cross = [
        edge[0] * (ys - corner[1]) - edge[1] * (xs - corner[0])
        for corner, edge in zip(quad, edges, strict=True)
    ]
    inside = np.all([c >= 0 for c in cross], axis=0) | np.all([c <= 0 for c in cross], axis=0)
    mask[low[1] : high[1], low[0] : high[0]] = inside
    return mask


def _grow(mask: np.ndarray, margin: int) -> np.ndarray:
    """``mask`` dilated by ``margin`` pixels (a square), computed over its bounding box."""
    import scipy.ndimage as ndi

    rows, cols = np.nonzero(mask)
    grown = np.zeros_like(mask)
    if len(rows) == 0:
        return grown
    r0, r1 = max(rows.min() - margin, 0), min(rows.max() + margin + 1, mask.shape[0])
    c0, c1 = max(cols.min() - margin, 0), min(cols.max() + margin + 1, mask.shape[1])
    grown[r0:r1, c0:c1] = ndi.maximum_filter(mask[r0:r1, c0:c1], size=2 * margin + 1)
    return grown


def _occlude(
    canvas: np.ndarray,
    mask: np.ndarray,
    photographs: list[np.ndarray],
    occlusion: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Paste a rectangular crop centred on a random point of the instance's outline
    (``mask``), sized to hide a random fraction up to ``occlusion`` of it (about half the
    rectangle falls on the instance; shrunk until it hides no more than ``occlusion``);
    returns the pixels it covers."""
    import scipy.ndimage as ndi

    hidden = np.zeros(canvas.shape, bool)
    area = int(mask.sum())
    goal = rng.uniform(0.0, occlusion)
    if goal < 0.02 or area == 0:
        return hidden
    outline = np.argwhere(mask & ~ndi.minimum_filter(mask, size=3))
    y, x = outline[int(rng.integers(len(outline)))]
    side = math.sqrt(2.0 * goal * area)
    aspect = math.exp(rng.uniform(-0.5, 0.5))
    while True:
        height, width = max(int(side / aspect), 4), max(int(side * aspect), 4)
        top, left = max(y - height // 2, 0), max(x - width // 2, 0)
        bottom, right = min(top + height, canvas.shape[0]), min(left + width, canvas.shape[1])
        if mask[top:bottom, left:right].sum() <= occlusion * area or side < 8:
            break
        side *= 0.8
    patch = _random_crop(photographs, (bottom - top, right - left), rng)
    _paste(canvas, patch, _translation(left, top))
    hidden[top : top + patch.shape[0], left : left + patch.shape[1]] = True
    return hidden
