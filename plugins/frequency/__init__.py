"""Frequency analysis (seed: "Image processing 2", convolution and spectrum).

The 2-D DFT's magnitude, phase and log spectrum; convolution by FFT equal to
spatial convolution for every boundary; ideal and Gaussian low- and
high-pass filters in the frequency domain.
"""

from ._fourier import (
    Spectrum,
    fft_convolve,
    fft_convolve_array,
    frequency_filter,
    frequency_grid,
    spectrum,
)

__all__ = [
    "Spectrum",
    "fft_convolve",
    "fft_convolve_array",
    "frequency_filter",
    "frequency_grid",
    "spectrum",
]
