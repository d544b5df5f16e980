"""Values ``report.html`` draws with others of the run (as the studio's viewers do).

- matches over their image pair: the two images side by side, a line per
  match, the robust fit's inliers and its outliers in two colours, each
  toggled by a check box;
- a point cloud coloured by its points' image colours or by depth, a switch
  between the two;
- a fundamental matrix's epipolar lines: each view's points, and their
  lines in the other view.

What goes with what comes from :mod:`graphvision.views.pairing`; a pairing
is drawn when the report holds every value it needs (graph outputs, and the
intermediates when kept). The pictures are inline SVG over inline PNG and
the toggles are check boxes styled by CSS alone: no script, no network.
"""

from __future__ import annotations

import base64
import itertools
from collections.abc import Mapping
from html import escape
from typing import Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph
from graphvision.values.geometry import Points3DPort
from graphvision.values.ports import PortType
from graphvision.values.records import MatchesPort
from graphvision.values.scalars import TablePort
from graphvision.views import pairing
from graphvision.views.pairing import Ref
from graphvision.views.scripted import PageValues, is_classifier
from graphvision.views.viewers import (
    _points3d_html,
    picture_longest,
    shrunk,
    table_parts,
    value_html,
)

__all__ = ["LINKED_STYLE", "linked_html", "pair_svg", "shown_html"]

GAP = 8  # pixels between the two images of a pair
EPIPOLAR_LINES = 30  # epipolar lines drawn from each view at most (evenly spread over its points)
COLOURS = {"inliers": "#22c55e", "outliers": "#ef4444", "matches": "#ff66ff",
           "lines in b": "#facc15", "lines in a": "#fb923c", "points": "#38bdf8"}  # fmt: skip
_ids = itertools.count(1)

LINKED_STYLE = """
.output:has(.pair) { flex-basis: 100%; max-width: none; }
.pair svg { max-height: 80vh; }
.pair svg { width: 100%; height: auto; background: #222; display: block; }
.toggles label { margin-right: 1em; font-size: 0.85em; }
.toggles .swatch { display: inline-block; width: 0.8em; height: 0.8em; margin: 0 0.2em; }
.cloudviews > input { display: none; }
.cloudviews > label { border: 1px solid #bbb; padding: 0.1em 0.5em; cursor: pointer; }
.cloudviews > input:checked + label { background: #dbeafe; font-weight: bold; }
"""


def _png_uri(picture: np.ndarray) -> str:
    from graphvision.values.pictures import png_bytes

    small = shrunk(picture, picture_longest(1024))
    data = base64.b64encode(png_bytes(small, smallest=1)).decode("ascii")
    return f"data:image/png;base64,{data}"


def _size(picture: np.ndarray) -> tuple[int, int]:
    return int(picture.shape[1]), int(picture.shape[0])


def pair_svg(
    image_a: np.ndarray, image_b: np.ndarray, layers: Mapping[str, np.ndarray], title: str
) -> str:
    """Two [0, 1] pictures side by side (b right of a, ``GAP`` apart) with ``layers`` of
    segments (name → K×4 ``x0, y0, x1, y1`` in the pair's pixels; a K×2 array draws
    points), each layer toggled by a check box."""
    (wa, ha), (wb, hb) = _size(image_a), _size(image_b)
    width, height = wa + GAP + wb, max(ha, hb)
    box = f"p{next(_ids)}"
    boxes, groups, css = [], [], []
    for k, (name, items) in enumerate(layers.items()):
        colour = COLOURS.get(name.split(" (")[0], "#ff0")
        boxes.append(
            f'<input type="checkbox" id="{box}-{k}" checked>'
            f'<label for="{box}-{k}"><span class="swatch" style="background:{colour}"></span>'
            f"{escape(name)}</label>"
        )
        css.append(f"#{box}-{k}:not(:checked) ~ svg .layer{k} {{ display: none; }}")
        if items.ndim == 2 and items.shape[1] == 2:
            shapes = "".join(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="3"/>' for x, y in items)
            groups.append(f'<g class="layer{k}" fill="none" stroke="{colour}">{shapes}</g>')
        else:
            shapes = "".join(
                f'<line x1="{a:.1f}" y1="{b:.1f}" x2="{c:.1f}" y2="{d:.1f}"/>'
                for a, b, c, d in items
            )
            groups.append(f'<g class="layer{k}" stroke="{colour}" stroke-width="1.2">{shapes}</g>')
    return (
        f'<div class="pair toggles"><style>{" ".join(css)}</style>{"".join(boxes)}'
        f'<svg viewBox="0 0 {width} {height}" role="img" aria-label="{escape(title)}">'
        f'<image href="{_png_uri(image_a)}" x="0" y="0" width="{wa}" height="{ha}"/>'
        f'<image href="{_png_uri(image_b)}" x="{wa + GAP}" y="0" width="{wb}" height="{hb}"/>'
        f"{''.join(groups)}</svg></div>"
    )


def _match_layers(
    whole: Any, inliers: Any, xy_a: np.ndarray, xy_b: np.ndarray, offset: float
) -> dict[str, np.ndarray]:
    """Segments of each match (b shifted right by ``offset``): inliers and outliers when
    the inlier set is known, else all matches."""
    pairs = np.asarray(whole.pairs)
    segments = np.column_stack([xy_a[pairs[:, 0]], xy_b[pairs[:, 1]]]).astype(np.float64)
    segments[:, 2] += offset
    if inliers is None:
        return {f"matches ({len(segments)})": segments}
    kept = {tuple(p) for p in np.asarray(inliers.pairs).tolist()}
    mask = np.array([tuple(p) in kept for p in pairs.tolist()], bool)
    return {
        f"inliers ({mask.sum()})": segments[mask],
        f"outliers ({(~mask).sum()})": segments[~mask],
    }


def _matches_html(found: Mapping[Ref, Any], pair: dict[str, Any], own: Any) -> str | None:
    def get(ref: list[str] | None) -> Any:
        return None if ref is None else found.get((ref[0], ref[1]))

    whole = get(pair["all"]) if get(pair["all"]) is not None else own
    kp_a, kp_b = get(pair["a"]["keypoints"]), get(pair["b"]["keypoints"])
    image_a, image_b = get(pair["a"]["image"]), get(pair["b"]["image"])
    if any(v is None for v in (whole, kp_a, kp_b, image_a, image_b)):
        return None
    offset = image_a.shape[1] + GAP
    layers = _match_layers(whole, get(pair["inliers"]), kp_a.xy, kp_b.xy, offset)
    where = f"{pair['a']['image'][0]} | {pair['b']['image'][0]}"
    return f'<p class="range">matches over {escape(where)}</p>' + pair_svg(
        image_a, image_b, layers, f"matches over {where}"
    )


def _epipolar_lines(F: np.ndarray, points: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Segments (K×4) of the lines ``F x`` of ``points`` (K×2) inside a ``size`` image."""
    width, height = size
    lines = np.column_stack([points, np.ones(len(points))]) @ F.T
    out = []
    for a, b, c in lines:
        ends = []
        if abs(b) > 1e-12:
            ends += [(0.0, -c / b), (width, -(c + a * width) / b)]
        if abs(a) > 1e-12:
            ends += [(-c / a, 0.0), (-(c + b * height) / a, height)]
        inside = [
            (x, y) for x, y in ends if -1e-9 <= x <= width + 1e-9 and -1e-9 <= y <= height + 1e-9
        ]
        if len(inside) >= 2:
            out.append([*inside[0], *inside[-1]])
    return np.array(out, np.float64).reshape(-1, 4)


def _epipolar_html(found: Mapping[Ref, Any], pair: dict[str, Any], F: np.ndarray) -> str | None:
    values: list[Any] = [
        found.get((pair[s][k][0], pair[s][k][1])) for s in ("a", "b") for k in ("points", "image")
    ]
    if any(v is None for v in values):
        return None
    points_a, image_a, points_b, image_b = (np.asarray(v) for v in values)
    points_a, points_b = (
        p[np.linspace(0, len(p), EPIPOLAR_LINES, endpoint=False).astype(int)]
        if len(p) > EPIPOLAR_LINES
        else p
        for p in (np.asarray(points_a), np.asarray(points_b))
    )
    offset = image_a.shape[1] + GAP
    in_b = _epipolar_lines(F, points_a, _size(image_b))
    in_b[:, [0, 2]] += offset
    in_a = _epipolar_lines(F.T, points_b, _size(image_a))
    dots = np.vstack([points_a, points_b + np.array([offset, 0.0])])
    layers = {f"lines in b ({len(in_b)})": in_b, f"lines in a ({len(in_a)})": in_a,
              f"points ({len(dots)})": dots}  # fmt: skip
    return pair_svg(image_a, image_b, layers, "epipolar lines")


def _cloud_html(value: np.ndarray, colours: np.ndarray, name: str) -> str:
    """The cloud seen from the camera twice, by image colour and by depth, with a switch."""
    box = f"c{next(_ids)}"
    by_image = _points3d_html(value, name, colours=colours)
    by_depth = _points3d_html(value, name)
    return (
        f'<div class="cloudviews toggles"><style>#{box}-i:checked ~ .by-depth, '
        f"#{box}-d:checked ~ .by-image {{ display: none; }}</style>"
        f'<input type="radio" name="{box}" id="{box}-i" checked><label for="{box}-i">'
        f"image colour</label>"
        f'<input type="radio" name="{box}" id="{box}-d"><label for="{box}-d">depth</label>'
        f'<div class="by-image">{by_image}</div><div class="by-depth">{by_depth}</div></div>'
    )


def linked_html(
    compiled: CompiledGraph,
    found: Mapping[Ref, Any],
    where: Ref | None,
    kind: type[PortType],
    value: Any,
    name: str,
) -> str:
    """What the report adds to value ``where`` (``(node, port)``) drawn with others of
    the run: matches over their images, a coloured cloud, epipolar lines; '' if none."""
    if where is None:
        return ""
    node, port = where
    if issubclass(kind, MatchesPort):
        pair = pairing.match_pair(compiled, node, port)
        return (_matches_html(found, pair, value) or "") if pair else ""
    if issubclass(kind, Points3DPort):
        ref = pairing.cloud_colours(compiled, node)
        colours = found.get(ref) if ref else None
        if colours is not None and len(colours) == len(value):
            return _cloud_html(value, np.asarray(colours), name)
        return ""
    if kind.type_name() == "Fundamental":
        pair = pairing.epipolar_pair(compiled, node)
        return (_epipolar_html(found, pair, np.asarray(value)) or "") if pair else ""
    return ""


def shown_html(
    compiled: CompiledGraph,
    found: Mapping[Ref, Any],
    where: Ref | None,
    kind: type[PortType],
    value: Any,
    name: str,
    page: PageValues | None = None,
) -> str:
    """A value by its viewer (:func:`~graphvision.views.viewers.value_html`) with what
    :func:`linked_html` adds; a coloured cloud replaces the cloud coloured by depth alone
    (the switch shows that one too). With ``page``, a value the studio's viewers draw in
    the page (:mod:`graphvision.views.scripted`) is in its box, this drawing its fallback."""

    def drawn() -> str:  # drawn smaller when it is the fallback of the page's script
        extra = linked_html(compiled, found, where, kind, value, name)
        if extra and issubclass(kind, Points3DPort):
            return f"<p>{escape(kind.summary(value))}</p>{extra}"
        return value_html(kind, value, name) + extra

    if page is None:
        return drawn()
    if issubclass(kind, TablePort) and is_classifier(value):
        confusion, rows = table_parts(value)
        extra = linked_html(compiled, found, where, kind, value, name)
        return page.wrap(where, kind, value, lambda: confusion) + rows + extra
    return page.wrap(where, kind, value, drawn)
