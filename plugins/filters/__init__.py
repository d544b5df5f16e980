"""Filtering and noise (seed: "Image processing 2").

Linear filters (correlation, convolution, Gaussian, box, sharpening) with the
course's boundary conditions, the median filter, and seeded noise models
(Gaussian, salt and pepper, impulse).
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
from ._noise import add_gaussian_noise, add_impulse_noise, add_salt_and_pepper

__all__ = [
    "BOUNDARIES",
    "Boundary",
    "add_gaussian_noise",
    "add_impulse_noise",
    "add_salt_and_pepper",
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
