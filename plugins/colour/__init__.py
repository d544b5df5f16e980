"""Colour (seed: "Color"): gray and chromaticity, colour spaces, colour histograms, retrieval.

Gray as the channel mean or BT.601 luminance, and normalised rgb chromaticity;
RGB ↔ HSV, CIE L*a*b* (D65) and YCbCr with scikit-image's conventions;
joint and per-channel histograms with a chosen number of bins, normalised;
Euclidean, χ², Hellinger (Bhattacharyya) and intersection distances; a
gallery of colour samples and transformed copies ranked by histogram
distance (precision at k).

The former ``color`` family is part of this one: ``RENAMED_OPS`` maps each of
its op ids to the id it has here, so a pipeline that still uses an old id can
be told the new one.
"""

from ._histograms import (
    METRICS,
    Histogram,
    HistogramPort,
    colour_histogram,
    histogram,
    histogram_distance,
    histogram_distances,
)
from ._intensity import LUMINANCE_WEIGHTS, chromaticity, to_gray
from ._retrieval import Gallery, Retrieval, gallery, retrieve, transformed_copies
from ._spaces import SPACES, from_rgb, rgb_to, to_rgb, to_rgb_from

#: Old op id → new op id, for the ops of the former ``color`` family (issue 23).
RENAMED_OPS: dict[str, str] = {
    "color.chromaticity": "colour.chromaticity",
    "color.to_gray": "colour.to_gray",
}

__all__ = [
    "LUMINANCE_WEIGHTS",
    "METRICS",
    "RENAMED_OPS",
    "SPACES",
    "Gallery",
    "Histogram",
    "HistogramPort",
    "Retrieval",
    "chromaticity",
    "colour_histogram",
    "from_rgb",
    "gallery",
    "histogram",
    "histogram_distance",
    "histogram_distances",
    "retrieve",
    "rgb_to",
    "to_gray",
    "to_rgb",
    "to_rgb_from",
    "transformed_copies",
]
