"""The compiled core of separable filtering, shared by every family that smooths.

A separable kernel :math:`H(u, v) = h_r(u)\\, h_c(v)` is applied as two 1-D
correlations, rows then columns,

.. math:: G = (F \\star h_c^{\\,\\mathrm{rows}}) \\star h_r^{\\,\\mathrm{cols}},

:math:`O(k)` operations per pixel instead of :math:`O(k^2)`. No padded copy
is made: the boundary rule becomes two index arrays (the source row under
each tap, the source column at each end of a line), and a numba kernel builds
each output row while its input rows are in cache: the column pass into one
padded line, then the row pass along it, one tap (or one symmetric pair of
taps) at a time over whole contiguous rows, a loop the compiler turns into
SIMD code. ``scipy.ndimage.correlate1d`` instead walks each output pixel's
window through a generic line buffer, one axis over the whole image at a
time. Results equal scipy's within
float32 rounding (the accumulation order differs). ``float64`` images are
filtered in ``float64`` (callers that need the precision keep it); any
other dtype in ``float32``.

Boundary names are scipy's: ``reflect`` (``b a | a b c d | d c``), ``mirror``
(``c b | a b c d | c b``), ``nearest``, ``wrap`` / ``grid-wrap`` and
``constant`` (zero).

References
----------
.. [1] R. Szeliski, *Computer Vision: Algorithms and Applications*, 2nd ed.,
   2022, section 3.2.1 (separable filtering).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "correlate_separable",
    "gaussian_derivative",
    "gaussian_taps",
    "smooth_gaussian",
    "smooth_gaussian_halved",
]

_NUMPY_PAD: dict[str, Any] = {
    "reflect": "symmetric",
    "mirror": "reflect",
    "nearest": "edge",
    "wrap": "wrap",
    "grid-wrap": "wrap",
    "constant": "constant",
}


def gaussian_taps(sigma: float, truncate: float = 4.0, order: int = 0) -> np.ndarray:
    r"""Correlation taps of scipy's sampled Gaussian (``order`` 0) or its derivatives (1, 2).

    Radius ``int(truncate·σ + 0.5)``; :math:`g(u) = e^{-u^2/2\sigma^2} / \sum e^{\dots}`,
    for the first derivative :math:`g'(u) = -u\, g(u) / \sigma^2` and for the
    second :math:`g''(u) = (u^2/\sigma^4 - 1/\sigma^2)\, g(u)`, given here as
    correlation taps (reversed), so that correlating with them differentiates.
    """
    radius = int(truncate * float(sigma) + 0.5)
    u = np.arange(-radius, radius + 1, dtype=np.float64)
    taps = np.exp(-0.5 * (u / sigma) ** 2)
    taps /= taps.sum()
    variance = float(sigma) * float(sigma)
    if order == 1:
        return u / variance * taps  # -u g(u) / σ², reversed
    if order == 2:
        return (u * u / variance - 1.0) / variance * taps  # even: reversing changes nothing
    if order != 0:
        raise ValueError(f"order must be 0, 1 or 2, got {order}")
    return taps


def _boundary_index(length: int, half: int, mode: str) -> np.ndarray:
    """Source index of each position of a line padded by ``half`` each side (−1: zero)."""
    positions = np.arange(length, dtype=np.int64)
    if mode == "constant":
        return np.pad(positions, half, mode="constant", constant_values=-1)
    return np.pad(positions, half, mode=_NUMPY_PAD[mode])


def _symmetry(taps: np.ndarray) -> int:
    """1 for symmetric taps, -1 for antisymmetric ones, 0 otherwise (the kernels' ``symmetry``)."""
    if np.array_equal(taps, taps[::-1]):
        return 1
    if np.array_equal(taps, -taps[::-1]):
        return -1
    return 0


def correlate_separable(
    image: np.ndarray, column_taps: np.ndarray, row_taps: np.ndarray, mode: str = "reflect"
) -> np.ndarray:
    """Correlate along axis 0 with ``column_taps``, then along axis 1 with ``row_taps``.

    Parameters
    ----------
    image : (H, W) or (H, W, C) ndarray
        ``float64`` is filtered in ``float64``, anything else in ``float32``.
    column_taps, row_taps : 1-D float ndarray
        Centred at element ``size // 2``; an even-length one is given a zero tap at its
        end, so the compiled passes (which take odd lengths) see the same window.
    mode : str
        scipy's boundary name (see the module docstring).

    Returns
    -------
    out : float32 (float64 for a float64 image) ndarray, the shape of ``image``
    """
    if image.ndim == 3:
        return np.stack(
            [
                correlate_separable(image[..., c], column_taps, row_taps, mode)
                for c in range(image.shape[2])
            ],
            axis=2,
        )
    from .separable_kernels import correlate_both

    dtype = np.float64 if image.dtype == np.float64 else np.float32
    data = np.ascontiguousarray(image, dtype=dtype)
    column = _odd_length(np.asarray(column_taps, dtype=dtype))
    row = _odd_length(np.asarray(row_taps, dtype=dtype))
    out = np.empty_like(data)
    correlate_both(
        data,
        column,
        _symmetry(column),
        _boundary_index(data.shape[0], column.size // 2, mode),
        row,
        _symmetry(row),
        _boundary_index(data.shape[1], row.size // 2, mode),
        out,
    )
    return out


def _odd_length(taps: np.ndarray) -> np.ndarray:
    """``taps`` with a zero appended when its length is even (the centre stays at
    ``size // 2``: taps ``[a, b, c, d]`` cover offsets −2 … 1, as ``[a, b, c, d, 0]``)."""
    return np.append(taps, taps.dtype.type(0)) if taps.size % 2 == 0 else taps


def smooth_gaussian(
    image: np.ndarray, sigma: float, mode: str = "reflect", truncate: float = 4.0
) -> np.ndarray:
    """``scipy.ndimage.gaussian_filter(image, sigma, mode=mode, truncate=truncate)``, compiled."""
    taps = gaussian_taps(sigma, truncate)
    return correlate_separable(image, taps, taps, mode)


def smooth_gaussian_halved(
    image: np.ndarray, sigma: float, mode: str = "reflect", truncate: float = 4.0
) -> np.ndarray:
    """``smooth_gaussian(image, sigma, mode, truncate)[::2, ::2]``, the dropped rows and
    columns never computed (the values kept are the same, computed the same way)."""
    if image.ndim == 3:
        channels = [
            smooth_gaussian_halved(image[..., c], sigma, mode, truncate)
            for c in range(image.shape[2])
        ]
        return np.stack(channels, axis=2)
    from .separable_kernels import correlate_both_halved

    taps = gaussian_taps(sigma, truncate)
    dtype = np.float64 if image.dtype == np.float64 else np.float32
    data = np.ascontiguousarray(image, dtype=dtype)
    taps = taps.astype(dtype)
    symmetry = _symmetry(taps)
    half = taps.size // 2
    out = np.empty(((data.shape[0] + 1) // 2, (data.shape[1] + 1) // 2), dtype=dtype)
    correlate_both_halved(
        data,
        taps,
        symmetry,
        _boundary_index(data.shape[0], half, mode),
        taps,
        symmetry,
        _boundary_index(data.shape[1], half, mode),
        out,
    )
    return out


def gaussian_derivative(
    image: np.ndarray,
    sigma: float,
    order: tuple[int, int],
    mode: str = "reflect",
    truncate: float = 4.0,
) -> np.ndarray:
    """``scipy.ndimage.gaussian_filter(image, sigma, order=order, mode=mode, truncate=truncate)``.

    ``order`` is the derivative order along axis 0 (rows, y) and axis 1
    (columns, x), each 0, 1 or 2; compiled.
    """
    return correlate_separable(
        image,
        gaussian_taps(sigma, truncate, order[0]),
        gaussian_taps(sigma, truncate, order[1]),
        mode,
    )
