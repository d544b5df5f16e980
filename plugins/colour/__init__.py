"""Colour (seed: "Color"): colour spaces, colour histograms, their distances, retrieval.

RGB ↔ HSV, CIE L*a*b* (D65) and YCbCr with scikit-image's conventions;
joint and per-channel histograms with a chosen number of bins, normalised;
Euclidean, χ², Hellinger (Bhattacharyya) and intersection distances; a
gallery of colour samples and transformed copies ranked by histogram
distance (precision at k).
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
from ._retrieval import Gallery, Retrieval, gallery, retrieve, transformed_copies
from ._spaces import SPACES, from_rgb, rgb_to, to_rgb, to_rgb_from

__all__ = [
    "METRICS",
    "SPACES",
    "Gallery",
    "Histogram",
    "HistogramPort",
    "Retrieval",
    "colour_histogram",
    "from_rgb",
    "gallery",
    "histogram",
    "histogram_distance",
    "histogram_distances",
    "retrieve",
    "rgb_to",
    "to_rgb",
    "to_rgb_from",
    "transformed_copies",
]
