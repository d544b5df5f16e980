"""OpenCV implementations of the ``filters`` family: Gaussian, box, median, correlation."""

from __future__ import annotations

import math

import numpy as np

from graphvision import implements

from .convert import EXTRA, REQUIRES, cv, filtered

__all__ = ["cv_box", "cv_convolve", "cv_correlate", "cv_gaussian", "cv_median"]


def _separable(image: np.ndarray, taps: np.ndarray, boundary: str) -> np.ndarray:
    """Rows then columns with the 1-D ``taps`` (``cv2.sepFilter2D``), float32 throughout."""
    cv2 = cv()
    kernel = taps.astype(np.float32).reshape(-1, 1)
    size = taps.size

    def apply(data: np.ndarray, flag: int) -> np.ndarray:
        return cv2.sepFilter2D(data, cv2.CV_32F, kernel, kernel, borderType=flag)

    return filtered(image.astype(np.float32, copy=False), (size, size), boundary, apply)


@implements("filters.gaussian", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_gaussian(image: np.ndarray, *, sigma: float = 1.0, boundary: str = "mirror") -> np.ndarray:
    """``cv2.getGaussianKernel(2h + 1, σ)`` with ``h = ⌈3σ⌉``, by ``cv2.sepFilter2D``."""
    half = math.ceil(3.0 * sigma)
    taps = cv().getGaussianKernel(2 * half + 1, sigma, cv().CV_64F).ravel()
    out = _separable(image, taps, boundary)
    return np.clip(out, 0.0, 1.0, out=out)


@implements("filters.box", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_box(image: np.ndarray, *, size: int = 3, boundary: str = "mirror") -> np.ndarray:
    """``cv2.boxFilter`` (normalised); anchor at ``size // 2`` as the reference's."""
    cv2 = cv()
    anchor = (size // 2, size // 2)

    def apply(data: np.ndarray, flag: int) -> np.ndarray:
        return cv2.boxFilter(data, cv2.CV_32F, (size, size), anchor=anchor, borderType=flag)

    out = filtered(image.astype(np.float32, copy=False), (size, size), boundary, apply)
    return np.clip(out, 0.0, 1.0, out=out)


@implements("filters.median", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_median(image: np.ndarray, *, size: int = 3, boundary: str = "mirror") -> np.ndarray:
    """``cv2.medianBlur`` on the image padded with the boundary (OpenCV's own border is
    replicate). Sizes 3 and 5 run on float32, exactly; larger ones on 8-bit levels, the
    only depth OpenCV's median takes for them (a difference of at most half a level)."""
    cv2 = cv()
    if size == 1:
        return image.copy()

    def apply(data: np.ndarray, flag: int) -> np.ndarray:
        half = size // 2
        padded = cv2.copyMakeBorder(data, half, half, half, half, flag)
        if size <= 5:
            out = cv2.medianBlur(padded.astype(np.float32), size)
        else:
            levels = np.clip(np.rint(padded * 255.0), 0, 255).astype(np.uint8)
            out = cv2.medianBlur(levels, size).astype(np.float32) / np.float32(255.0)
        return out[half : half + data.shape[0], half : half + data.shape[1]]

    return filtered(image, (size, size), boundary, apply).astype(np.float32, copy=False)


def _correlate(image: np.ndarray, kernel: np.ndarray, boundary: str) -> np.ndarray:
    cv2 = cv()
    kh, kw = kernel.shape
    taps = kernel.astype(np.float32)

    def apply(data: np.ndarray, flag: int) -> np.ndarray:
        return cv2.filter2D(data, cv2.CV_32F, taps, anchor=(kw // 2, kh // 2), borderType=flag)

    return filtered(image.astype(np.float32, copy=False), (kh, kw), boundary, apply)


@implements("filters.correlate", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_correlate(image: np.ndarray, kernel: np.ndarray, *, boundary: str = "mirror") -> np.ndarray:
    """``cv2.filter2D`` (a correlation), anchor at the kernel's ``(h // 2, w // 2)``."""
    return _correlate(image, kernel, boundary)


@implements("filters.convolve", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_convolve(image: np.ndarray, kernel: np.ndarray, *, boundary: str = "mirror") -> np.ndarray:
    """``cv2.filter2D`` with the kernel flipped in both dimensions."""
    return _correlate(image, np.ascontiguousarray(kernel[::-1, ::-1]), boundary)
