"""Values ``report.html`` draws with the studio's own viewers.

The studio's viewer modules (``frontend/src``: viewers.js, pairs.js, charts.js,
colormap.js, composed by panels.js) are bundled with the report's graph layout into
``static/graph.js`` by ``frontend/build.sh``, and the report inlines that bundle (no
network). For each value they draw, the page holds a description in the studio's
format (:mod:`graphvision.studio.payload`: ``view``, ``node``, ``port``, ``shape``,
``over``, ``confusion``, ``curves``...) and what the viewer asks of the run: the
pictures (PNG ``data:`` URLs) and the raw values (``deflate``-compressed little-endian
arrays, base64) of the values it draws with. So the report and the studio draw:

- a mask or a label map tinted over the image it was found in (when the report holds
  that image: a graph output, or an intermediate kept by ``--keep-intermediates``),
  the tint toggled, with an alpha slider;
- a classifier's confusion matrix and its first right and wrong predictions, each
  sample's picture captioned "true → predicted" (when its samples are in the report);
- a trained network's training curves: its loss, and its training and held-out
  accuracy, against the epoch, with labelled axes;
- matches over their image pair (inliers and outliers apart, each toggled) and a
  fundamental matrix's epipolar lines over both images, with zoom and pan (when the
  report holds the images, keypoints or points: with ``--keep-intermediates``);
- a point cloud in a 3-D view turned by dragging (at most ``MAX_POINTS``, evenly
  taken), coloured by depth, or by its points' image colours with a switch between
  the two when the node gives them;
- an image, a float map (disparity, depth, a filter response), a label map or a mask
  with zoom and pan to single pixels and the value under the cursor (an image's float
  value, an RGB image's three); a float map through viridis with its colour bar, units
  and a range box (auto, or a fixed low and high), a label map in distinct colours.
  Their values ride the page as 16-bit codes (:mod:`graphvision.views.page_arrays`:
  exact for an image's ``k / 255`` levels and for multiples of 1/4, 1/16...; else
  within half of 1/65,534 of their range), float32 when one is infinite; a map of
  more than ``MAX_VALUES`` values (pixels × channels: 512² gray, 295² RGB), or whose
  values take more than ``MAX_MAP_BYTES`` of the page (noisy float values compress
  badly), is sent reduced to every ``step``-th pixel on both axes, and the page says so
  (the output's file has them all).

Each is drawn into its box in place of the page's own HTML drawing of the value, which
stays as the page without script: its pictures at most ``FALLBACK_LONGEST`` pixels on a
side, since the values ride the page beside them (a full-size PNG of each, hidden once
the script drew, took a third of a report: 0.8 of stereo's 2.3 MB).
"""

from __future__ import annotations

import base64
import contextlib
import json
import math
from collections.abc import Callable, Mapping
from html import escape
from typing import Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph
from graphvision.values.geometry import Points3DPort
from graphvision.values.images import BinaryImagePort, ImagePort, LabelImagePort
from graphvision.values.ports import PortType
from graphvision.values.records import MatchesPort
from graphvision.values.scalars import TablePort
from graphvision.views import pairing
from graphvision.views.page_arrays import page_array as _raw
from graphvision.views.pairing import Ref
from graphvision.views.viewers import is_float_map, pictures_at_most, units_of

__all__ = [
    "FALLBACK_LONGEST",
    "LONGEST",
    "SCRIPTED_STYLE",
    "SHOWN_PREDICTIONS",
    "PageValues",
    "curves_of",
    "is_classifier",
]

MAX_POINTS = 20_000  # points of a cloud in the 3-D view (as many as the studio sends)
LONGEST = 1600  # a tinted map and its image are drawn at most this many pixels on a side
MAX_VALUES = 1 << 18  # a map's values sent (pixels × channels); more are sent reduced
MAX_MAP_BYTES = 512 << 10  # and the page's characters they take; more are sent reduced
SHOWN_PREDICTIONS = 8  # right and wrong predictions shown, each (as the studio shows)
FALLBACK_LONGEST = 200  # the page's own drawing of a value its script draws, without script

SCRIPTED_STYLE = """
.gv-view[data-drawn]:not([data-keep]) > .gv-fallback { display: none; }
.gv-image { position: relative; width: 100%; min-width: 320px; }
.gv-canvas { width: 100%; display: block; cursor: crosshair; image-rendering: pixelated; }
.gv-status, .gv-caption { font: 12px monospace; color: #4b5563; min-height: 1.2em; }
.gv-tools label { margin-right: 8px; font-size: 12px; }
.gv-alpha { width: 80px; vertical-align: middle; }
.gv-confusion { border-collapse: collapse; font: 12px monospace; margin: 4px 0; }
.gv-confusion caption { text-align: left; white-space: nowrap; }
.gv-confusion td, .gv-confusion th { border: 1px solid #e5e7eb; padding: 2px 6px; }
.gv-samples { display: flex; flex-wrap: wrap; gap: 4px; }
.gv-samples figure { margin: 0; text-align: center; font: 11px monospace; }
.gv-samples canvas { width: 40px; height: 40px; image-rendering: pixelated; border: 3px solid;
                     display: block; }
.gv-samples canvas.gv-right { border-color: #16a34a; }
.gv-samples canvas.gv-wrong { border-color: #dc2626; }
.gv-curves { display: flex; flex-wrap: wrap; gap: 8px; }
.gv-colourbar { font-size: 11px; margin-top: 4px; }
.gv-bar { width: 256px; height: 12px; display: block; }
.gv-ticks { display: flex; justify-content: space-between; width: 256px; font: 10px monospace; }
.gv-rangebox { font-size: 12px; margin: 4px 0; } .gv-range { width: 90px; }
"""


def curves_of(value: Any) -> dict[str, Any] | None:
    """A trained model's curves, one value per epoch: ``{"loss": [...], "accuracy":
    {"training": [...], "held out": [...]}}`` from its ``history`` (the loss),
    ``accuracy`` and ``held_out_accuracy`` vectors; None when it has no history."""
    history = getattr(value, "history", None)
    if not (isinstance(history, np.ndarray) and history.ndim == 1 and history.size):
        return None
    series = {}
    for name, field in (("training", "accuracy"), ("held out", "held_out_accuracy")):
        curve = getattr(value, field, None)
        if isinstance(curve, np.ndarray) and curve.shape == history.shape:
            series[name] = _numbers(curve)
    curves: dict[str, Any] = {"loss": _numbers(history)}
    if series:
        curves["accuracy"] = series
    return curves


def is_classifier(table: Any) -> bool:
    """A table of a classifier's results: integer ``label`` and ``predicted`` columns."""
    return (
        isinstance(table, Mapping)
        and {"label", "predicted"} <= set(table)
        and all(
            np.issubdtype(np.asarray(table[c]).dtype, np.integer) for c in ("label", "predicted")
        )
    )


def _numbers(array: np.ndarray) -> list[float | None]:
    return [round(v, 6) if math.isfinite(v) else None for v in array.astype(float).tolist()]


class PageValues:
    """What the page's script needs to draw the report's values with the studio's viewers.

    :meth:`wrap` gives a value's box (its description kept here) around the page's own
    drawing of it; :meth:`script` the data of every described value, as JSON.
    """

    def __init__(self, compiled: CompiledGraph, found: Mapping[Ref, Any]) -> None:
        self.compiled = compiled
        self.found = found
        self.values: dict[str, dict[str, Any]] = {}
        self.raw: dict[str, dict[str, Any]] = {}
        self.pictures: dict[str, str] = {}

    def wrap(
        self, where: Ref | None, kind: type[PortType], value: Any, fallback: Callable[[], str]
    ) -> str:
        """``fallback()`` (the page's drawing of the value) in a box the script draws the
        value into with the studio's viewer, its pictures then at most ``FALLBACK_LONGEST``
        pixels on a side (hidden once the script draws, the values ride the page beside
        them); ``fallback()`` alone, full size, when no viewer applies."""
        described = None if where is None else self.describe(where, kind, value)
        if described is None:
            return fallback()
        key = f"{where[0]}.{where[1]}"  # type: ignore[index]
        self.values[key] = {**self.values.get(key, {}), **described}
        kept = described.get("keep")  # a kept drawing stays beside the script's: full size
        with contextlib.nullcontext() if kept else pictures_at_most(FALLBACK_LONGEST):
            shown = fallback()
        return (
            f'<div class="gv-view" data-view="{escape(key)}">'
            f'<div class="gv-fallback">{shown}</div></div>'
        )

    def describe(self, where: Ref, kind: type[PortType], value: Any) -> dict[str, Any] | None:
        """The studio's description of ``value`` for the viewers the report draws with
        them (see the module), or None."""
        node, port = where
        found: dict[str, Any] = {"type": kind.type_name(), "summary": kind.summary(value),
                                 "node": node, "port": port}  # fmt: skip
        curves = curves_of(value)
        if curves is not None:
            return {**found, "view": "summary", "curves": curves, "keep": True}
        if issubclass(kind, TablePort) and is_classifier(value):
            return {**found, "view": "table", **self._classifier(node, value)}
        if issubclass(kind, LabelImagePort | BinaryImagePort):
            return self._tinted(found, kind, value) or self._map(found, kind, value)
        if issubclass(kind, Points3DPort):
            return self._cloud(found, value)
        if issubclass(kind, MatchesPort):
            return self._matches(found, value)
        if kind.type_name() == "Fundamental":
            return self._epipolar(found, value)
        if issubclass(kind, ImagePort) or is_float_map(kind, value):
            return self._map(found, kind, value)
        return None

    def _map(
        self, found: dict[str, Any], kind: type[PortType], value: Any
    ) -> dict[str, Any] | None:
        """An image, float map, label map or mask with its values, for the pixel viewer:
        every ``step``-th pixel on both axes when it has more than ``MAX_VALUES`` values
        or they take more than ``MAX_MAP_BYTES`` in the page."""
        values = np.asarray(value)
        gray_or_rgb = values.ndim == 2 or (values.ndim == 3 and values.shape[2] == 3)
        if not gray_or_rgb or values.size == 0 or values.dtype.kind not in "biuf":
            return None
        views = ((LabelImagePort, "labels"), (BinaryImagePort, "mask"), (ImagePort, "image"))
        view = next((name for base, name in views if issubclass(kind, base)), "floatmap")
        if view == "labels" and (values.min() < 0 or values.max() > np.iinfo(np.int32).max):
            return None
        (rows, cols), channels = values.shape[:2], values[0, 0].size
        step = max(1, math.isqrt(values.size // MAX_VALUES))
        compact = view in ("image", "floatmap")
        while -(-rows // step) * -(-cols // step) * channels > MAX_VALUES:
            step += 1
        raw = _raw(values[::step, ::step], levels=view == "image", compact=compact)
        while len(raw["deflate"]) > MAX_MAP_BYTES and min(raw["shape"][:2]) > 1:
            # the bytes go with the pixels sent: the next step that should fit, then check
            over = math.sqrt(len(raw["deflate"]) / MAX_MAP_BYTES)
            step = max(step + 1, math.ceil(step * over))
            raw = _raw(values[::step, ::step], levels=view == "image", compact=compact)
        self.raw[f"{found['node']}.{found['port']}"] = raw
        described = {**found, "view": view, "shape": raw["shape"], "step": step}
        if view == "floatmap":
            described["units"] = units_of(kind)
        return {**described, "full": [rows, cols]}

    def _keep(self, ref: list[str] | tuple[str, str], data: dict[str, Any]) -> None:
        """``data`` of a value a viewer draws with (a box's own description wins)."""
        self.values.setdefault(f"{ref[0]}.{ref[1]}", data)

    def _picture(self, ref: list[str] | tuple[str, str] | None) -> bool:
        """Keep the picture of image ``ref`` at full size (what finds are drawn over);
        False when the report does not hold it."""
        value = self.found.get((ref[0], ref[1])) if ref else None
        if ref is None or not isinstance(value, np.ndarray):
            return False
        key = f"{ref[0]}.{ref[1]}"
        if key not in self.pictures:
            picture = self.compiled.steps[ref[0]].outputs[ref[1]].preview(value)
            if picture is None:
                return False
            self.pictures[key] = _png_uri(picture)
        return True

    def _matches(self, found: dict[str, Any], value: Any) -> dict[str, Any] | None:
        """Matches with their whole set, inliers, keypoints and images, for the pair view."""
        pair = pairing.match_pair(self.compiled, found["node"], found["port"])
        if pair is None or not all(self._picture(pair[s]["image"]) for s in ("a", "b")):
            return None
        sets = {name: self.found.get(tuple(pair[name])) if pair[name] else None
                for name in ("all", "inliers")}  # fmt: skip
        keypoints: list[Any] = [self.found.get(tuple(pair[s]["keypoints"])) for s in ("a", "b")]
        if sets["all"] is None or any(k is None for k in keypoints):
            return None
        for name, matches in sets.items():
            if matches is not None:
                self._keep(pair[name], {"columns": _pairs(matches)})
        for side, points in zip(("a", "b"), keypoints, strict=True):
            xy = np.asarray(points.xy, np.float64)
            self._keep(pair[side]["keypoints"], {"columns": {"x": _numbers(xy[:, 0]),
                                                             "y": _numbers(xy[:, 1])}})  # fmt: skip
        return {**found, "view": "matches", "pair": pair, "columns": _pairs(value)}

    def _epipolar(self, found: dict[str, Any], value: Any) -> dict[str, Any] | None:
        """A fundamental matrix with each view's points and image, for epipolar lines."""
        pair = pairing.epipolar_pair(self.compiled, found["node"])
        if pair is None or not all(self._picture(pair[s]["image"]) for s in ("a", "b")):
            return None
        points: list[Any] = [self.found.get(tuple(pair[s]["points"])) for s in ("a", "b")]
        if any(np.ndim(p) != 2 or np.shape(p)[1] != 2 for p in points):
            return None
        for side, xy in zip(("a", "b"), points, strict=True):
            self.raw[".".join(pair[side]["points"])] = _raw(np.asarray(xy, np.float64))
        return {**found, "view": "fundamental", "pair": pair, "value": _numbers(np.ravel(value))}

    def _cloud(self, found: dict[str, Any], value: Any) -> dict[str, Any] | None:
        """A point cloud (at most ``MAX_POINTS``, evenly taken) with its points' colours
        when the node gives them, for the 3-D view."""
        points = np.asarray(value, np.float64)
        if points.ndim != 2 or points.shape[1] != 3 or not len(points):
            return None
        step = max(1, math.ceil(len(points) / MAX_POINTS))
        key = f"{found['node']}.{found['port']}"
        self.raw[key] = _raw(points[::step])
        ref = pairing.cloud_colours(self.compiled, found["node"])
        colours = self.found.get(ref) if ref else None
        if colours is not None and np.shape(colours) == points.shape:
            taken = np.asarray(colours)[::step]  # an image's colours: its 8-bit levels as bytes
            self.raw[f"{ref[0]}.{ref[1]}"] = _raw(taken, levels=True)  # type: ignore[index]
        else:
            ref = None
        described = {**found, "view": "points3d", "count": len(points), "step": 1}
        return {**described, "colours": list(ref) if ref else None}

    def _tinted(
        self, found: dict[str, Any], kind: type[PortType], value: Any
    ) -> dict[str, Any] | None:
        """A mask or label map with the image it is tinted over, both kept for the script."""
        over = pairing.image_behind(self.compiled, found["node"], "a")
        base = self.found.get(over) if over else None
        if over is None or not isinstance(base, np.ndarray) or base.shape[:2] != value.shape:
            return None
        step = max(1, math.ceil(max(value.shape) / LONGEST))
        kind_over = self.compiled.steps[over[0]].outputs[over[1]]
        picture = kind_over.preview(base[::step, ::step])
        values = np.asarray(value)[::step, ::step]
        if picture is None or values.dtype.kind not in "biu" or values.size == 0:
            return None
        if values.min() < 0 or values.max() > np.iinfo(np.int32).max:
            return None
        key = f"{found['node']}.{found['port']}"
        self.raw[key] = _raw(values)
        self.pictures[f"{over[0]}.{over[1]}"] = _png_uri(picture)
        view = "labels" if issubclass(kind, LabelImagePort) else "mask"
        described = {**found, "view": view, "shape": list(values.shape), "over": list(over)}
        return {**described, "step": step, "full": list(value.shape)}

    def _classifier(self, node: str, table: Mapping[str, Any]) -> dict[str, Any]:
        """The confusion matrix, the first right and wrong rows, and their samples when
        the report holds them (only those samples' pixels are kept: rows renumbered)."""
        labels, predicted = np.asarray(table["label"]), np.asarray(table["predicted"])
        classes, counts = pairing.confusion_counts(labels, predicted)
        chosen = {
            name: np.flatnonzero(rows)[:SHOWN_PREDICTIONS]
            for name, rows in (("right", labels == predicted), ("wrong", labels != predicted))
        }
        rows = {name: [[int(i), labels[i].item(), predicted[i].item()] for i in indices]
                for name, indices in chosen.items()}  # fmt: skip
        described: dict[str, Any] = {
            "confusion": {"classes": classes, "counts": counts.tolist()},
            **rows,
            "samples": None,
        }
        ref = pairing.prediction_samples(self.compiled, node)
        samples = self.found.get(ref) if ref else None
        images = np.asarray(getattr(samples, "images", None))
        shown = np.concatenate([chosen["right"], chosen["wrong"]]).astype(np.int64)
        if ref is None or images.ndim != 3 or len(images) != len(labels) or not shown.size:
            return described
        key = f"{ref[0]}.{ref[1]}"
        self.values[key] = {
            "view": "samples", "node": ref[0], "port": ref[1], "side": list(images.shape[1:]),
            "pixels": _numbers(np.clip(images[shown], 0, 1).ravel().round(3)),
        }  # fmt: skip
        renumbered = iter(range(len(shown)))
        for name in ("right", "wrong"):
            described[name] = [[next(renumbered), a, b] for _, a, b in rows[name]]
        described["samples"] = list(ref)
        return described

    def script(self) -> str:
        """The described values and what they draw with, as the page's JSON; '' if none."""
        if not self.values:
            return ""
        data = {"values": self.values, "raw": self.raw, "pictures": self.pictures}
        # no "<" at all inside the script element: no "</script>" nor "<!--" can end it
        text = json.dumps(data, separators=(",", ":")).replace("<", "\\u003c")
        return f'<script type="application/json" data-values="1">{text}</script>'


def _pairs(matches: Any) -> dict[str, list[int]]:
    pairs = np.asarray(matches.pairs)
    return {"a": pairs[:, 0].tolist(), "b": pairs[:, 1].tolist()}


def _png_uri(picture: np.ndarray) -> str:
    from graphvision.values.pictures import png_bytes

    data = png_bytes(picture, smallest=1, longest=LONGEST)
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")
