"""What the page's viewers receive for a value: a description (JSON) and its bytes.

Each value is described by ``describe_value`` as one *view*, chosen from its port type
(by the engine's types, and by type name for the families' own types, which the engine
does not import):

``image``     an intensity image: PNG, and the float values (``.f32``) for the cursor;
``floatmap``  any other float map (disparity, depth, responses): raw ``float32`` with its
              range; the page draws it through a colour map with a colour bar;
``labels``    a label image: a PNG in distinct colours, the labels (``.f32``) for the cursor;
``mask``      a binary image: PNG;
``keypoints``, ``boxes``, ``lines``, ``circles``  drawn over the image they were found in
              (``over``: the producing node's image input), and listed as a table;
``points3d``  an N×3 point cloud (at most 20 000 points sent), for the 3-D view, with
              ``colours``: the node's ``PointColours`` output, when it has one;
``matches``   with ``pair``: the whole set, its inliers and each side's keypoints and image
              (see :func:`graphvision.views.pairing.match_pair`), drawn over the image pair;
``fundamental`` the 3×3 matrix with ``pair``: each view's points and image (epipolar lines);
``samples``   a classifier's samples: their labels and (small ones) their pixels;
``scalar``, ``table``, ``matrix``, ``text`` and ``summary`` for the rest (a ``png`` too when
              the port type has a preview picture).

Float maps carry their port type's ``units`` (for the colour bar); a mask or label map its
``over`` image (tinted over it); a classifier's table (integer ``label`` and ``predicted``)
its ``confusion`` matrix, the first right and wrong rows and its ``samples``; a trained
network (a value with a per-epoch ``history``) its training ``curves``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph
from graphvision.values.images import (
    BinaryImagePort,
    FloatImagePort,
    ImagePort,
    LabelImagePort,
)
from graphvision.values.ports import ArrayPort, PortType
from graphvision.values.records import BoxesPort, KeypointsPort, MatchesPort
from graphvision.values.scalars import TablePort, _ScalarPort
from graphvision.views import pairing, scripted

__all__ = ["MAX_STEP", "describe_value", "png_of", "raw_of", "rgba_of", "shrunk"]

MAX_POINTS = 20_000
MAX_ROWS = 200
MAX_SAMPLES = 400  # a classifier's samples sent with their pixels (each at most 64×64)
SAMPLE_SIDE = 64
SHOWN_PREDICTIONS = 8  # right and wrong predictions shown, each


def _finite_range(array: np.ndarray) -> tuple[float, float]:
    """The smallest and largest finite values (0 to 1 when there are none). One pass over
    the array itself when all are finite (the usual case): no copy, no mask."""
    if array.size and array.dtype.kind in "biu":
        return float(array.min()), float(array.max())
    if array.size:
        low, high = float(np.min(array)), float(np.max(array))
        if math.isfinite(low) and math.isfinite(high):
            return low, high
    finite = array[np.isfinite(array)]
    if finite.size == 0:
        return 0.0, 1.0
    return float(finite.min()), float(finite.max())


def view_of(kind: type[PortType], value: Any) -> str:
    """The viewer of a value of port type ``kind`` (see the module docstring)."""
    name = kind.type_name()
    if issubclass(kind, LabelImagePort):
        return "labels"
    if issubclass(kind, BinaryImagePort):
        return "mask"
    if issubclass(kind, ImagePort):
        return "image"
    special = {"Lines": "lines", "Circles": "circles", "Points3D": "points3d",
               "Fundamental": "fundamental", "Samples": "samples"}  # fmt: skip
    if name in special:
        return special[name]
    if issubclass(kind, KeypointsPort):
        return "keypoints"
    if issubclass(kind, BoxesPort):
        return "boxes"
    if issubclass(kind, MatchesPort):
        return "matches"
    if issubclass(kind, _ScalarPort):
        return "text" if isinstance(value, str) else "scalar"
    if issubclass(kind, TablePort):
        return "table"
    if isinstance(value, np.ndarray) and value.dtype.kind == "f" and value.ndim == 2:
        if min(value.shape) >= 8 and (issubclass(kind, FloatImagePort) or name != "Array"):
            return "floatmap"
        return "matrix" if value.size <= 64 else "summary"
    return "summary"


def describe_value(
    kind: type[PortType], value: Any, compiled: CompiledGraph, node: str, port: str
) -> dict[str, Any]:
    """The JSON a viewer starts from: view, type, summary, shape, range, overlay data."""
    view = view_of(kind, value)
    found: dict[str, Any] = {
        "view": view,
        "type": kind.type_name(),
        "summary": kind.summary(value),
        "node": node,
        "port": port,
    }
    if isinstance(value, np.ndarray):
        found.update(shape=list(value.shape), dtype=str(value.dtype))
    if view in ("image", "floatmap", "labels", "mask"):
        found["range"] = _finite_range(np.asarray(value))
        found["png"] = view != "floatmap"
    elif view in ("keypoints", "boxes", "lines", "circles", "matches"):
        found.update(_features(view, value))
        found["over"] = _image_input(compiled, node)
    elif view == "points3d":
        points = np.asarray(value, np.float64)
        step = max(1, math.ceil(len(points) / MAX_POINTS))
        found["points"] = np.round(points[::step], 4).tolist()
        found["step"] = step
    elif view == "scalar":
        found["value"] = value.item() if hasattr(value, "item") else value
    elif view == "text":
        found["value"] = str(value)
    elif view == "table":
        found["columns"] = {k: _list(np.asarray(v)[:MAX_ROWS]) for k, v in value.items()}
        found["rows"] = int(len(next(iter(value.values()), [])))
    elif view in ("matrix", "fundamental"):
        found["value"] = _list(value)
    elif view == "samples":
        found.update(_samples(value))
    else:  # a picture when the type draws one (ndarray values of two or more axes)
        drawn = getattr(kind.preview, "__func__", None) is not PortType.preview.__func__  # type: ignore[attr-defined]
        found["png"] = drawn and _preview(kind, value) is not None
    found.update(_links(kind, value, compiled, node, port, view))
    return found


def units_of(kind: type[PortType]) -> str:
    """What a float map's values measure (its port type's ``units``), for its colour bar."""
    units = getattr(kind, "units", "")
    if units:
        return str(units)
    return "weights" if kind.type_name() == "Kernel" else ""


def _links(
    kind: type[PortType], value: Any, compiled: CompiledGraph, node: str, port: str, view: str
) -> dict[str, Any]:
    """What the viewer draws with this value: other values by ``[node, port]``, and what
    it needs of this one that its view alone does not carry."""
    found: dict[str, Any] = {}
    if view == "floatmap":
        found["units"] = units_of(kind)
    elif view in ("mask", "labels"):
        over = pairing.image_behind(compiled, node, "a")
        found["over"] = list(over) if over else None
    elif view == "matches":
        found["pair"] = pairing.match_pair(compiled, node, port)
    elif view == "fundamental":
        found["pair"] = pairing.epipolar_pair(compiled, node)
    elif view == "points3d":
        colours = pairing.cloud_colours(compiled, node)
        found["colours"] = list(colours) if colours else None
    elif view == "table" and _is_classifier(value):
        found.update(_classifier(value))
        samples = pairing.prediction_samples(compiled, node)
        found["samples"] = list(samples) if samples else None
    curves = scripted.curves_of(value)  # the report's curves: one drawing of them
    if curves is not None:
        found["curves"] = curves
    return found


def _is_classifier(table: Any) -> bool:
    return {"label", "predicted"} <= set(table) and all(
        np.issubdtype(np.asarray(table[c]).dtype, np.integer) for c in ("label", "predicted")
    )


def _classifier(table: Any) -> dict[str, Any]:
    """The confusion matrix over every row, and the first right and wrong rows."""
    labels, predicted = np.asarray(table["label"]), np.asarray(table["predicted"])
    classes, counts = pairing.confusion_counts(labels, predicted)
    rows = {
        name: [
            [int(i), labels[i].item(), predicted[i].item()]
            for i in np.flatnonzero(chosen)[:SHOWN_PREDICTIONS]
        ]
        for name, chosen in (("right", labels == predicted), ("wrong", labels != predicted))
    }  # [row, label, predicted]
    return {"confusion": {"classes": classes, "counts": counts.tolist()}, **rows}


def _samples(value: Any) -> dict[str, Any]:
    """Labels of every sample; the pixels of the first MAX_SAMPLES when they are small."""
    images = np.asarray(value.images)
    found: dict[str, Any] = {"labels": np.asarray(value.labels).tolist(), "count": len(images)}
    if images.ndim == 3 and max(images.shape[1:]) <= SAMPLE_SIDE:
        found["side"] = list(images.shape[1:])
        found["pixels"] = np.round(images[:MAX_SAMPLES].astype(np.float64), 3).ravel().tolist()
    return found


def _features(view: str, value: Any) -> dict[str, Any]:
    """Overlay geometry and a table for what a node found (at most MAX_POINTS rows)."""
    if view == "keypoints":
        columns = {
            "x": value.xy[:, 0], "y": value.xy[:, 1], "scale": value.scale,
            "orientation": value.orientation, "response": value.response,
        }  # fmt: skip
    elif view == "boxes":
        box = value.xyxy
        columns = {"x0": box[:, 0], "y0": box[:, 1], "x1": box[:, 2], "y1": box[:, 3],
                   "score": value.score}  # fmt: skip
    elif view == "matches":
        columns = {"a": value.pairs[:, 0], "b": value.pairs[:, 1], "distance": value.distance}
    elif view == "lines":
        columns = {"rho": value[:, 0], "theta": value[:, 1], "votes": value[:, 2]}
    else:
        columns = {"x": value[:, 0], "y": value[:, 1], "radius": value[:, 2], "score": value[:, 3]}
    count = len(next(iter(columns.values())))
    return {
        "count": count,
        "columns": {k: _list(np.asarray(v)[:MAX_POINTS]) for k, v in columns.items()},
    }


def _image_input(compiled: CompiledGraph, node: str) -> list[str] | None:
    """``[node, port]`` of the image the producing node read (what its finds are drawn on)."""
    step = compiled.steps.get(node)
    if step is None:
        return None
    for port, (source, source_port) in step.inputs.items():
        kind = step.spec.inputs[port].type
        if isinstance(kind, type) and issubclass(kind, ImagePort):
            return [source, source_port]
    return None


def _list(array: Any) -> Any:
    array = np.asarray(array)
    if array.dtype.kind == "f":
        return [None if not math.isfinite(v) else round(v, 6) for v in array.ravel().tolist()]
    return array.tolist()


def _preview(kind: type[PortType], value: Any) -> np.ndarray | None:
    try:
        return kind.preview(value)
    except Exception:  # a preview is a nicety: a value without one is described in words
        return None


def png_of(kind: type[PortType], value: Any) -> bytes | None:
    """The PNG of a value's picture at full size, or None when its type has none."""
    from graphvision.values.pictures import png_bytes

    picture = _preview(kind, value)
    if picture is None:
        return None
    return png_bytes(picture, smallest=1, longest=16384)


def raw_of(kind: type[PortType], value: Any) -> tuple[bytes, list[int]] | None:
    """The values of an image or map as little-endian ``float32`` (channels last), with shape."""
    if not isinstance(value, np.ndarray) or not issubclass(kind, ArrayPort) or value.ndim > 3:
        return None
    array = np.ascontiguousarray(value, dtype="<f4")
    return array.tobytes(), list(array.shape)


MAX_STEP = 16


def shrunk(picture: np.ndarray, step: int) -> np.ndarray:
    """``picture`` ``step`` times smaller on each axis: the mean of each ``step × step``
    block (float32; the last rows and columns that fill no whole block are left out)."""
    height, width = picture.shape[0] // step, picture.shape[1] // step
    if step <= 1 or height == 0 or width == 0:
        return picture
    total = np.zeros((height, width, *picture.shape[2:]), np.float32)
    for i in range(step):
        for j in range(step):
            total += picture[i : height * step : step, j : width * step : step]
    total *= np.float32(1.0 / (step * step))
    return total


def rgba_of(kind: type[PortType], value: Any, step: int = 1) -> tuple[bytes, list[int]] | None:
    """The value's picture as ``uint8`` RGBA bytes with its ``[H, W]``: no compression, so
    no encoding time (the studio serves this machine; a PNG costs 10-50x more to make).

    Each channel is ``trunc(clip(255 v + 0.5, 0, 255))`` in float32, NaN as 0: the bytes
    of ``round(255 clip(v, 0, 1))``, made in three passes over the picture in place.
    ``step`` > 1 makes a preview :func:`shrunk` that many times (the page shows it
    instead when the picture is drawn smaller than it is), one channel at a time
    (:func:`_preview_planes`).
    """
    picture = _preview(kind, value)
    if picture is None or picture.ndim not in (2, 3) or min(picture.shape[:2]) == 0:
        return None
    step = min(max(1, step), MAX_STEP)
    if step > 1 and min(picture.shape[0], picture.shape[1]) >= step:
        planes = _preview_planes(picture if picture.ndim == 3 else picture[:, :, None], step)
        _to_levels(planes)
        channels, height, width = planes.shape
        rgba = np.empty((height, width, 4), np.uint8)
        rgba[:, :, 3] = 255
        for k in range(channels):  # a plane at a time: long loops, not one of 3 per pixel
            rgba[:, :, k] = planes[k]
        if channels < 3:  # gray (or gray and alpha): the same value in red, green and blue
            rgba[:, :, 1] = rgba[:, :, 2] = planes[0]
        return rgba.tobytes(), [height, width]
    scaled = _to_levels(np.array(picture, np.float32))
    if scaled.ndim == 2:
        scaled = scaled[:, :, None]
    height, width, channels = scaled.shape
    rgba = np.empty((height, width, 4), np.uint8)
    rgba[:, :, 3] = 255
    rgba[:, :, : min(channels, 4)] = scaled[:, :, :4]
    if channels < 3:  # gray (or gray and alpha): the same value in red, green and blue
        rgba[:, :, 1:3] = scaled[:, :, :1]
    return rgba.tobytes(), [height, width]


def _to_levels(picture: np.ndarray) -> np.ndarray:
    """``trunc``-ready levels in place: ``clip(255 v + 0.5, 0, 255)`` in float32, NaN as 0."""
    np.multiply(picture, np.float32(255.0), out=picture)
    np.add(picture, np.float32(0.5), out=picture)
    np.fmax(picture, 0.0, out=picture)  # fmax and fmin take the number over a NaN: NaN is 0
    np.fmin(picture, 255.0, out=picture)
    return picture


def _preview_planes(picture: np.ndarray, step: int) -> np.ndarray:
    """:func:`shrunk` of an ``H×W×C`` picture as ``C×h×w`` planes (at most 4), the same sums
    in the same order: one channel at a time, each block's pixels added along whole rows
    (half the time of the 3-channel sums for the matches picture, whose inner loops were 3
    elements long)."""
    height, width = picture.shape[0] // step, picture.shape[1] // step
    planes = np.zeros((min(picture.shape[2], 4), height, width), np.float32)
    for k, plane in enumerate(planes):
        for i in range(step):
            for j in range(step):
                plane += picture[i : height * step : step, j : width * step : step, k]
    planes *= np.float32(1.0 / (step * step))
    return planes
