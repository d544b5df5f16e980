"""numba kernels of the two-pass labelling (imported on first use: numba loads slowly).

The first pass visits pixels in raster order and looks only at neighbours
already visited. For 8-connectivity it follows Wu, Otoo & Suzuki's decision
tree: when the pixel above is foreground, every other visited neighbour
touches it, so its label is copied with no union; only the up-right
neighbour meeting the up-left or left one records an equivalence.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["two_pass"]


@njit(cache=True, nogil=True, inline="always")
def _find(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]  # path halving
        i = parent[i]
    return i


@njit(cache=True, nogil=True, inline="always")
def _union(parent, a, b):
    a = _find(parent, a)
    b = _find(parent, b)
    if a < b:
        parent[b] = a
        return a
    parent[a] = b
    return b


@njit(cache=True, nogil=True)
def two_pass(mask, eight):
    """Label ``mask``; return (int32 labels numbered in raster order, region count)."""
    rows, cols = mask.shape
    labels = np.zeros((rows, cols), np.int32)
    parent = np.zeros(rows * cols // 2 + 2, np.int32)
    count = 0
    for y in range(rows):
        for x in range(cols):
            if not mask[y, x]:
                continue
            has_up = y > 0
            up = labels[y - 1, x] if has_up else 0
            if eight:
                if up:
                    current = up
                else:
                    up_right = labels[y - 1, x + 1] if has_up and x + 1 < cols else 0
                    up_left = labels[y - 1, x - 1] if has_up and x > 0 else 0
                    left = labels[y, x - 1] if x > 0 else 0
                    if up_right:
                        current = up_right
                        if up_left:
                            current = _union(parent, up_right, up_left)
                        elif left:
                            current = _union(parent, up_right, left)
                    elif up_left:
                        current = up_left
                    elif left:
                        current = left
                    else:
                        count += 1
                        parent[count] = count
                        current = count
            else:
                left = labels[y, x - 1] if x > 0 else 0
                if up and left:
                    current = up if up == left else _union(parent, up, left)
                elif up or left:
                    current = up or left
                else:
                    count += 1
                    parent[count] = count
                    current = count
            labels[y, x] = current
    # roots are the smallest label of their set: numbering roots in increasing order
    # gives consecutive labels in the raster order of each region's first pixel
    final = np.zeros(count + 1, np.int32)
    regions = 0
    for i in range(1, count + 1):
        root = _find(parent, i)
        if root == i:
            regions += 1
            final[i] = regions
        else:
            final[i] = final[root]
    for y in range(rows):
        for x in range(cols):
            labels[y, x] = final[labels[y, x]]
    return labels, regions
