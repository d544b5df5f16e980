"""Census matching without a cost volume (block matching) or with one volume and two
sweeps (semi-global matching): the compiled row kernels of ``_match_kernels.py`` and
``_sgm_kernels.py``, equal to the volume kernels to the bit."""

from __future__ import annotations

import numpy as np

from ._cost import maximum_cost

__all__ = ["census_block_match", "census_sgm"]


def _signatures(left: np.ndarray, right: np.ndarray, window: int) -> tuple[np.ndarray, np.ndarray]:
    from ._match_kernels import census_signatures

    half = window // 2
    return census_signatures(left, half), census_signatures(right, half)


def census_block_match(
    left: np.ndarray,
    right: np.ndarray,
    d_min: int,
    count: int,
    window: int,
    block: int,
    uniqueness: float,
    subpixel: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """The left and right winner-take-all disparities of census costs summed over blocks."""
    from ._match_kernels import census_block_match as match

    outside = int(maximum_cost("census", window))
    found: tuple[np.ndarray, np.ndarray] = match(
        *_signatures(left, right, window), d_min, count, outside, block // 2, uniqueness, subpixel
    )
    return found


def census_sgm(
    left: np.ndarray,
    right: np.ndarray,
    search: tuple[int, int, int, int],
    penalties: tuple[int, int, float | None],
    paths: int,
    select: tuple[float, bool],
) -> tuple[np.ndarray, np.ndarray]:
    """The left and right disparities of census costs summed over blocks and aggregated
    along ``paths`` paths in 16-bit integers; ``search`` is ``(d_min, count, window,
    block)``, ``penalties`` are ``(P1, P2, edge)`` already
    scaled by the block's area, ``select`` is ``(uniqueness, subpixel)``."""
    from ._match_kernels import jump_penalties
    from ._sgm_kernels import census_sweep_paths

    d_min, count, window, block = search
    outside = int(maximum_cost("census", window))
    small, large, edge = penalties
    jumps = []
    for sign in (1, -1):
        steps = np.array([[0, sign], [sign, 0], [sign, sign], [sign, -sign]])[: paths // 2]
        jumps.append(
            jump_penalties(left, steps, float(small), float(large), -1.0 if edge is None else edge)
        )
    found: tuple[np.ndarray, np.ndarray] = census_sweep_paths(
        _signatures(left, right, window),
        (d_min, count, outside, block // 2),
        small,
        jumps[0],
        jumps[1],
        select,
    )
    return found
