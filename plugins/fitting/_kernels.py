"""numba kernels of RANSAC's sampler and sample count (imported on first use: numba loads
slowly).

:func:`draw_sample` draws the same minimal samples as ``Generator.choice(count, size,
replace=False)`` (Floyd's algorithm, then a Fisher-Yates shuffle, every bounded integer
by ``Generator.integers``, which numba draws from the same bit stream), so a compiled
RANSAC loop sees, seed for seed, the samples of :func:`~.ransac`'s Python loop.
"""

from __future__ import annotations

import math

from ..shared.jit import njit

__all__ = ["draw_sample", "iterations_needed"]


@njit(cache=True, nogil=True)
def draw_sample(rng, count, out):  # pragma: no cover - compiled
    """``out[:] = rng.choice(count, size=len(out), replace=False)`` (for len(out) ≤ 200:
    NumPy's Floyd branch, which every pool of 10,000 or fewer and every small sample takes)."""
    size = out.shape[0]
    for j in range(count - size, count):
        value = rng.integers(0, j + 1)
        for k in range(j - count + size):
            if out[k] == value:
                value = j
                break
        out[j - count + size] = value
    for i in range(size - 1, 0, -1):
        k = rng.integers(0, i + 1)
        out[i], out[k] = out[k], out[i]


@njit(cache=True, nogil=True)
def iterations_needed(outlier_ratio, sample_size, confidence):  # pragma: no cover - compiled
    """:func:`~._ransac.ransac_iterations`, compiled (the same floating-point operations;
    counts beyond 10^18, which bound a loop to ``max_iterations`` anyway, are 10^18)."""
    good = (1.0 - outlier_ratio) ** float(sample_size)
    if good >= 1.0:
        return 1
    miss = math.log1p(-good)
    if miss == 0.0:
        return 10**9
    needed = math.ceil(math.log(1.0 - confidence) / miss)
    return int(needed) if needed < 1e18 else 10**18  # a bound on the loop, not a count
