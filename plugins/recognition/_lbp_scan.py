"""Scanning an image with an LBP cascade: the window scales, the integral image resampled
at a scale (bilinear in the exact integral: an area-averaged reduction) and the windows
the cascade accepts at each scale."""

from __future__ import annotations

import numpy as np

from ._lbp_model import LBPCascadeModel

__all__ = [
    "lbp_windows",
    "resampled_integral",
    "scan_step",
    "window_scales",
]


def window_scales(
    shape: tuple[int, int],
    window: tuple[int, int],
    scale_factor: float,
    min_size: float,
    max_size: float,
) -> np.ndarray:
    """Scales s = s0 · factor^k of the window (height, width), from the one whose larger
    side is ``min_size`` pixels, while its larger side is at most ``max_size`` and the
    window fits in the image (height, width)."""
    side = max(window)
    scales = []
    scale = min_size / side
    while (
        scale * side <= max_size + 1e-9
        and window[0] * scale <= shape[0]
        and window[1] * scale <= shape[1]
    ):
        scales.append(scale)
        scale *= scale_factor
    return np.array(scales)


def resampled_integral(padded: np.ndarray, scale: float) -> np.ndarray:
    r"""The zero-padded integral image of the image reduced by ``scale`` (area average,
    sums kept in input pixels): :math:`S_s(v, u) = F(v s, u s)`, F interpolated
    bilinearly (exact for a piecewise-constant image), float64
    (⌊H / s⌋ + 1, ⌊W / s⌋ + 1)."""
    from ._lbp_kernels import resample_integral

    return resample_integral(np.ascontiguousarray(padded, np.float64), float(scale))


def scan_step(scale: float, step: int) -> int:
    """The window step at ``scale`` in reduced pixels: ``step`` itself, or with ``step`` 0
    OpenCV's rule (``detectMultiScale``): 2 while the scale is at most 2, then 1."""
    if step:
        return step
    return 1 if scale > 2.0 else 2


def lbp_windows(
    image: np.ndarray,
    model: LBPCascadeModel,
    *,
    scale_factor: float = 1.1,
    step: int = 1,
    min_size: float = 24.0,
    max_size: float = 4096.0,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Every window of a gray image that passes all stages: boxes (N, 4) (x0, y0, x1, y1)
    in input pixels, the last stage's margin (N,), and the weak classifiers evaluated
    (see the module for the scales, :func:`scan_step` for ``step``)."""
    from ._cascade_kernels import corner_offsets
    from ._lbp_kernels import padded_integral, resample_integral, scan_level

    padded = padded_integral(np.asarray(image, np.float64))
    window = (model.height, model.width)
    boxes, margins, evaluated = [], [], 0
    stage_end = model.stage_end
    offsets: dict[int, np.ndarray] = {}
    for scale in window_scales(image.shape, window, scale_factor, min_size, max_size):
        level = padded if scale == 1 else resample_integral(padded, float(scale))
        stride = level.shape[1]
        if stride not in offsets:
            offsets[stride] = corner_offsets(model.rects, model.feature, stride)
        found, margin, count = scan_level(
            level,
            model.height,
            model.width,
            scan_step(scale, step),
            offsets[stride],
            model.subsets,
            model.leaves,
            stage_end,
            model.stage_threshold,
        )
        evaluated += count
        top, left = found[:, 0] * scale, found[:, 1] * scale
        boxes.append(
            np.column_stack([left, top, left + model.width * scale, top + model.height * scale])
        )
        margins.append(margin)
    if not boxes:
        return np.zeros((0, 4)), np.zeros(0), 0
    return np.concatenate(boxes), np.concatenate(margins), evaluated
