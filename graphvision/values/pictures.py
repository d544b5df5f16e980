"""What a value looks like: small pictures for reports and notebooks.

Functions here turn values into ``float32`` pictures in [0, 1] (``H×W`` or
``H×W×3``) and pictures into PNG bytes. Port types use them in their
``preview``; the HTML report and the notebook representations show the
result. Nothing here is a vision algorithm: labels get colours, responses
get stretched to [0, 1], point sets get drawn as dots.
"""

from __future__ import annotations

import io

import numpy as np

__all__ = ["label_colours", "png_bytes", "scatter", "stretch", "thumbnail"]

_GOLDEN = 0.618033988749895


def stretch(values: np.ndarray) -> np.ndarray:
    """Values mapped linearly so that their minimum is 0 and their maximum 1 (0 if constant)."""
    values = np.asarray(values, dtype=np.float32)
    if values.size == 0:
        return values
    low, high = float(values.min()), float(values.max())
    if not np.isfinite(low + high) or high <= low:
        return np.zeros(values.shape, np.float32)
    return (values - low) / (high - low)


def label_colours(labels: np.ndarray) -> np.ndarray:
    """Each label in its own colour, 0 black: hues ``label × golden ratio`` (mod 1), HSV to RGB."""
    hue = (labels.astype(np.float64) * _GOLDEN) % 1.0
    sector = np.floor(hue * 6.0)
    fraction = hue * 6.0 - sector
    value, saturation = 0.95, 0.65
    low = value * (1 - saturation)
    falling = value * (1 - saturation * fraction)
    rising = value * (1 - saturation * (1 - fraction))
    full = np.full_like(hue, value)
    bottom = np.full_like(hue, low)
    table = [
        (full, rising, bottom),
        (falling, full, bottom),
        (bottom, full, rising),
        (bottom, falling, full),
        (rising, bottom, full),
        (full, bottom, falling),
    ]
    rgb = np.zeros((*labels.shape, 3), np.float32)
    for index, channels in enumerate(table):
        chosen = sector == index
        for c in range(3):
            rgb[..., c][chosen] = channels[c][chosen]
    rgb[labels == 0] = 0.0
    return rgb


def scatter(points: np.ndarray, side: int = 256) -> np.ndarray:
    """The points ``(x, y)`` as dots on a white square of ``side`` pixels, x right, y down."""
    canvas = np.ones((side, side), np.float32)
    finite = points[np.isfinite(points).all(axis=1)] if len(points) else points
    if len(finite) == 0:
        return canvas
    low, high = finite.min(axis=0), finite.max(axis=0)
    scale = (side - 8) / max(float((high - low).max()), 1e-12)
    cols, rows = np.round((finite - low) * scale + 4).astype(int).T
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            canvas[np.clip(rows + dy, 0, side - 1), np.clip(cols + dx, 0, side - 1)] = 0.0
    return canvas


def thumbnail(picture: np.ndarray, longest: int = 512) -> np.ndarray:
    """``picture`` shrunk by block averaging until its longer side is at most ``longest``.

    A side shorter than the block keeps its length (a 1×4000 strip becomes 1×500,
    never empty), so every picture of at least one pixel has a thumbnail.
    """
    if picture.ndim < 2 or picture.size == 0:  # nothing to shrink (png_bytes draws it)
        return picture
    step = int(np.ceil(max(picture.shape[:2]) / longest))
    if step <= 1:
        return picture
    across = [min(step, side) for side in picture.shape[:2]]
    rows, cols = (
        side // block * block for side, block in zip(picture.shape[:2], across, strict=True)
    )
    blocks = picture[:rows, :cols].reshape(
        rows // across[0], across[0], cols // across[1], across[1], *picture.shape[2:]
    )
    return blocks.mean(axis=(1, 3)).astype(np.float32)


def png_bytes(picture: np.ndarray, smallest: int = 64, longest: int = 2048) -> bytes:
    """PNG of a [0, 1] picture; a tiny one (a kernel) is enlarged to ``smallest`` pixels.

    Any picture gives a PNG: NaN and infinity are drawn black, a single channel
    (``H×W×1``) gray, two channels as gray (the first), four as RGBA, more as
    their first three; an empty picture is one black pixel. Enlarging stops at
    ``longest`` pixels on the longer side (a 1×500 strip is not made 64×32000).
    """
    from PIL import Image  # Pillow directly: imageio's plugin lookup cost a warm run 50 ms

    picture = _drawable(np.asarray(picture))
    shortest, longer = min(picture.shape[:2]), max(picture.shape[:2])
    factor = min(int(np.ceil(smallest / shortest)), max(1, longest // longer))
    if factor > 1:
        picture = np.repeat(np.repeat(picture, factor, axis=0), factor, axis=1)
    data = _bytes(picture)
    buffer = io.BytesIO()
    # zlib's fastest level: 2-4x faster than Pillow's default (6) on a 512-pixel
    # thumbnail, for files about 10 % larger; a report page is written on every run.
    Image.fromarray(data).save(buffer, format="PNG", compress_level=1)
    return buffer.getvalue()


def _bytes(picture: np.ndarray) -> np.ndarray:
    """``round(clip(picture, 0, 1) × 255)`` as ``uint8``, NaN 0, worked in float64 in place
    (a float32 value times 255 is exact there, so the rounding is the exact one): one
    copy, where ``nan_to_num`` then ``clip`` made four passes and three copies."""
    values = np.array(picture, dtype=np.float64)  # a copy of its own, written in place
    np.clip(values, 0.0, 1.0, out=values)  # +inf to 1, -inf to 0; NaN stays NaN
    nan = np.isnan(values)
    if nan.any():
        values[nan] = 0.0
    values *= 255.0
    np.rint(values, out=values)  # halves to even, as np.round
    return values.astype(np.uint8)


def _drawable(picture: np.ndarray) -> np.ndarray:
    """``picture`` as ``H×W``, ``H×W×3`` or ``H×W×4`` with ``H, W >= 1``."""
    if picture.ndim == 1:
        picture = picture[None, :]
    elif picture.ndim > 3:
        picture = picture.reshape(*picture.shape[:3], -1)[..., 0]
    if picture.ndim == 3:
        channels = picture.shape[2]
        picture = picture[..., :3] if channels > 4 else picture
        picture = picture[..., 0] if channels in (1, 2) else picture
        if picture.ndim == 3 and picture.shape[2] == 0:
            picture = np.zeros(picture.shape[:2], np.float32)
    if picture.size == 0 or picture.ndim < 2:
        return np.zeros((1, 1), np.float32)
    if np.iscomplexobj(picture):
        return np.abs(picture)
    if picture.dtype == np.bool_ or not np.issubdtype(picture.dtype, np.number):
        return picture.astype(np.float32)
    return picture
