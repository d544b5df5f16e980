"""Lowe's difference-of-Gaussian pyramid and its keypoints: the Gaussian scale space made with
the compiled separable Gaussian (incremental sigmas), its differences, and the search,
refinement and tests of each octave's extrema in one compiled pass (:mod:`._dog_kernels`)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from graphvision import KeypointSet

from ..shared.separable import gaussian_taps, smooth_gaussian

__all__ = [
    "SiftParams",
    "detect_dog",
]


BORDER = 5


@dataclass(frozen=True)
class SiftParams:
    """Lowe's parameters (defaults as in the paper and OpenCV)."""

    intervals: int = 3
    sigma: float = 1.6
    contrast_threshold: float = 0.04
    edge_ratio: float = 10.0
    upsample: bool = True
    max_keypoints: int = 0


@dataclass
class _Pyramid:
    gaussians: list[np.ndarray]  # per octave: (intervals + 3, H, W) float32
    dogs: list[np.ndarray]  # per octave: (intervals + 2, H, W) float32
    factor: float  # input pixels per octave-0 pixel (0.5 when upsampled)
    shift: float  # input coordinate of octave-0 pixel 0 (-0.25 when upsampled)
    params: SiftParams
    # (octave, layer) -> (magnitude, angle, done): gradients filled on demand by the kernels
    gradients: dict = field(default_factory=dict)

    def layer_sigma(self, layer: np.ndarray) -> np.ndarray:
        """Blur, in octave pixels, of the (fractional) layer."""
        return self.params.sigma * 2.0 ** (layer / self.params.intervals)


@functools.lru_cache(maxsize=64)
def _reflected(length: int, half: int) -> np.ndarray:
    """Source index of each position of a line of ``length`` padded by ``half`` (reflect)."""
    return np.pad(np.arange(length, dtype=np.int64), half, mode="symmetric")


def _blur_stack(stack: np.ndarray, steps: list[float]) -> None:
    """``stack[i] = smooth_gaussian(stack[i - 1], steps[i - 1], truncate=3.0)``, in place.

    The same compiled separable kernel writing straight into the octave's stack
    (no temporary level and copy), the boundary indices made once per size.
    """
    from ..shared.separable_kernels import correlate_both

    rows, cols = stack.shape[1:]
    for i, step in enumerate(steps, start=1):
        taps = gaussian_taps(step, 3.0).astype(np.float32)
        half = taps.size // 2
        correlate_both(
            stack[i - 1], taps, 1, _reflected(rows, half), taps, 1, _reflected(cols, half), stack[i]
        )


def _pyramid(image: np.ndarray, params: SiftParams) -> _Pyramid:
    from ._dog_kernels import upsample_twice

    base = np.ascontiguousarray(image, np.float32)
    assumed = 0.5
    factor = 1.0
    shift = 0.0
    if params.upsample:
        # pixel centres: up-sampled pixel j sits at input coordinate j / 2 - 1/4
        base = upsample_twice(base)  # = ndi.zoom(base, 2, order=1, grid_mode=True, mode="nearest")
        assumed, factor, shift = 1.0, 0.5, -0.25
    base = smooth_gaussian(base, math.sqrt(max(params.sigma**2 - assumed**2, 0.01)))
    s = params.intervals
    octaves = max(1, int(math.log2(min(base.shape))) - 3)
    totals = [params.sigma * 2.0 ** (i / s) for i in range(s + 3)]
    steps = [math.sqrt(totals[i] ** 2 - totals[i - 1] ** 2) for i in range(1, s + 3)]
    gaussians, dogs = [], []
    for _ in range(octaves):
        stack = np.empty((s + 3, *base.shape), np.float32)
        stack[0] = base
        _blur_stack(stack, steps)
        gaussians.append(stack)
        dogs.append(np.diff(stack, axis=0))
        base = stack[s][::2, ::2]
        if min(base.shape) < 2 * BORDER + 4:
            break
    return _Pyramid(gaussians, dogs, factor, shift, params)


def detect_dog(
    image: np.ndarray, params: SiftParams = SiftParams()
) -> tuple[KeypointSet, _Pyramid, np.ndarray]:
    """DoG keypoints (without orientation) and the pyramid they were found in.

    Returns the keypoints in input coordinates, the pyramid, and for each
    keypoint its (octave, layer, x, y) in octave coordinates.
    """

    from ._dog_kernels import octave_keypoints

    pyramid = _pyramid(image, params)
    s = params.intervals
    prefilter = 0.5 * params.contrast_threshold / s
    found = []
    for octave, dog in enumerate(pyramid.dogs):
        rows = octave_keypoints(
            dog, prefilter, params.contrast_threshold / s, params.edge_ratio, s, BORDER
        )
        found.append(np.column_stack([np.full(len(rows), octave), rows]))
    table = np.vstack(found) if found else np.zeros((0, 5))
    if params.max_keypoints and len(table) > params.max_keypoints:
        table = table[np.argsort(-table[:, 4], kind="stable")[: params.max_keypoints]]
    octaves, layer, ox, oy, response = table.T
    scale_to_input = pyramid.factor * 2.0**octaves
    keypoints = KeypointSet(
        np.column_stack([ox * scale_to_input, oy * scale_to_input]) + pyramid.shift,
        pyramid.layer_sigma(layer) * scale_to_input,
        np.zeros(len(table)),
        response.astype(np.float64),
    )
    return keypoints, pyramid, table[:, :4]
