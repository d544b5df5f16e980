"""Image formation (seed: "Image formation", "Color perception"): field of view, thin-lens
focus and depth of field, defocus blur from a depth map, vignetting (model, synthesis,
flat-field estimation and correction), Bayer mosaics and demosaicking.
"""

from ._bayer import bayer_masks, demosaic, mosaic
from ._optics import (
    circle_of_confusion,
    defocus,
    depth_of_field,
    field_of_view,
    focus_distance,
)
from ._vignetting import (
    correct_vignetting,
    draw_vignetting,
    estimate_vignetting,
    vignette,
    vignetting_field,
)

__all__ = [
    "bayer_masks",
    "circle_of_confusion",
    "correct_vignetting",
    "defocus",
    "demosaic",
    "depth_of_field",
    "draw_vignetting",
    "estimate_vignetting",
    "field_of_view",
    "focus_distance",
    "mosaic",
    "vignette",
    "vignetting_field",
]
