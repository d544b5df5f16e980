"""A colour scale for disparities and depths: dark blue (near the low end) to dark red."""

from __future__ import annotations

import numpy as np

__all__ = ["colour_map"]

# Anchor colours from low to high values (dark blue → cyan → yellow → dark red), spaced evenly.
_ANCHORS = np.array(
    [
        [0.05, 0.03, 0.35],
        [0.10, 0.35, 0.90],
        [0.10, 0.80, 0.85],
        [0.55, 0.90, 0.30],
        [0.98, 0.80, 0.10],
        [0.90, 0.25, 0.05],
        [0.50, 0.02, 0.02],
    ]
)


def colour_map(
    values: np.ndarray, low: float | None = None, high: float | None = None
) -> np.ndarray:
    """Values as colours from dark blue (``low``) to dark red (``high``); NaN black.

    ``low`` and ``high`` default to the finite values' 1st and 99th percentiles.
    """
    finite = np.isfinite(values)
    rgb = np.zeros((*values.shape, 3), np.float32)
    if not finite.any():
        return rgb
    if low is None or high is None:
        p1, p99 = np.percentile(values[finite], [1, 99])
        low = float(p1) if low is None else low
        high = float(p99) if high is None else high
    span = max(high - low, 1e-12)
    t = np.clip((values[finite] - low) / span, 0.0, 1.0) * (len(_ANCHORS) - 1)
    index = np.minimum(t.astype(np.int64), len(_ANCHORS) - 2)
    fraction = (t - index)[:, None]
    rgb[finite] = (1 - fraction) * _ANCHORS[index] + fraction * _ANCHORS[index + 1]
    return rgb
