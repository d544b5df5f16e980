"""Erosion, dilation, opening, closing, hole filling and small-object removal."""

from __future__ import annotations

from typing import Annotated, Literal, TypeVar

import numpy as np
from pydantic import Field

from graphvision import BinaryImage, Conformance, GrayImage, node

from ..shared.params import Count
from ._footprints import Footprint
from ._packed import MAX_HALF_WIDTH, binary_extreme

__all__ = ["close", "dilate", "erode", "fill_holes", "logical", "open", "remove_small_objects"]

MaskOrGray = TypeVar("MaskOrGray", BinaryImage, GrayImage)


def _is_rectangle(footprint: np.ndarray) -> bool:
    return bool(footprint.all())


def _extreme(image: np.ndarray, footprint: np.ndarray, kind: str) -> np.ndarray:
    """Min (erosion) or max (dilation) over the footprint, centred on each pixel.

    Masks go through bit-packed rows (:mod:`._packed`). For gray images a
    full rectangle is separable: a 1-D running min/max along rows then
    columns (van Herk / Gil-Werman, O(1) per pixel); other shapes use the
    footprint directly. Outside the image counts as foreground for erosion
    and background for dilation, so the border neither eats nor grows objects.
    """
    import scipy.ndimage as ndi

    if image.dtype == np.bool_ and footprint.shape[1] // 2 <= MAX_HALF_WIDTH:
        return binary_extreme(image, footprint, erode=kind == "erode")
    boolean = image.dtype == np.bool_
    data = image.view(np.uint8) if boolean else image
    rectangle = _is_rectangle(footprint)
    if kind == "erode":
        fill = 1 if boolean else np.inf
        if rectangle:
            out = ndi.minimum_filter(data, size=footprint.shape, mode="constant", cval=fill)
        else:
            out = ndi.grey_erosion(data, footprint=footprint, mode="constant", cval=fill)
    elif rectangle:
        out = ndi.maximum_filter(data, size=footprint.shape, mode="constant", cval=0)
    else:  # scipy reflects the footprint: Minkowski addition, so closing is exact
        out = ndi.grey_dilation(data, footprint=footprint, mode="constant", cval=0)
    return out.view(np.bool_) if boolean else out


@node("morphology.erode", version=1, conformance=Conformance("max_abs", 0.0))
def erode(image: MaskOrGray, footprint: Footprint) -> MaskOrGray:
    r"""Erosion: a pixel stays foreground only where the element *fits*.

    Binary: :math:`g(x, y) = 1` if every 1 of the element lies on a 1 of
    :math:`f` when centred at :math:`(x, y)`, else 0. Gray: the minimum over
    the element. Shrinks structures, removes bridges and specks.

    Parameters
    ----------
    image : (H, W) bool or float32 ndarray
    footprint : bool ndarray with odd sides

    Returns
    -------
    eroded : same type as ``image``

    References
    ----------
    .. [1] R. C. Gonzalez, R. E. Woods, *Digital Image Processing*, 4th ed.,
       2018, section 9.2.
    """
    return _extreme(image, footprint, "erode")


@node("morphology.dilate", version=1, conformance=Conformance("max_abs", 0.0))
def dilate(image: MaskOrGray, footprint: Footprint) -> MaskOrGray:
    r"""Dilation: a pixel becomes foreground where the element *hits* :math:`f`.

    Binary: :math:`g(x, y) = 1` if any 1 of the (reflected) element lies on
    a 1 of :math:`f`; gray: the maximum. Grows structures and fills small holes.

    Parameters
    ----------
    image : (H, W) bool or float32 ndarray
        The mask (or gray image) to grow.
    footprint : bool ndarray with odd sides
        The element; it is reflected about its centre before it is applied.

    Returns
    -------
    dilated : same type as ``image``
    """
    return _extreme(image, footprint, "dilate")


@node("morphology.open", version=1, conformance=Conformance("max_abs", 0.0))
def open(image: MaskOrGray, footprint: Footprint) -> MaskOrGray:
    """Opening: erosion then dilation. Removes objects smaller than the element, keeps rough shape.

    Parameters
    ----------
    image : BinaryImage or GrayImage
        Bright structures that the element cannot fit inside are removed
        (a gray image is opened by a minimum filter, then a maximum filter).
    footprint : Footprint
        The element; its shape decides what survives.

    Returns
    -------
    opened : same type as ``image``
    """
    return _extreme(_extreme(image, footprint, "erode"), footprint, "dilate")


@node("morphology.close", version=1, conformance=Conformance("max_abs", 0.0))
def close(image: MaskOrGray, footprint: Footprint) -> MaskOrGray:
    """Closing: dilation then erosion. Fills holes and gaps smaller than the element.

    Parameters
    ----------
    image : BinaryImage or GrayImage
        Dark gaps and holes that the element cannot fit inside are filled.
    footprint : Footprint
        The element (closing with it is opening the complement).

    Returns
    -------
    closed : same type as ``image``
    """
    return _extreme(_extreme(image, footprint, "dilate"), footprint, "erode")


@node("morphology.fill_holes", version=1)
def fill_holes(
    mask: BinaryImage,
    *,
    max_area: Annotated[int, Field(ge=0)] | None = None,
    connectivity: Literal[4, 8] = 4,
) -> BinaryImage:
    """Fill the holes of the mask: background regions that do not touch the border.

    Background components are labelled (with the complement of the
    foreground's connectivity by default, 4); those not reaching the image
    border are holes. ``max_area`` fills only holes up to that many pixels.

    Parameters
    ----------
    mask : BinaryImage
        The foreground.
    max_area : int, optional
        Fill only holes of at most this many pixels (all holes when absent).
    connectivity : {4, 8}
        Connectivity of the background components.

    Returns
    -------
    filled : (H, W) bool ndarray
    """
    from ..regions import label_components

    holes = label_components(~mask, connectivity=connectivity)
    border = np.unique(np.concatenate([holes[0], holes[-1], holes[:, 0], holes[:, -1]]))
    is_hole = np.ones(int(holes.max()) + 1, dtype=bool)
    is_hole[border] = False
    is_hole[0] = False
    if max_area is not None:
        is_hole &= np.bincount(holes.ravel(), minlength=is_hole.size) <= max_area
    return mask | is_hole[holes]


@node("morphology.remove_small_objects", version=1)
def remove_small_objects(
    mask: BinaryImage,
    *,
    min_area: Count = 64,
    connectivity: Literal[4, 8] = 8,
) -> BinaryImage:
    """Drop connected components with fewer than ``min_area`` pixels.

    Parameters
    ----------
    mask : BinaryImage
        The foreground.
    min_area : int
        Components with fewer pixels are removed.
    connectivity : {4, 8}
        Connectivity of the components.

    Returns
    -------
    cleaned : (H, W) bool ndarray
    """
    from ..regions import label_components

    labels = label_components(mask, connectivity=connectivity)
    keep = np.bincount(labels.ravel()) >= min_area
    keep[0] = False
    return keep[labels]


@node("morphology.logical", version=1)
def logical(
    a: BinaryImage, b: BinaryImage, *, op: Literal["and", "or", "xor", "and_not"] = "and"
) -> BinaryImage:
    """Combine two masks pixel by pixel: ``a & b``, ``a | b``, ``a ^ b`` or ``a & ~b``.

    Parameters
    ----------
    a, b : BinaryImage
        Masks of the same shape.
    op : {"and", "or", "xor", "and_not"}
        The operation.

    Returns
    -------
    mask : (H, W) bool ndarray
    """
    if a.shape != b.shape:
        raise ValueError(f"a and b must have the same shape, got {a.shape} and {b.shape}")
    if op == "and":
        return a & b
    if op == "or":
        return a | b
    if op == "xor":
        return a ^ b
    return a & ~b
