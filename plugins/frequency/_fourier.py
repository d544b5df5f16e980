"""The 2-D discrete Fourier transform: spectra, convolution by FFT, frequency-domain filters."""

from __future__ import annotations

from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import FloatImage, GrayImage, Kernel, node

from ..filters import Boundary

__all__ = [
    "Spectrum",
    "fft_convolve",
    "fft_convolve_array",
    "frequency_filter",
    "frequency_grid",
    "spectrum",
]

PadMode = Literal["constant", "wrap", "edge", "symmetric"]
_PAD: dict[str, PadMode] = {
    "zero": "constant",
    "wrap": "wrap",
    "replicate": "edge",
    "mirror": "symmetric",
}


class Spectrum(NamedTuple):
    magnitude: FloatImage
    phase: FloatImage
    log_magnitude: GrayImage


@node("frequency.spectrum", version=1)
def spectrum(image: GrayImage) -> Spectrum:
    r"""The image's 2-D discrete Fourier transform: magnitude, phase and log spectrum.

    .. math:: F(u, v) = \sum_{x, y} I(x, y)\, e^{-2\pi i (ux/W + vy/H)}

    A signal is a sum of sines and cosines of various frequencies; the
    magnitude says how much of each, the phase where. Shifted so that zero
    frequency is at the centre ``(H // 2, W // 2)``. The log spectrum
    :math:`\log(1 + |F|)`, scaled to [0, 1], is the picture to look at.

    Parameters
    ----------
    image : (H, W) float32 ndarray
        The gray image.

    Returns
    -------
    magnitude : (H, W) float32, :math:`|F|`
    phase : (H, W) float32, :math:`\arg F` in radians
    log_magnitude : (H, W) float32 in [0, 1]

    References
    ----------
    .. [1] Szeliski (2022), section 3.4.
    """
    transform = np.fft.fftshift(np.fft.fft2(image.astype(np.float64)))
    magnitude = np.abs(transform)
    log_magnitude = np.log1p(magnitude)
    peak = log_magnitude.max()
    scaled = log_magnitude / peak if peak > 0 else log_magnitude
    return Spectrum(
        magnitude.astype(np.float32),
        np.angle(transform).astype(np.float32),
        scaled.astype(np.float32),
    )


def fft_convolve_array(image: np.ndarray, kernel: np.ndarray, boundary: str) -> np.ndarray:
    """Convolution of a 2-D ``image`` with ``kernel`` (centre ``(kh // 2, kw // 2)``) by FFT,
    the boundary handled by padding exactly as the spatial filter sees it."""
    kh, kw = kernel.shape
    ch, cw = kh // 2, kw // 2
    data = image.astype(np.float64)
    if boundary == "crop":
        padded = data
    else:
        padded = np.pad(data, ((ch, kh - 1 - ch), (cw, kw - 1 - cw)), mode=_PAD[boundary])
    import scipy.fft

    shape = tuple(
        scipy.fft.next_fast_len(n + k - 1, real=True)
        for n, k in zip(padded.shape, kernel.shape, strict=True)
    )
    full = scipy.fft.irfft2(scipy.fft.rfft2(padded, shape) * scipy.fft.rfft2(kernel, shape), shape)
    # full[n] = Σ_u K[u] P[n - u] (no wrap-around: the transform is at least P + K - 1 long);
    # the output pixel i reads full[i + k - 1], the valid part
    return full[kh - 1 : padded.shape[0], kw - 1 : padded.shape[1]]


@node("frequency.fft_convolve", version=1)
def fft_convolve(image: FloatImage, kernel: Kernel, *, boundary: Boundary = "mirror") -> FloatImage:
    r"""Convolution computed as a product of spectra (the convolution theorem).

    .. math:: \mathcal F(f * g) = \mathcal F(f) \odot \mathcal F(g)

    Equal to ``filters.convolve`` for every boundary (the image is padded as
    the spatial filter would see it, so the circular convolution of the DFT
    becomes the linear one); costs :math:`O(N \log N)` whatever the kernel
    size, where the spatial filter costs :math:`O(N k^2)`.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) float32 ndarray
        The image (colour channel by channel).
    kernel : (kh, kw) float64 ndarray
        The kernel, centred at ``(kh // 2, kw // 2)``.
    boundary : {"mirror", "replicate", "wrap", "zero", "crop"}
        As in ``filters.convolve``.

    Returns
    -------
    filtered : float32 ndarray

    References
    ----------
    .. [1] Szeliski (2022), section 3.4 (the convolution theorem).
    """
    if boundary == "crop" and (
        kernel.shape[0] > image.shape[0] or kernel.shape[1] > image.shape[1]
    ):
        raise ValueError(
            f"kernel {kernel.shape[0]}×{kernel.shape[1]} is larger than the image "
            f"{image.shape[0]}×{image.shape[1]}"
        )
    if image.ndim == 3:
        channels = [fft_convolve_array(image[..., c], kernel, boundary) for c in range(3)]
        return np.stack(channels, axis=-1).astype(np.float32)
    return fft_convolve_array(image, kernel, boundary).astype(np.float32)


def frequency_grid(shape: tuple[int, ...]) -> np.ndarray:
    """Radial frequency :math:`\\sqrt{u^2 + v^2}` in cycles per pixel of each DFT coefficient."""
    v = np.fft.fftfreq(shape[0])[:, None]
    u = np.fft.rfftfreq(shape[1])[None, :]
    return np.sqrt(u * u + v * v)


@node("frequency.filter", version=1)
def frequency_filter(
    image: GrayImage,
    *,
    kind: Literal["gaussian", "ideal"] = "gaussian",
    band: Literal["low", "high"] = "low",
    cutoff: Annotated[float, Field(gt=0, le=0.75)] = 0.1,
) -> FloatImage:
    r"""Low- or high-pass filtering in the frequency domain (the image taken as periodic).

    .. math:: H_\text{ideal}(f) = [f \le f_c], \qquad
              H_\text{Gauss}(f) = e^{-f^2 / 2 f_c^2}, \qquad H_\text{high} = 1 - H_\text{low}

    with :math:`f` the radial frequency in cycles per pixel. The Gaussian
    low-pass equals a spatial Gaussian of :math:`\sigma = 1 / (2\pi f_c)`
    with the wrap boundary; the ideal one rings (its kernel is a sinc).

    Parameters
    ----------
    image : (H, W) float32 ndarray
        The gray image.
    kind : {"gaussian", "ideal"}
        Shape of the transfer function.
    band : {"low", "high"}
        Keep the low or the high frequencies.
    cutoff : float
        :math:`f_c` in cycles per pixel (Nyquist is 0.5).

    Returns
    -------
    filtered : (H, W) float32 ndarray (a high-pass has negative values)

    References
    ----------
    .. [1] Gonzalez & Woods, *Digital Image Processing*, 4th ed., 2018, section 4.8.
    """
    frequency = frequency_grid(image.shape)
    if kind == "ideal":
        transfer = (frequency <= cutoff).astype(np.float64)
    else:
        transfer = np.exp(-(frequency**2) / (2.0 * cutoff**2))
    if band == "high":
        transfer = 1.0 - transfer
    filtered = np.fft.irfft2(np.fft.rfft2(image.astype(np.float64)) * transfer, image.shape)
    return filtered.astype(np.float32)
