"""numba kernel of line voting (imported on first use: numba loads slowly).

Each edge point's votes go straight into the accumulator, split linearly
between the two nearest ρ bins: no ``points × θ`` temporaries.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["vote_lines"]


@numba.njit(cache=True, nogil=True)
def vote_lines(x, y, weights, first, width, cos, sin, rho0, n_rho):
    """Accumulator ``(len(cos), n_rho)``: point ``i`` votes for the ``width`` θ bins from
    ``first[i]`` (modulo the bin count) with weight ``weights[i]``; ``cos`` and ``sin`` are
    divided by the ρ step and ``rho0`` is ρ of bin 0 in steps."""
    n_theta = cos.size
    accumulator = np.zeros((n_theta, n_rho))
    for i in range(x.size):
        for k in range(width):
            t = (first[i] + k) % n_theta
            position = x[i] * cos[t] + y[i] * sin[t] - rho0
            lower = int(np.floor(position))
            frac = position - lower
            if lower >= 0 and lower + 1 < n_rho:
                accumulator[t, lower] += weights[i] * (1.0 - frac)
                accumulator[t, lower + 1] += weights[i] * frac
    return accumulator
