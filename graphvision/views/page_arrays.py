"""Arrays in ``report.html``'s JSON: what the page's script decodes (``decodeRaw`` in
``frontend/src/report-graph.js``) into the values its viewers draw and read out.

Each is little-endian bytes, deflated, base64, with its ``dtype`` and ``shape``;
``planes`` when its bytes go plane by plane; ``scale`` (with ``offset`` and ``nan``)
when integer codes stand for real values ``offset + code / scale``.
"""

from __future__ import annotations

import base64
import zlib
from typing import Any

import numpy as np

__all__ = ["page_array"]

_RAW_TYPES = (np.uint8, np.uint16, np.int32)


def page_array(values: np.ndarray, levels: bool = False, compact: bool = False) -> dict[str, Any]:
    """An array as little-endian bytes, deflated (``zlib``), base64 (the script inflates
    it with ``DecompressionStream``): an integer map in the smallest of uint8, uint16,
    int32 that holds it; real values in float32, their bytes in ``planes`` (each value's
    first bytes, then the second ones...: a quarter smaller deflated on a disparity map),
    or with ``levels`` (an image), as bytes with ``scale`` 255 when every value is
    exactly ``float32(k) / 255`` (an 8-bit image read from a file). With ``compact``
    (a float map or an image the pixel viewer reads out), real values travel as uint16
    (:func:`_sixteen_bits`): half the bytes of float32 or less."""
    extra: dict[str, Any] = {}
    if values.dtype.kind == "f" and levels:
        bytes_ = np.round(np.clip(values, 0, 1) * 255).astype(np.uint8)
        if np.array_equal(bytes_.astype(np.float32) / np.float32(255), values):
            values, extra = bytes_, {"scale": 255}
    if values.dtype.kind == "f" and compact:
        found = _sixteen_bits(values)
        if found is not None:
            values, extra = found
    if values.dtype.kind == "f":
        dtype: type = np.float32
        extra = {"planes": 4}
    else:
        high = int(values.max()) if values.size else 0
        dtype = next(t for t in _RAW_TYPES if high <= np.iinfo(t).max)
        if dtype is np.uint8:  # codes of one byte: no planes
            extra.pop("planes", None)
    array = np.ascontiguousarray(values, np.dtype(dtype).newbyteorder("<"))
    if "planes" in extra:
        size = np.dtype(dtype).itemsize
        array = np.ascontiguousarray(array.view(np.uint8).reshape(-1, size).T)
    return {
        "dtype": np.dtype(dtype).name,
        "shape": list(values.shape),
        "deflate": base64.b64encode(zlib.compress(array.tobytes(), 1)).decode("ascii"),
        **extra,
    }


_EXACT_SCALES = (1, 4, 16, 256)  # whole numbers, quarters (a disparity), sixteenths...
_NAN = 65535  # the uint16 code of NaN


def _sixteen_bits(values: np.ndarray) -> tuple[np.ndarray, dict[str, Any]] | None:
    """Real values as uint16 codes ``q`` standing for ``offset + q / scale`` (NaN as
    ``nan``, 65535), sent byte plane by byte plane; None (float32 then) when a value is
    infinite or none is finite. Exact when every value is a multiple of ``1 / scale`` for
    a scale of :data:`_EXACT_SCALES` (quarter-pixel disparities, whole millimetres);
    else the finite range ``[low, high]`` in 65,535 steps: each value within
    ``(high - low) / 131070`` of its own, far below the 4 digits the viewer reads out
    but for values many times smaller than the map's range (a float map's colours are
    its 1st–99th percentiles: 8 bits)."""
    finite = np.isfinite(values)
    whole = bool(finite.all())
    if not whole and (np.isinf(values).any() or not finite.any()):
        return None
    shown = values if whole else values[finite]
    low, high = float(shown.min()), float(shown.max())
    top = _NAN - 1
    sample = shown.ravel()[:256]
    for scale in _EXACT_SCALES if low >= 0 else ():
        if high * scale > top:
            break
        if np.array_equal(np.rint(sample * scale), sample * scale):
            scaled = values * np.float32(scale)
            codes = np.rint(scaled)
            if np.array_equal(codes[finite], scaled[finite]):
                return _codes(codes, finite, whole), {"scale": scale, "nan": _NAN, "planes": 2}
    steps = top / (high - low) if high > low else 1.0
    codes = np.rint((values.astype(np.float64) - low) * steps)
    return _codes(codes, finite, whole), {"scale": steps, "offset": low, "nan": _NAN, "planes": 2}


def _codes(codes: np.ndarray, finite: np.ndarray, whole: bool) -> np.ndarray:
    if not whole:
        codes[~finite] = _NAN
    return codes.astype(np.uint16)
