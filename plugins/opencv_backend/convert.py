"""The one place where graphvision's conventions meet OpenCV's.

=================  ===============================  ================================
what               graphvision                      OpenCV
=================  ===============================  ================================
images             float32 in [0, 1]                uint8 in [0, 255] (or float32)
colour order       RGB                              BGR
points             ``(x, y)`` float64, ``N×2``      float32, ``N×1×2``
keypoints          :class:`~graphvision.KeypointSet` ``cv2.KeyPoint`` (size = diameter)
                   (scale σ, orientation radians)   (angle degrees, clockwise in y-up)
matches            :class:`~graphvision.MatchSet`    ``cv2.DMatch`` (query, train)
borders            mirror / replicate / wrap /      BORDER_REFLECT / REPLICATE /
                   zero / crop                      WRAP (padded here) / CONSTANT /
                                                    any, then cropped
=================  ===============================  ================================

OpenCV is imported by :func:`cv`, on the first call of an implementation, never
when the plugin is discovered; without it the error names the extra to install.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from graphvision import KeypointSet, MatchSet

__all__ = [
    "EXTRA",
    "REQUIRES",
    "WHEELS",
    "board_from_cv",
    "border",
    "circles_from_cv",
    "cv",
    "disparity_from_cv",
    "filtered",
    "from_bgr",
    "from_u8",
    "keypoints_from_cv",
    "keypoints_to_cv",
    "lines_from_cv",
    "matches_from_cv",
    "points_to_cv",
    "significance",
    "to_bgr",
    "to_u8",
]

REQUIRES = ("cv2",)
EXTRA = "opencv"
WHEELS = (
    "opencv-python-headless",
    "opencv-python",
    "opencv-contrib-python-headless",
    "opencv-contrib-python",
)
"""The distributions that install ``cv2`` (the extra's first): a requirement on OpenCV's
release is one on each, since any of them may be the one installed."""

_BORDERS = {"mirror": "BORDER_REFLECT", "replicate": "BORDER_REPLICATE", "zero": "BORDER_CONSTANT"}


def cv() -> Any:
    """The ``cv2`` module, imported on first use (one thread: the engine runs nodes in
    parallel itself, and a node's result must not depend on its neighbours)."""
    try:
        import cv2
    except ImportError as error:  # pragma: no cover - the backend is chosen only when found
        raise ImportError(
            "the opencv backend needs OpenCV: pip install 'graphvision[opencv]'"
        ) from error
    if cv2.getNumThreads() != 1:
        cv2.setNumThreads(1)
    return cv2


# -- images ------------------------------------------------------------------------------


def to_u8(image: np.ndarray) -> np.ndarray:
    """A float image in [0, 1] as uint8, rounded to the nearest level (a mask: 0 / 255)."""
    if image.dtype == np.bool_:
        return image.astype(np.uint8) * 255
    return np.clip(np.rint(image * 255.0), 0, 255).astype(np.uint8)


def from_u8(image: np.ndarray) -> np.ndarray:
    """A uint8 image as float32 in [0, 1]."""
    return image.astype(np.float32) * np.float32(1.0 / 255.0)


def to_bgr(image: np.ndarray) -> np.ndarray:
    """RGB (H×W×3) as BGR; a gray image unchanged."""
    return np.ascontiguousarray(image[..., ::-1]) if image.ndim == 3 else image


def from_bgr(image: np.ndarray) -> np.ndarray:
    """BGR (H×W×3) as RGB; a gray image unchanged."""
    return to_bgr(image)


# -- borders -----------------------------------------------------------------------------


def border(boundary: str) -> int:
    """The OpenCV border flag of a boundary that has one (``wrap`` and ``crop`` are
    handled by :func:`filtered`)."""
    return int(getattr(cv(), _BORDERS.get(boundary, "BORDER_REFLECT")))


def filtered(
    image: np.ndarray,
    window: tuple[int, int],
    boundary: str,
    apply: Callable[[np.ndarray, int], np.ndarray],
) -> np.ndarray:
    """``apply(image, border_flag)`` with graphvision's boundary for a window of
    ``window = (rows, cols)`` centred at ``(rows // 2, cols // 2)``.

    ``wrap`` (which most OpenCV filters refuse) pads the image periodically with
    ``copyMakeBorder`` and crops the result; ``crop`` keeps the pixels whose
    window lies inside the image.
    """
    cv2 = cv()
    kh, kw = window
    top, left = kh // 2, kw // 2
    bottom, right = kh - 1 - top, kw - 1 - left
    data = np.ascontiguousarray(image)
    if boundary == "wrap":
        padded = cv2.copyMakeBorder(data, top, bottom, left, right, cv2.BORDER_WRAP)
        out = apply(padded, cv2.BORDER_REFLECT)
        return out[top : top + image.shape[0], left : left + image.shape[1]]
    out = apply(data, border(boundary))
    if boundary == "crop":
        return out[top : out.shape[0] - bottom, left : out.shape[1] - right]
    return out


# -- points, keypoints, matches ------------------------------------------------------------


def points_to_cv(points: np.ndarray) -> np.ndarray:
    """``N×2`` ``(x, y)`` points as OpenCV's ``N×1×2`` float32 (``float64`` kept when the
    call needs it is the caller's choice: pass ``points.astype(np.float64)``)."""
    return np.ascontiguousarray(points, dtype=np.float32).reshape(-1, 1, 2)


SIFT_SIZE_PER_SIGMA = 2.0
"""OpenCV's SIFT keypoint ``size`` is the diameter ``2 σ`` of the keypoint's scale."""


def keypoints_to_cv(keypoints: KeypointSet) -> list[Any]:
    """``KeypointSet`` as ``cv2.KeyPoint``: size = 2σ, angle in degrees, measured as
    OpenCV measures it (image axes, y down, so the same sense as ours)."""
    cv2 = cv()
    return [
        cv2.KeyPoint(
            float(x),
            float(y),
            float(SIFT_SIZE_PER_SIGMA * s),
            float(np.degrees(o) % 360.0),
            float(r),
        )
        for (x, y), s, o, r in zip(
            keypoints.xy, keypoints.scale, keypoints.orientation, keypoints.response, strict=True
        )
    ]


def keypoints_from_cv(points: Any) -> KeypointSet:
    """``cv2.KeyPoint`` list as a ``KeypointSet`` (σ = size / 2, orientation in radians)."""
    if len(points) == 0:
        return KeypointSet.empty()
    xy = np.array([p.pt for p in points], dtype=np.float64)
    scale = np.array([p.size / SIFT_SIZE_PER_SIGMA for p in points], dtype=np.float64)
    orientation = np.radians(np.array([p.angle for p in points], dtype=np.float64))
    response = np.array([p.response for p in points], dtype=np.float64)
    return KeypointSet(xy, scale, orientation, response)


def significance(
    inliers: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    fits: Callable[[np.ndarray, np.ndarray], np.ndarray],
    sample_size: int,
    max_nfa: float | None,
    what: str,
    seed: int,
) -> float:
    """log10 NFA of a model OpenCV fitted, by the reference's a-contrario test (the same
    chance rate, counts of distinct pairs, refusal above ``max_nfa``): OpenCV has none."""
    from ..fitting._ransac import model_significance, refuse_chance

    data = np.hstack([a, b])
    count = len(np.unique(data, axis=0))
    support = len(np.unique(data[inliers], axis=0)) if inliers.any() else 0
    log_nfa, alpha = model_significance(
        fits, (a, b), count, sample_size, support, max_nfa=max_nfa, seed=seed
    )
    refuse_chance(log_nfa, max_nfa, what, support, count, alpha)
    return log_nfa


def matches_from_cv(matches: Any) -> MatchSet:
    """``cv2.DMatch`` list (query = first set, train = second) as a ``MatchSet``."""
    pairs = np.array([(m.queryIdx, m.trainIdx) for m in matches], dtype=np.int64).reshape(-1, 2)
    distance = np.array([m.distance for m in matches], dtype=np.float64)
    return MatchSet(pairs, distance)


def lines_from_cv(lines: Any) -> np.ndarray:
    """``cv2.HoughLinesWithAccumulator``'s ``(ρ, θ, votes)`` (``N×1×3`` float32, or
    ``None``) as ``float64 N×3``, strongest first, ``θ ∈ [0, π)`` (OpenCV's ρ and θ are
    graphvision's: x the column, y the row, ρ signed)."""
    if lines is None:
        return np.zeros((0, 3), dtype=np.float64)
    rows = np.asarray(lines, dtype=np.float64).reshape(-1, 3)
    return rows[np.argsort(-rows[:, 2], kind="stable")]


def circles_from_cv(circles: Any) -> np.ndarray:
    """``cv2.HoughCirclesWithAccumulator``'s ``(x, y, r, votes)`` (float32, or ``None``)
    as ``float64 N×4`` (OpenCV's x, y are graphvision's: column and row of the centre)."""
    if circles is None:
        return np.zeros((0, 4), dtype=np.float64)
    return np.asarray(circles, dtype=np.float64).reshape(-1, 4)


DISPARITY_SCALE = 16
"""OpenCV's stereo matchers return disparities in fixed point, 1/16 pixel, as int16."""


def disparity_from_cv(fixed: np.ndarray, min_disparity: int, num_disparities: int) -> np.ndarray:
    """OpenCV's 1/16-pixel int16 disparity (invalid: below ``min_disparity``) as float32
    pixels, NaN where invalid or outside ``[min_disparity, min_disparity + n - 1]`` (OpenCV
    searches a range rounded up to a multiple of 16)."""
    disparity = fixed.astype(np.float32) / np.float32(DISPARITY_SCALE)
    top = min_disparity + num_disparities - 1
    disparity[(disparity < min_disparity) | (disparity > top)] = np.nan
    return disparity


def board_from_cv(points: Any, columns: int, rows: int, image: np.ndarray) -> np.ndarray:
    """``cv2.findChessboardCorners``' corners (``N×1×2`` float32, in one of the board's
    turns) as ``rows·columns × 2`` float64 in graphvision's fixed order: x along
    ``columns``, the board seen from its front, the first square dark (OpenCV may start
    at any end, and on a square board along either side)."""
    import scipy.ndimage as ndi

    from ..camera._corners import _oriented

    grid = np.asarray(points, dtype=np.float64).reshape(rows, columns, 2)
    smooth = ndi.gaussian_filter(np.asarray(image, dtype=np.float64), 1.0)
    ordered = _oriented(grid, smooth)
    return np.full((rows * columns, 2), np.nan) if ordered is None else ordered
