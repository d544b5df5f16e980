"""Sequential two-pass connected-component labelling with union-find (numba)."""

from __future__ import annotations

from typing import Literal

import numpy as np

from graphvision import BinaryImage, Conformance, LabelImage, node

__all__ = ["MAX_LABEL", "check_label_count", "label", "label_components", "relabel"]

MAX_LABEL = int(np.iinfo(np.int32).max)


def check_label_count(count: int) -> None:
    """Raise OverflowError when ``count`` regions cannot be held in int32 labels."""
    if count > MAX_LABEL:
        raise OverflowError(f"{count} regions do not fit in int32 labels (at most {MAX_LABEL})")


def label_components(mask: np.ndarray, *, connectivity: int = 8) -> np.ndarray:
    """Label the connected components of ``mask`` (int32, 0 = background, 1..N in raster order)."""
    from ._kernels import two_pass  # numba compiles (or loads its cache) on first use

    check_label_count(mask.size // 2 + 1)  # provisional labels are int32 too
    labels, _ = two_pass(np.ascontiguousarray(mask, dtype=np.bool_), connectivity == 8)
    return labels


@node("regions.label", version=1, conformance=Conformance("max_abs", 0.0))
def label(mask: BinaryImage, *, connectivity: Literal[4, 8] = 8) -> LabelImage:
    """Connected components by the sequential two-pass algorithm with an equivalence table.

    First pass, left to right and top to bottom: a foreground pixel with no
    labelled neighbour among those already visited (left and up; also
    up-left and up-right for 8-connectivity) gets a new label; otherwise it
    copies a neighbour's label, and when neighbours carry different labels
    they are recorded as equivalent (union-find: union by smallest label,
    path halving). Second pass: every pixel takes its class's smallest label,
    renumbered 1..N in the order regions first appear. Compiled with numba.

    Parameters
    ----------
    mask : (H, W) bool ndarray
    connectivity : {4, 8}

    Returns
    -------
    labels : (H, W) int32 ndarray, 0 = background

    Raises
    ------
    OverflowError
        When the regions do not fit in int32 labels.

    References
    ----------
    .. [1] A. Rosenfeld, J. Pfaltz, "Sequential operations in digital picture
       processing", J. ACM 13(4), 1966.
    .. [2] K. Wu, E. Otoo, K. Suzuki, "Optimizing two-pass connected-component
       labeling algorithms", Pattern Anal. Appl. 12, 2009.
    """
    return label_components(mask, connectivity=connectivity)


@node("regions.relabel", version=1)
def relabel(labels: LabelImage) -> LabelImage:
    """Renumber labels to 1..N in increasing order of the old labels (0 stays background).

    Parameters
    ----------
    labels : LabelImage
        Any labels, 0 the background.

    Returns
    -------
    labels : (H, W) int32 ndarray with consecutive labels
    """
    present = np.unique(labels)
    present = present[present != 0]
    lookup = np.zeros(int(labels.max()) + 1, dtype=np.int32)
    lookup[present] = np.arange(1, present.size + 1, dtype=np.int32)
    return lookup[labels]
