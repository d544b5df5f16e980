"""Morphology (seed: "Cleaning the image"): structuring elements, erosion (fit),
dilation (hit), opening, closing, on binary and gray images; hole filling,
removal of small objects, and logic between masks.
"""

from ._footprints import Footprint, FootprintPort, footprint, footprint_from_mask
from ._operators import close, dilate, erode, fill_holes, logical, open, remove_small_objects

__all__ = [
    "Footprint",
    "FootprintPort",
    "close",
    "dilate",
    "erode",
    "fill_holes",
    "footprint",
    "footprint_from_mask",
    "logical",
    "open",
    "remove_small_objects",
]
