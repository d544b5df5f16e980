"""Matching costs of a rectified pair over a range of disparities: the cost volume.

``volume[y, x, k]`` is the cost of matching left pixel ``(x, y)`` with right
pixel ``(x − d, y)``, ``d = d_min + k``, aggregated over a ``window × window``
block (census: the block is the transform's neighbourhood). A right pixel
outside the image gets the cost's maximum, so that a pixel near the left
border prefers any disparity that stays inside.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

__all__ = ["Cost", "cost_volume", "maximum_cost"]

Cost = Literal["census", "sad", "ssd", "zncc"]


def maximum_cost(cost: Cost, window: int) -> float:
    """The largest value of the cost: census bits; 1 for SAD and SSD of [0, 1] images; 2 for
    1 − NCC."""
    if cost == "census":
        return float(window * window - 1)
    return 2.0 if cost == "zncc" else 1.0


def _shifted(right: np.ndarray, d: int) -> tuple[np.ndarray, np.ndarray]:
    """``right`` moved ``d`` pixels to the right (column x holds right[x − d]) and the
    mask of columns that came from inside the image."""
    cols = right.shape[1]
    out = np.zeros_like(right)
    inside = np.zeros(cols, dtype=bool)
    if d >= 0:
        out[:, d:] = right[:, : cols - d] if d < cols else 0
        inside[d:] = True
    else:
        out[:, :d] = right[:, -d:]
        inside[:d] = True
    return out, inside


def _box_mean(values: np.ndarray, window: int) -> np.ndarray:
    """Mean over a ``window × window`` block per slice, edges repeated (``nearest``)."""
    from scipy import ndimage

    size = (window, window) + (1,) * (values.ndim - 2)
    out: np.ndarray = ndimage.uniform_filter(values, size=size, mode="nearest")
    return out


def cost_volume(
    left: np.ndarray, right: np.ndarray, d_min: int, count: int, cost: Cost, window: int
) -> np.ndarray:
    r"""The cost volume ``(rows, cols, count)`` of a rectified gray pair (uint16 for census,
    float32 otherwise).

    - ``census``: Hamming distance between census signatures (a bit per
      window pixel, set when darker than the centre; Zabih & Woodfill 1994):
      robust to gain and bias between the cameras.
    - ``sad``, ``ssd``: mean of :math:`|L - R_d|` or :math:`(L - R_d)^2` over the block.
    - ``zncc``: :math:`1 - \rho`, with :math:`\rho` the zero-mean normalised
      cross-correlation of the blocks (a flat block has :math:`\rho = 0`).
    """
    highest = maximum_cost(cost, window)
    if cost == "census":
        from ._kernels import census, census_costs  # numba compiles on first use

        half = window // 2
        volume: np.ndarray = census_costs(
            census(left, half, half), census(right, half, half), d_min, count, int(highest)
        )
        return volume
    volume = np.empty((*left.shape, count), dtype=np.float32)
    if cost == "zncc":
        mean_l = _box_mean(left, window)
        spread_l = np.sqrt(np.maximum(_box_mean(left * left, window) - mean_l**2, 0))
        mean_r = _box_mean(right, window)
        spread_r = np.sqrt(np.maximum(_box_mean(right * right, window) - mean_r**2, 0))
    for k in range(count):
        shifted, inside = _shifted(right, d_min + k)
        if cost == "sad":
            volume[..., k] = np.abs(left - shifted)
        elif cost == "ssd":
            volume[..., k] = (left - shifted) ** 2
        else:
            covariance = _box_mean(left * shifted, window) - mean_l * _shifted(mean_r, d_min + k)[0]
            spread = spread_l * _shifted(spread_r, d_min + k)[0]
            flat = spread < 1e-6
            rho = np.where(flat, 0.0, covariance / np.where(flat, 1.0, spread))
            volume[..., k] = 1.0 - np.clip(rho, -1.0, 1.0)
        volume[:, ~inside, k] = highest
    if cost != "zncc":
        volume = _box_mean(volume, window)
    return volume
