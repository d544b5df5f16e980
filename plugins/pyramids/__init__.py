"""Pyramids and template matching (seed: "Image processing 2").

Gaussian pyramids (blur, then subsample, so what cannot be represented is
removed first), Laplacian pyramids with exact reconstruction, naive
subsampling beside them; correlation, zero-mean correlation and normalised
cross-correlation maps, peaks with sub-pixel refinement, and multi-scale
matching by scaling the image.
"""

from ._ports import ImagePyramid, Pyramid, PyramidPort
from ._pyramid import (
    blur,
    expand,
    gaussian_levels,
    gaussian_pyramid,
    laplacian_pyramid,
    mosaic,
    naive_pyramid,
    pyramid_level,
    reconstruct,
    zone_plate,
)
from ._template import (
    MatchError,
    MultiscaleMatch,
    Peaks,
    SampledTemplate,
    correlation_map,
    draw_match,
    find_peaks,
    match_error,
    match_multiscale,
    match_template,
    sample_template,
)

__all__ = [
    "ImagePyramid",
    "MatchError",
    "MultiscaleMatch",
    "Peaks",
    "Pyramid",
    "PyramidPort",
    "SampledTemplate",
    "blur",
    "correlation_map",
    "draw_match",
    "expand",
    "find_peaks",
    "gaussian_levels",
    "gaussian_pyramid",
    "laplacian_pyramid",
    "match_error",
    "match_multiscale",
    "match_template",
    "mosaic",
    "naive_pyramid",
    "pyramid_level",
    "reconstruct",
    "sample_template",
    "zone_plate",
]
