"""Thresholding (seed: "Image processing 1", "Image thresholding").

Global: manual thresholds, Otsu, Barron's generalisation of Otsu (GHT),
multi-level Otsu. Local: Niblack's ``T_W = μ_W + k σ_W`` and Sauvola's
variant, in constant time per pixel from integral images; OpenCV's adaptive
threshold, a pixel against its window's (box or Gaussian) mean minus a constant.
"""

from ._adaptive import adaptive
from ._global import ght, histogram, manual, multi_otsu, otsu, split_scores
from ._local import local, window_mean_std

__all__ = [
    "adaptive",
    "ght",
    "histogram",
    "local",
    "manual",
    "multi_otsu",
    "otsu",
    "split_scores",
    "window_mean_std",
]
