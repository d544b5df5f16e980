"""OpenCV implementations of colour conversions, derivatives, Canny, morphology,
thresholds and labelling."""

from __future__ import annotations

import math

import numpy as np

from graphvision import implements

from .convert import EXTRA, REQUIRES, cv, filtered, to_u8

__all__ = [
    "cv_adaptive_threshold",
    "cv_canny",
    "cv_close",
    "cv_derivative",
    "cv_dilate",
    "cv_erode",
    "cv_from_rgb",
    "cv_label",
    "cv_open",
    "cv_otsu",
    "cv_to_gray",
]

_LUMINANCE = np.array([0.299, 0.587, 0.114], dtype=np.float32)


@implements("colour.to_gray", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_to_gray(image: np.ndarray, *, method: str = "mean") -> np.ndarray:
    """``cv2.cvtColor(RGB2GRAY)`` (BT.601 weights) for ``luminance``; ``cv2.transform``
    with equal weights for ``mean``."""
    cv2 = cv()
    if image.ndim == 2:
        return image
    data = np.ascontiguousarray(image, dtype=np.float32)
    if method == "luminance":
        return cv2.cvtColor(data, cv2.COLOR_RGB2GRAY)
    mean = cv2.transform(data, np.full((1, 3), 1.0 / 3.0, dtype=np.float32))
    return mean.reshape(image.shape[:2])


@implements("colour.from_rgb", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_from_rgb(image: np.ndarray, *, space: str = "lab") -> np.ndarray:
    """``cv2.cvtColor`` to HSV (hue rescaled from degrees to a fraction of a turn) and
    L*a*b*; YCbCr in the studio range, which OpenCV lacks (its ``YCrCb`` is full
    range, channels swapped), by ``cv2.transform`` with the BT.601 studio matrix."""
    cv2 = cv()
    data = np.ascontiguousarray(image, dtype=np.float32)
    if space == "hsv":
        hsv = cv2.cvtColor(data, cv2.COLOR_RGB2HSV)
        hsv[..., 0] *= np.float32(1.0 / 360.0)
        hsv[..., 0][hsv[..., 0] >= 1.0] = 0.0
        return hsv
    if space == "lab":
        return cv2.cvtColor(data, cv2.COLOR_RGB2Lab)
    studio = np.array(
        [
            [65.481, 128.553, 24.966, 16.0],
            [-37.797, -74.203, 112.0, 128.0],
            [112.0, -93.786, -18.214, 128.0],
        ],
        dtype=np.float32,
    )
    return cv2.transform(data, studio)


def _taps(kind: str, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """(derivative, smoothing) taps for correlation, as the reference defines each kind
    (Sobel's are ``cv2.getDerivKernels(1, 0, 3)`` scaled by 1/8)."""
    if kind == "sobel":
        d, s = cv().getDerivKernels(1, 0, 3, normalize=True, ktype=cv().CV_64F)
        return d.ravel(), s.ravel()  # normalised Sobel: [-1 0 1]/2 and [1 2 1]/4
    if kind == "forward":
        return np.array([0.0, -1.0, 1.0]), np.array([1.0])
    if kind in ("central", "prewitt"):
        smooth = np.array([1.0]) if kind == "central" else np.full(3, 1.0 / 3.0)
        return np.array([-0.5, 0.0, 0.5]), smooth
    half = math.ceil(3.0 * sigma)
    u = np.arange(-half, half + 1, dtype=np.float64)
    g = np.exp(-(u * u) / (2.0 * sigma * sigma))
    return u * g / np.sum(u * u * g), g / g.sum()


def _derivative(image: np.ndarray, axis: str, kind: str, sigma: float, boundary: str) -> np.ndarray:
    cv2 = cv()
    d, s = _taps(kind, sigma)
    row, column = (d, s) if axis == "x" else (s, d)
    kx, ky = row.astype(np.float32), column.astype(np.float32)
    window = (ky.size, kx.size)

    def apply(data: np.ndarray, flag: int) -> np.ndarray:
        anchor = (kx.size // 2, ky.size // 2)
        return cv2.sepFilter2D(data, cv2.CV_32F, kx, ky, anchor=anchor, borderType=flag)

    return filtered(image.astype(np.float32, copy=False), window, boundary, apply)


@implements("edges.derivative", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_derivative(
    image: np.ndarray,
    *,
    axis: str = "x",
    kind: str = "gaussian",
    sigma: float = 1.0,
    boundary: str = "mirror",
) -> np.ndarray:
    """``cv2.sepFilter2D`` with the kind's taps (Sobel's from ``cv2.getDerivKernels``)."""
    return _derivative(image, axis, kind, sigma, boundary)


@implements("edges.canny", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_canny(
    image: np.ndarray,
    *,
    sigma: float = 1.0,
    low: float = 0.05,
    high: float = 0.1,
    thresholds: str = "absolute",
    boundary: str = "mirror",
) -> tuple[np.ndarray, np.ndarray]:
    """``cv2.Canny(dx, dy, low, high, L2gradient=True)`` on the derivative-of-Gaussian
    gradient scaled to 16-bit integers (OpenCV's Canny takes no float gradient). Its
    non-maximum suppression compares with the neighbours in one of four directions
    (no interpolation), so a few edge pixels move by one."""
    from ..edges import Canny

    cv2 = cv()
    dx = _derivative(image, "x", "gaussian", sigma, boundary)
    dy = _derivative(image, "y", "gaussian", sigma, boundary)
    magnitude = np.hypot(dx, dy).astype(np.float32)
    if thresholds == "quantile":
        low, high = (float(q) for q in np.quantile(magnitude, [low, high]))
    peak = float(max(np.abs(dx).max(), np.abs(dy).max()))
    if peak == 0.0:
        return Canny(np.zeros(image.shape, dtype=bool), magnitude)
    scale = 32000.0 / peak
    ix = np.rint(dx * scale).astype(np.int16)
    iy = np.rint(dy * scale).astype(np.int16)
    edges = cv2.Canny(ix, iy, low * scale, high * scale, L2gradient=True) > 0
    return Canny(edges & (magnitude > 0), magnitude)


def _extreme(image: np.ndarray, footprint: np.ndarray, kind: str) -> np.ndarray:
    """``cv2.erode`` / ``cv2.dilate`` with the reference's border (outside is foreground
    for erosion, background for dilation); dilation by the reflected footprint, as
    Minkowski addition (OpenCV's dilate does not reflect it)."""
    cv2 = cv()
    boolean = image.dtype == np.bool_
    data = image.astype(np.uint8) if boolean else np.ascontiguousarray(image, dtype=np.float32)
    shape = footprint.astype(np.uint8)
    rows, cols = shape.shape
    if kind == "erode":
        fill = 1.0 if boolean else float(data.max(initial=1.0))
        out = cv2.erode(
            data, shape, anchor=(cols // 2, rows // 2),
            borderType=cv2.BORDER_CONSTANT, borderValue=fill,
        )  # fmt: skip
    else:
        flipped = np.ascontiguousarray(shape[::-1, ::-1])
        anchor = (cols - 1 - cols // 2, rows - 1 - rows // 2)
        out = cv2.dilate(
            data, flipped, anchor=anchor, borderType=cv2.BORDER_CONSTANT, borderValue=0.0
        )
    return out.astype(bool) if boolean else out


@implements("morphology.erode", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_erode(image: np.ndarray, footprint: np.ndarray) -> np.ndarray:
    """``cv2.erode``, outside the image counting as foreground."""
    return _extreme(image, footprint, "erode")


@implements("morphology.dilate", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_dilate(image: np.ndarray, footprint: np.ndarray) -> np.ndarray:
    """``cv2.dilate`` by the reflected footprint, outside the image background."""
    return _extreme(image, footprint, "dilate")


@implements("morphology.open", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_open(image: np.ndarray, footprint: np.ndarray) -> np.ndarray:
    """Erosion then dilation, each as above."""
    return _extreme(_extreme(image, footprint, "erode"), footprint, "dilate")


@implements("morphology.close", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_close(image: np.ndarray, footprint: np.ndarray) -> np.ndarray:
    """Dilation then erosion, each as above."""
    return _extreme(_extreme(image, footprint, "dilate"), footprint, "erode")


@implements("threshold.otsu", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_otsu(
    image: np.ndarray, *, bins: int = 256, foreground: str = "bright"
) -> tuple[np.ndarray, float]:
    """``cv2.threshold(THRESH_OTSU)`` on the image stretched to 8-bit levels over its
    range. OpenCV always splits 256 levels (``bins`` is the reference's alone) and
    returns an integer level ``t``; the threshold is the middle of levels ``t`` and
    ``t + 1`` mapped back to the image's range."""
    from ..threshold._global import Thresholded

    cv2 = cv()
    low, high = float(image.min()), float(image.max())
    if low == high:
        raise ValueError(f"image is constant (every pixel is {low:g}): no threshold exists")
    levels = to_u8((image - low) / (high - low))
    level, _ = cv2.threshold(levels, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    threshold = low + (level + 0.5) / 255.0 * (high - low)
    mask = image > threshold if foreground == "bright" else image <= threshold
    return Thresholded(mask, float(threshold))


@implements("threshold.adaptive", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_adaptive_threshold(
    image: np.ndarray,
    *,
    window: int = 11,
    c: float = 0.02,
    method: str = "mean",
    foreground: str = "bright",
) -> np.ndarray:
    """``cv2.adaptiveThreshold`` on the 8-bit image (``ADAPTIVE_THRESH_MEAN_C`` or
    ``GAUSSIAN_C``, ``THRESH_BINARY`` for bright, ``THRESH_BINARY_INV`` for dark) with
    ``C = 255 c``. OpenCV rounds the local mean and ``C`` to whole levels."""
    cv2 = cv()
    kind = cv2.ADAPTIVE_THRESH_MEAN_C if method == "mean" else cv2.ADAPTIVE_THRESH_GAUSSIAN_C
    rule = cv2.THRESH_BINARY if foreground == "bright" else cv2.THRESH_BINARY_INV
    return cv2.adaptiveThreshold(to_u8(image), 255, kind, rule, window, 255.0 * c) > 0


@implements("regions.label", backend="opencv", requires=REQUIRES, extra=EXTRA)
def cv_label(mask: np.ndarray, *, connectivity: int = 8) -> np.ndarray:
    """``cv2.connectedComponents``, renumbered 1..N in the order regions first appear
    in raster order (the reference's numbering; OpenCV's depends on its algorithm)."""
    cv2 = cv()
    count, labels = cv2.connectedComponents(
        mask.astype(np.uint8), connectivity=connectivity, ltype=cv2.CV_32S
    )
    if count <= 1:
        return labels.astype(np.int32)
    flat = labels.ravel()
    where = np.flatnonzero(flat)
    first = np.full(count, flat.size, dtype=np.int64)
    first[flat[where[::-1]]] = where[::-1]  # repeated labels: the last write, the first pixel
    order = np.argsort(first[1:], kind="stable") + 1  # OpenCV's labels, by first appearance
    if np.array_equal(order, np.arange(1, count)):
        return labels
    renumber = np.zeros(count, dtype=np.int32)
    renumber[order] = np.arange(1, count, dtype=np.int32)
    return renumber[labels]
