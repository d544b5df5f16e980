"""How each kind of value is shown in a page: one viewer per port type family.

- scalars as numbers, tables as tables (a table with ``label`` and
  ``predicted`` columns, a classifier's results, also as a confusion matrix);
- float maps (disparity, depth, filter responses, kernels) in colour, with a
  colour bar giving the range and the units (the port type's ``units``, when
  it declares them);
- label maps with a distinct colour per label, the background black;
- 3-D points seen from the camera, coloured by depth, with their colour bar;
- anything else through its port type's ``preview`` picture.

Pictures are inline PNG (``data:`` URLs); bars are inline SVG. Nothing is
fetched from the network.
"""

from __future__ import annotations

import base64
import contextlib
from collections.abc import Iterator, Mapping
from contextvars import ContextVar
from html import escape
from typing import Any

import numpy as np

from graphvision.values.geometry import Points3DPort
from graphvision.values.images import FloatImagePort, ImagePort, KernelPort, LabelImagePort
from graphvision.values.ports import PortType
from graphvision.values.scalars import TablePort, _ScalarPort
from graphvision.views.pairing import confusion_counts

__all__ = [
    "colour_scale",
    "float_map_range",
    "is_float_map",
    "picture_html",
    "picture_longest",
    "pictures_at_most",
    "shrunk",
    "table_parts",
    "units_of",
    "value_html",
]

_TABLE_ROWS = 50
# viridis (van der Walt and Smith, matplotlib 2.0) at nine even stops: perceptually
# uniform and readable in gray and by colour-blind readers
_STOPS = ("#440154", "#482878", "#3e4989", "#31688e", "#26828e", "#1f9e89", "#35b779",
          "#6ece58", "#fde725")  # fmt: skip
_ANCHORS = np.array([[int(h[i : i + 2], 16) / 255 for i in (1, 3, 5)] for h in _STOPS])


_CAP: ContextVar[int | None] = ContextVar("picture_cap", default=None)


@contextlib.contextmanager
def pictures_at_most(longest: int) -> Iterator[None]:
    """Pictures drawn meanwhile at most ``longest`` pixels on a side: the drawing of a
    value that the page's script draws over (:mod:`graphvision.views.scripted`), seen
    only without script, need not hold the pixels the script draws from its values."""
    cap = _CAP.get()
    token = _CAP.set(longest if cap is None else min(cap, longest))
    try:
        yield
    finally:
        _CAP.reset(token)


def picture_longest(own: int) -> int:
    """The longest side of a picture that is drawn at ``own`` pixels at most, or less
    within :func:`pictures_at_most`."""
    cap = _CAP.get()
    return own if cap is None else min(cap, own)


def picture_html(picture: np.ndarray, alt: str) -> str:
    """An ``<img>`` holding ``picture`` (a [0, 1] array) as an inline PNG thumbnail."""
    from graphvision.values.pictures import png_bytes

    data = base64.b64encode(png_bytes(shrunk(picture, picture_longest(512)))).decode("ascii")
    return f'<img alt="{escape(alt)}" src="data:image/png;base64,{data}">'


def shrunk(picture: np.ndarray, longest: int) -> np.ndarray:
    """:func:`~graphvision.values.pictures.thumbnail` of ``picture`` (block averages until
    its longer side is at most ``longest``), summed block offset by block offset over
    strided views in float64: the same averages within a float32 rounding, 2-3 times
    faster than the mean over a 5-D reshape (a batch file's report spent 10 ms there)."""
    from graphvision.values.pictures import thumbnail

    if picture.ndim < 2 or picture.size == 0 or max(picture.shape[:2]) <= longest:
        return thumbnail(picture, longest)  # as it is (or drawn as it is by png_bytes)
    step = int(np.ceil(max(picture.shape[:2]) / longest))
    across = [min(step, side) for side in picture.shape[:2]]
    rows, cols = (
        side // block * block for side, block in zip(picture.shape[:2], across, strict=True)
    )
    whole = picture[:rows, :cols]
    total = np.zeros((rows // across[0], cols // across[1], *picture.shape[2:]), np.float64)
    for i in range(across[0]):
        for j in range(across[1]):
            total += whole[i :: across[0], j :: across[1]]
    total /= across[0] * across[1]
    return total.astype(np.float32)


def colour_scale(values: np.ndarray, low: float, high: float) -> np.ndarray:
    """``values`` as viridis colours, ``low`` dark violet to ``high`` yellow; NaN black.

    Worked channel by channel over the whole map, the non-finite pixels set apart only when
    there are any (a fancy-indexed copy of every pixel took most of a float map's report)."""
    values = np.asarray(values, np.float64)
    finite = np.isfinite(values)
    whole = bool(finite.all())
    if not whole:
        values = np.where(finite, values, low)
    t = np.clip((values - low) / max(high - low, 1e-300), 0.0, 1.0) * (len(_STOPS) - 1)
    index = np.minimum(t.astype(np.int64), len(_STOPS) - 2)
    fraction = t - index
    rest = 1 - fraction
    rgb = np.empty((*values.shape, 3), np.float32)
    for c in range(3):
        anchors = _ANCHORS[:, c]
        rgb[..., c] = rest * anchors[index] + fraction * anchors[index + 1]
    if not whole:
        rgb[~finite] = 0.0
    return rgb


def float_map_range(values: np.ndarray) -> tuple[float, float] | None:
    """The range a float map is coloured over: its finite values' 1st to 99th percentile
    (widened to their minimum and maximum when those two are equal); None if none is finite."""
    finite = np.asarray(values, np.float64)[np.isfinite(values)]
    if finite.size == 0:
        return None
    low, high = (float(v) for v in np.percentile(finite, [1, 99]))
    if high <= low:
        low, high = float(finite.min()), float(finite.max())
    return low, high


def _colour_bar(low: float, high: float, units: str) -> str:
    """An SVG bar of the colour scale, with its ends, middle and units written under it."""
    stops = "".join(
        f'<stop offset="{i / (len(_STOPS) - 1):.3f}" stop-color="{c}"/>'
        for i, c in enumerate(_STOPS)
    )
    ticks = "".join(
        f'<text x="{x}" y="30" text-anchor="{anchor}">{value:.4g}</text>'
        for x, anchor, value in (
            (0, "start", low), (130, "middle", (low + high) / 2), (260, "end", high)
        )
    )  # fmt: skip
    return (
        f'<figure class="colourbar"><svg width="260" height="34" viewBox="0 0 260 34" '
        f'font-size="11" role="img" '
        f'aria-label="colour bar {low:.4g} to {high:.4g} {escape(units)}">'
        f'<defs><linearGradient id="viridis">{stops}</linearGradient></defs>'
        f'<rect x="0" y="0" width="260" height="16" fill="url(#viridis)" stroke="#999"/>{ticks}'
        f"</svg><figcaption>{escape(units)}</figcaption></figure>"
    )


def units_of(kind: type[PortType]) -> str:
    """What a float map's values measure, for its colour bar: its port type's ``units``."""
    kernel = issubclass(kind, KernelPort)
    return getattr(kind, "units", "") or ("weights" if kernel else "no unit (a filter response)")


def _float_map_html(kind: type[PortType], value: np.ndarray, name: str) -> str:
    units = units_of(kind)
    span = float_map_range(value)
    invalid = int(np.count_nonzero(~np.isfinite(value)))
    note = f", {invalid} invalid pixels (NaN) drawn black" if invalid else ""
    if span is None:
        return f"<p>no finite value{note}</p>"
    low, high = span
    finite = value[np.isfinite(value)]
    return (
        picture_html(colour_scale(_capped_sample(value), low, high), name)
        + _colour_bar(low, high, units)
        + f'<p class="range">coloured over the 1st–99th percentile [{low:.4g}, {high:.4g}]; '
        f"values {float(finite.min()):.4g} to {float(finite.max()):.4g}{escape(note)}</p>"
    )


def _capped_sample(value: np.ndarray) -> np.ndarray:
    """``value`` itself, or every k-th row and column of it within :func:`pictures_at_most`
    when that cap is below the map's size: the capped drawing (seen only without script)
    is coloured from at least the cap's pixels on a side, not from every pixel (colouring
    a whole 512² map for a 200-pixel picture took 28 ms of a report)."""
    cap = _CAP.get()
    if cap is None or value.ndim < 2 or max(value.shape[:2]) < 2 * cap:
        return value
    step = max(value.shape[:2]) // cap
    return value[::step, ::step]


def _labels_html(value: np.ndarray, name: str) -> str:
    labels = np.unique(value[value > 0])
    return picture_html(_label_picture(value), name) + (
        f'<p class="range">{len(labels)} labels, each its own colour; background (0) black</p>'
    )


def _label_picture(value: np.ndarray) -> np.ndarray:
    """:func:`~graphvision.values.pictures.label_colours` of a label map, the colours worked
    out once per label up to the largest and looked up for each pixel (a report page per
    batch file spent 10 ms colouring every pixel): the same picture, as each pixel's colour
    depends on its label alone."""
    from graphvision.values.pictures import label_colours

    if value.dtype.kind not in "iu" or value.size == 0:
        return label_colours(value)
    low, high = int(value.min()), int(value.max())
    if low < 0 or high >= max(value.size, 1 << 16):  # a table larger than the map gains nothing
        return label_colours(value)
    return label_colours(np.arange(high + 1, dtype=value.dtype))[value]


def _points3d_html(
    value: np.ndarray, name: str, side: int = 384, colours: np.ndarray | None = None
) -> str:
    """The points seen along the camera's axis (x right, y down), each coloured by its
    depth Z (or by ``colours``, N×3 in [0, 1]: its image colour), nearer points drawn
    over farther ones."""
    if len(value) == 0:
        return ""
    low_xy, high_xy = np.percentile(value[:, :2], [0.5, 99.5], axis=0)
    scale = (side - 8) / max(float((high_xy - low_xy).max()), 1e-12)
    cols, rows = np.round((value[:, :2] - low_xy) * scale + 4).astype(np.int64).T
    inside = (rows >= 0) & (rows < side) & (cols >= 0) & (cols < side)
    depth = value[inside, 2]
    span = float_map_range(depth) or (0.0, 1.0)
    order = np.argsort(-depth)  # far first: the nearest is written last
    canvas = np.ones((side, side, 3), np.float32)
    shown = colour_scale(depth, *span) if colours is None else np.asarray(colours)[inside]
    shown = shown[order]
    rows, cols = rows[inside][order], cols[inside][order]
    radius = 1 if len(rows) < 20_000 else 0
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            canvas[np.clip(rows + dy, 0, side - 1), np.clip(cols + dx, 0, side - 1)] = shown
    if colours is not None:
        return picture_html(canvas, name) + (
            '<p class="range">seen from the camera (x right, y down), each point in the '
            "colour of its pixel</p>"
        )
    units = getattr(Points3DPort, "units", "") or "Z, units of the points"
    return (
        picture_html(canvas, name)
        + _colour_bar(*span, f"depth {units}")
        + '<p class="range">seen from the camera (x right, y down), coloured by depth</p>'
    )


def _confusion_html(labels: np.ndarray, predicted: np.ndarray) -> str:
    """The confusion matrix of a classifier's results: rows the true class, columns the
    predicted one, cells shaded by their share of the row; the diagonal is right."""
    classes, counts = confusion_counts(labels, predicted)
    head = "".join(f"<th>{escape(str(c))}</th>" for c in classes)
    rows = []
    for i, truth in enumerate(classes):
        total = max(int(counts[i].sum()), 1)
        cells = "".join(
            f'<td class="{"right" if i == j else "wrong"}" '
            f'style="--share:{counts[i, j] / total:.3f}">{counts[i, j]}</td>'
            for j in range(len(classes))
        )
        rows.append(f"<tr><th>{escape(str(truth))}</th>{cells}</tr>")
    right = int(np.trace(counts))
    return (
        f'<table class="confusion"><caption>confusion matrix: {right} of {len(labels)} right '
        f"({right / max(len(labels), 1):.1%}); rows true, columns predicted</caption>"
        f"<tr><th>true \\ predicted</th>{head}</tr>{''.join(rows)}</table>"
    )


def table_html(table: Mapping[str, np.ndarray]) -> str:
    """A column table as an HTML table (its first rows), with a confusion matrix first
    when it holds a classifier's results (integer ``label`` and ``predicted`` columns)."""
    confusion, rows = table_parts(table)
    return confusion + rows


def table_parts(table: Mapping[str, np.ndarray]) -> tuple[str, str]:
    """A classifier's confusion matrix ('' for another table) and the table's rows (folded
    under the matrix when there is one)."""
    columns = list(table)
    count = len(next(iter(table.values()))) if columns else 0
    confusion = ""
    if {"label", "predicted"} <= set(columns) and all(
        np.issubdtype(np.asarray(table[c]).dtype, np.integer) for c in ("label", "predicted")
    ):
        confusion = _confusion_html(np.asarray(table["label"]), np.asarray(table["predicted"]))
    head = "".join(f"<th>{escape(c)}</th>" for c in columns)
    rows = []
    for i in range(min(count, _TABLE_ROWS)):
        cells = []
        for column in columns:
            item = table[column][i]
            text = f"{item:.4g}" if isinstance(item, float | np.floating) else str(item)
            cells.append(f"<td>{escape(text)}</td>")
        rows.append(f"<tr>{''.join(cells)}</tr>")
    more = f"<p>{count - _TABLE_ROWS} more rows in the CSV</p>" if count > _TABLE_ROWS else ""
    shown = f"<table><tr>{head}</tr>{''.join(rows)}</table>{more}"
    if confusion:  # the rows behind the matrix, on demand
        return confusion, f"<details><summary>the {count} rows</summary>{shown}</details>"
    return "", shown


def is_float_map(kind: type[PortType], value: Any) -> bool:
    """A single-channel map of real values with no fixed range: coloured with a colour bar."""
    if not (isinstance(value, np.ndarray) and value.ndim == 2 and value.size):
        return False
    if not np.issubdtype(value.dtype, np.floating):
        return False
    declared = issubclass(kind, FloatImagePort | KernelPort) or hasattr(kind, "units")
    return declared and not issubclass(kind, ImagePort)


def value_html(kind: type[PortType], value: Any, name: str) -> str:
    """How a value of port type ``kind`` is shown: a picture, a table, a number or its summary."""
    if issubclass(kind, _ScalarPort):
        shown = f"{value:.6g}" if isinstance(value, float) else str(value)
        return f'<div class="value">{escape(shown)}</div>'
    if issubclass(kind, TablePort):
        return table_html(value)
    parts = [f"<p>{escape(kind.summary(value))}</p>"]
    if is_float_map(kind, value):
        return parts[0] + _float_map_html(kind, value, name)
    if issubclass(kind, LabelImagePort):
        return parts[0] + _labels_html(value, name)
    if issubclass(kind, Points3DPort):
        return parts[0] + _points3d_html(value, name)
    picture = kind.preview(value)
    if picture is not None:
        parts.append(picture_html(picture, name))
    elif isinstance(value, np.ndarray) and value.size <= 16:  # a homography, a camera matrix
        parts.append(f"<pre>{escape(np.array2string(value, precision=6))}</pre>")
    return "".join(parts)
