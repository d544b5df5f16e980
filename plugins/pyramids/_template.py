"""Template matching: correlation maps, peaks, and matching over scales by scaling the image."""

from __future__ import annotations

import math
from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import (
    Array,
    ColorImage,
    Conformance,
    Float,
    FloatImage,
    GrayImage,
    Image,
    Points2D,
    node,
)

from ..hough import local_maxima, quadratic_peak_2d, suppress_close
from ..shared.checks import ordered
from ..shared.draw import colour_canvas
from ..shared.params import Count, ScaleFactor

__all__ = [
    "MatchError",
    "MultiscaleMatch",
    "Peaks",
    "SampledTemplate",
    "correlation_map",
    "draw_match",
    "find_peaks",
    "match_error",
    "match_multiscale",
    "match_template",
    "sample_template",
]

Method = Literal["correlation", "zero_mean", "ncc"]


def correlation_map(image: np.ndarray, template: np.ndarray, method: str) -> np.ndarray:
    """Correlation of every valid template placement, float64 ``(H - h + 1, W - w + 1)``.

    The numerator is a circular cross-correlation by real FFTs (``numpy.fft``) of a size
    at least the image's: a valid placement never wraps around, so no padding to
    ``H + h - 1`` is needed. It matches a linear correlation by ``fftconvolve`` to float64
    rounding (tested within 1e-12 of the template's energy times the image's largest
    square).
    """
    from scipy.fft import next_fast_len

    if template.shape[0] > image.shape[0] or template.shape[1] > image.shape[1]:
        raise ValueError(
            f"template {template.shape[0]}×{template.shape[1]} is larger than the image "
            f"{image.shape[0]}×{image.shape[1]}"
        )
    data = image.astype(np.float64)
    kernel = template.astype(np.float64)
    if method != "correlation":
        kernel = kernel - kernel.mean()
    shape = (next_fast_len(data.shape[0], True), next_fast_len(data.shape[1], True))
    spectrum = np.fft.rfft2(data, shape)
    spectrum *= np.fft.rfft2(kernel, shape).conj()
    rows, cols = data.shape[0] - kernel.shape[0] + 1, data.shape[1] - kernel.shape[1] + 1
    response = np.fft.irfft2(spectrum, shape)[:rows, :cols]
    if method != "ncc":
        return np.ascontiguousarray(response)
    from ._template_kernels import normalise_response

    tiny = float(np.finfo(np.float32).eps)
    energy = float(np.sum(kernel * kernel))
    kernel_rows, kernel_columns = kernel.shape
    return normalise_response(data, response, kernel_rows, kernel_columns, energy, tiny)


@node(
    "pyramids.match_template",
    version=1,
    conformance=Conformance(
        "max_abs", 1e-4, note="OpenCV correlates in float32 (by DFT for large templates)"
    ),
)
def match_template(image: GrayImage, template: GrayImage, *, method: Method = "ncc") -> FloatImage:
    r"""Correlation map of a template over every position where it fits inside the image.

    .. math::
        C(x) = \sum_u T(u)\, I(x + u), \quad
        Z(x) = \sum_u (T(u) - \bar T)\, I(x + u), \quad
        N(x) = \frac{\sum_u (T(u) - \bar T)(I(x + u) - \bar I_x)}
                    {\sqrt{\sum_u (T(u) - \bar T)^2 \sum_u (I(x + u) - \bar I_x)^2}}

    Correlation is the dot product of the template with each window, a
    similarity that bright regions inflate; zero-mean correlation removes
    the template's mean; normalised cross-correlation (NCC) also divides by
    both norms, so it lies in [-1, 1] and ignores gain and offset. Element
    ``(r, c)`` is the window whose top-left pixel is ``(r, c)``, as in
    ``skimage.feature.match_template``. Numerators by FFT, window sums by
    integral images; flat windows give 0.

    Parameters
    ----------
    image : (H, W) float32 ndarray
        Where to search.
    template : (h, w) float32 ndarray
        What to search for; no larger than the image.
    method : {"correlation", "zero_mean", "ncc"}
        Which correlation.

    Returns
    -------
    response : (H - h + 1, W - w + 1) float32 ndarray

    References
    ----------
    .. [1] J. P. Lewis, "Fast normalized cross-correlation", Vision
       Interface, 1995.
    """
    return correlation_map(image, template, method).astype(np.float32)


class Peaks(NamedTuple):
    points: Points2D
    scores: Array


@node("pyramids.peaks", version=1)
def find_peaks(
    response: FloatImage,
    *,
    threshold: float = 0.5,
    min_distance: Count = 5,
    max_peaks: Count = 10,
) -> Peaks:
    """Peaks of a response map, strongest first, refined to a fraction of a pixel.

    Local maxima above ``threshold``, at least ``min_distance`` apart,
    refined by a quadratic through the 3×3 around each.

    Parameters
    ----------
    response : FloatImage
        A correlation map (``pyramids.match_template``) or any response.
    threshold : float
        Smallest peak value.
    min_distance : int
        Least distance between two peaks, in pixels.
    max_peaks : int
        Most peaks returned.

    Returns
    -------
    points : (N, 2) float64, (x, y) of each peak in ``response``'s pixels
    scores : (N,) float64, the response at each peak
    """
    data = response.astype(np.float64)
    if data.ndim != 2:
        raise ValueError(f"response must be a 2-D map, got shape {response.shape}")
    peaks = local_maxima(data, 2 * min_distance + 1, -np.inf)
    peaks = peaks[data[peaks[:, 0], peaks[:, 1]] >= threshold]
    scores = data[peaks[:, 0], peaks[:, 1]]
    kept = peaks[suppress_close(peaks.astype(np.float64), scores, min_distance, max_peaks)]
    rows, cols = kept[:, 0], kept[:, 1]
    inner = (rows > 0) & (rows < data.shape[0] - 1) & (cols > 0) & (cols < data.shape[1] - 1)
    offsets = np.zeros((len(kept), 2))
    if inner.any():
        offsets[inner] = quadratic_peak_2d(data, rows[inner], cols[inner])
    points = np.column_stack([cols + offsets[:, 1], rows + offsets[:, 0]]).astype(np.float64)
    return Peaks(points.reshape(-1, 2), data[rows, cols])


class MultiscaleMatch(NamedTuple):
    location: Points2D
    scale: Float
    score: Float


@node("pyramids.match_multiscale", version=1, check=ordered(("min_scale", "max_scale")))
def match_multiscale(
    image: GrayImage,
    template: GrayImage,
    *,
    min_scale: ScaleFactor = 0.5,
    max_scale: ScaleFactor = 2.0,
    steps: Annotated[int, Field(ge=1, le=200)] = 25,
) -> MultiscaleMatch:
    r"""Find a template that appears in the image at an unknown scale, by scaling the image.

    "Instead of scaling the template, we scale the image": for each scale
    :math:`s` of a geometric series over [``min_scale``, ``max_scale``] (the
    template's size in the image over its own size), the image is resized
    by :math:`1/s` (smoothed first when it shrinks, so it does not alias)
    and matched by NCC. The best scale is refined by a parabola through the
    scores of its neighbours (in :math:`\log s`), the position by a quadratic
    through the 3×3 around the peak, and mapped back to the image with the
    factors the image was really resized by, :math:`a_y = H / \operatorname{round}(H/s)`
    and :math:`a_x = W / \operatorname{round}(W/s)`:
    :math:`x = (x' + \tfrac12)\, a_x - \tfrac12` for the template's centre :math:`x'`
    in the resized image (pixel centres at integers). The nominal :math:`s`
    differs from them by up to :math:`s / (2 \operatorname{round}(W/s))`, a
    fraction of a pixel at the far side of the image.

    Parameters
    ----------
    image : (H, W) float32 ndarray
        Where to search.
    template : (h, w) float32 ndarray
        What to search for.
    min_scale, max_scale : float
        Range of the template's scale in the image, 1/8 to 1,024 (the image is
        resized by 1 / s: 1/8 makes it 64 times larger).
    steps : int
        Number of scales tried.

    Returns
    -------
    location : (1, 2) float64, the template's centre in the image
    scale : float
    score : float, the NCC at the best match
    """
    from skimage.transform import rescale

    from ..hough import parabolic_offset

    scales = np.geomspace(min_scale, max_scale, steps)
    h, w = template.shape
    results: list[tuple[float, int, int, np.ndarray]] = []
    shapes: list[tuple[int, ...]] = []  # round(H / s) × round(W / s): the sizes really made
    for s in scales:
        resized = rescale(image, 1.0 / s, order=1, anti_aliasing=s > 1, mode="reflect")
        shapes.append(resized.shape)
        if resized.shape[0] < h or resized.shape[1] < w:
            results.append((-np.inf, 0, 0, resized))
            continue
        response = correlation_map(resized, template, "ncc")
        peak_row, peak_col = np.unravel_index(int(np.argmax(response)), response.shape)
        results.append(
            (float(response[peak_row, peak_col]), int(peak_row), int(peak_col), response)
        )
    best = int(np.argmax([r[0] for r in results]))
    score, row, col, response = results[best]
    if not np.isfinite(score):
        raise ValueError(
            f"template {h}×{w} is larger than the image at every scale up to {max_scale}"
        )
    log_scale = math.log(scales[best])
    if 0 < best < steps - 1 and all(np.isfinite(results[k][0]) for k in (best - 1, best + 1)):
        step = math.log(scales[1] / scales[0])
        offset = parabolic_offset(
            np.array(results[best - 1][0]), np.array(score), np.array(results[best + 1][0])
        )
        log_scale += float(offset) * step
    dy, dx = 0.0, 0.0
    if 0 < row < response.shape[0] - 1 and 0 < col < response.shape[1] - 1:
        dy, dx = quadratic_peak_2d(response, np.array([row]), np.array([col]))[0]
    # the image was resized to round(H / s) × round(W / s): the factors that map it back are
    # those of the sizes, not the nominal s (they differ by up to s / (2 round(H / s)))
    factor_y = image.shape[0] / shapes[best][0]
    factor_x = image.shape[1] / shapes[best][1]
    centre_x = (col + dx + (w - 1) / 2 + 0.5) * factor_x - 0.5
    centre_y = (row + dy + (h - 1) / 2 + 0.5) * factor_y - 0.5
    return MultiscaleMatch(np.array([[centre_x, centre_y]]), math.exp(log_scale), score)


class SampledTemplate(NamedTuple):
    template: GrayImage
    location: Points2D
    scale: Float


@node("pyramids.sample_template", version=1)
def sample_template(
    image: GrayImage,
    *,
    x: Annotated[int, Field(ge=0)] = 0,
    y: Annotated[int, Field(ge=0)] = 0,
    size: Annotated[int, Field(ge=3, le=1024)] = 48,
    factor: Annotated[float, Field(gt=0.05, le=20)] = 0.5,
) -> SampledTemplate:
    """A template with its truth: the ``size``² patch at top-left ``(x, y)``, resized by ``factor``.

    The patch appears in the image at ``1 / factor`` times the template's size.

    Parameters
    ----------
    image : (H, W) float32 ndarray
        The image to cut from.
    x, y : int
        Top-left corner of the patch.
    size : int
        Side of the square patch.
    factor : float
        Resize factor of the template (smoothed first when shrinking).

    Returns
    -------
    template : the resized patch
    location : (1, 2) float64, the patch's centre in the image
    scale : float, 1 / factor
    """
    from skimage.transform import rescale

    if y + size > image.shape[0] or x + size > image.shape[1]:
        raise ValueError(
            f"patch at x={x}, y={y} of size {size} leaves the image "
            f"{image.shape[0]}×{image.shape[1]}"
        )
    patch = image[y : y + size, x : x + size]
    template = rescale(patch, factor, order=1, anti_aliasing=factor < 1, mode="reflect")
    centre = np.array([[x + (size - 1) / 2, y + (size - 1) / 2]])
    return SampledTemplate(np.clip(template, 0, 1).astype(np.float32), centre, 1.0 / factor)


class MatchError(NamedTuple):
    location_error: Float
    scale_error: Float


@node("pyramids.match_error", version=1)
def match_error(
    location: Points2D, scale: Float, true_location: Points2D, true_scale: Float
) -> MatchError:
    """Distance in pixels between found and true locations, and the relative scale error.

    Parameters
    ----------
    location : (1, 2) float64
        The location found.
    scale : float
        The scale found.
    true_location : (1, 2) float64
        The truth.
    true_scale : float
        The true scale.

    Returns
    -------
    location_error : float, pixels
    scale_error : float, ``|scale / true_scale - 1|``
    """
    distance = float(np.linalg.norm(location[0] - true_location[0]))
    return MatchError(distance, abs(scale / true_scale - 1.0))


@node("pyramids.draw_match", version=1)
def draw_match(
    image: Image, location: Points2D, template: GrayImage, scale: Float | None = None
) -> ColorImage:
    """A green box of the template's size (times ``scale``) centred on each location found.

    Parameters
    ----------
    image : Image
        The image searched (gray is drawn in colour).
    location : Points2D
        Centres of the matches (e.g. ``pyramids.match_multiscale``'s location).
    template : GrayImage
        The template, for the box's size.
    scale : float, optional
        The template's scale in the image (1 when not connected).

    Returns
    -------
    drawing : (H, W, 3) float32 ndarray
    """
    canvas = colour_canvas(image)
    factor = 1.0 if scale is None else float(scale)
    half_h = (template.shape[0] * factor - 1) / 2
    half_w = (template.shape[1] * factor - 1) / 2
    rows, cols = canvas.shape[:2]
    for x, y in location:
        top, bottom = round(y - half_h), round(y + half_h)
        left, right = round(x - half_w), round(x + half_w)
        span_x = np.arange(max(left, 0), min(right, cols - 1) + 1)
        span_y = np.arange(max(top, 0), min(bottom, rows - 1) + 1)
        for row in (top, bottom):
            if 0 <= row < rows:
                canvas[row, span_x] = (0.1, 0.95, 0.1)
        for col in (left, right):
            if 0 <= col < cols:
                canvas[span_y, col] = (0.1, 0.95, 0.1)
    return canvas.astype(np.float32)
