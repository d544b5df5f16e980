"""Filtering and noise (seed: "Image processing 2").

Linear filters (correlation, convolution, Gaussian, box, sharpening) with the
course's boundary conditions, and the median filter. Noise models are in the
``synthetic`` family.
"""

from ._boundary import BOUNDARIES, Boundary
from ._linear import (
    box,
    box_kernel,
    convolve,
    correlate,
    gaussian,
    gaussian_kernel,
    gaussian_kernel_1d,
    sharpen,
    to_image,
)
from ._median import median

__all__ = [
    "BOUNDARIES",
    "Boundary",
    "box",
    "box_kernel",
    "convolve",
    "correlate",
    "gaussian",
    "gaussian_kernel",
    "gaussian_kernel_1d",
    "median",
    "sharpen",
    "to_image",
]
