"""Which values a viewer draws together, found from the compiled graph alone.

A node's finds are drawn over the image they belong to, and some values only
make sense with others: matches join two keypoint sets, each found in its own
image; a fundamental matrix relates the points of two images; a point cloud
may have a colour per point beside it; a classifier's predictions were made
on samples. Shared by the studio's payloads and ``report.html``; every
reference is ``(node, port)`` of a node output (a graph input is not one: the
studio keeps node outputs only, so a pairing through one is not made).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph
from graphvision.values.images import ImagePort
from graphvision.values.ports import PortType
from graphvision.values.records import KeypointsPort, MatchesPort

__all__ = [
    "Ref",
    "cloud_colours",
    "confusion_counts",
    "epipolar_pair",
    "image_behind",
    "image_input",
    "match_pair",
    "outputs_by_ref",
    "prediction_samples",
]

Ref = tuple[str, str]
"""A node output: ``(node, port)``."""

_SIDES = {"a": ("a", "keypoints_a", "src", "left", "image_a"),
          "b": ("b", "keypoints_b", "dst", "right", "image_b")}  # fmt: skip


def _is(kind: Any, port: type[PortType]) -> bool:
    return isinstance(kind, type) and issubclass(kind, port)


def image_input(compiled: CompiledGraph, node: str) -> Ref | None:
    """The first image input of ``node`` that another node produced, or None."""
    step = compiled.steps.get(node)
    if step is None:
        return None
    for port, (source, source_port) in step.inputs.items():
        if _is(step.spec.inputs[port].type, ImagePort) and source in compiled.steps:
            return source, source_port
    return None


def image_behind(compiled: CompiledGraph, node: str, side: str, depth: int = 6) -> Ref | None:
    """The image the values of ``node`` on ``side`` (``"a"`` or ``"b"``) were found in: the
    node's own image input, else the one behind its input for that side (``a``,
    ``keypoints_a``, ``src``...; its first input when none is named so), up the graph."""
    for _ in range(depth):
        step = compiled.steps.get(node)
        if step is None:
            return None
        found = image_input(compiled, node)
        if found is not None:
            return found
        named = [p for p in _SIDES[side] if p in step.inputs]
        port = named[0] if named else next(iter(step.inputs), None)
        if port is None:
            return None
        node = step.inputs[port][0]
    return None


def _keypoints_of(compiled: CompiledGraph, source: Ref, kind: Any) -> Ref | None:
    """``source`` itself when it is keypoints, else the keypoints its producer found."""
    if _is(kind, KeypointsPort):
        return source
    step = compiled.steps.get(source[0])
    if step is None:
        return None
    port = next((p for p, k in step.outputs.items() if _is(k, KeypointsPort)), None)
    return (source[0], port) if port is not None else None


def match_pair(compiled: CompiledGraph, node: str, port: str) -> dict[str, Any] | None:
    """How to draw matches output ``port`` of ``node`` over their image pair.

    Returns ``{"all": ref, "inliers": ref or None, "a": {"keypoints": ref, "image": ref},
    "b": {...}}``: ``all`` the whole match set and ``inliers`` the subset a robust fit
    kept (a reader's Matches output named ``inliers``, or this very output when it is
    one), so the others are its outliers; None when the keypoints cannot be found.
    """
    step = compiled.steps.get(node)
    if step is None:
        return None
    upstream = [
        (p, s) for p, s in step.inputs.items() if _is(step.spec.inputs[p].type, MatchesPort)
    ]
    if port == "inliers" and upstream:
        whole: Ref = upstream[0][1]
        inliers: Ref | None = (node, port)
    else:
        whole, inliers = (node, port), _inliers_reading(compiled, (node, port))
    sides = [(p, s) for p, s in step.inputs.items() if (p, s) not in upstream][:2]
    if len(sides) != 2:
        return None
    found: dict[str, Any] = {"all": list(whole), "inliers": list(inliers) if inliers else None}
    for side, (input_port, source) in zip(("a", "b"), sides, strict=True):
        keypoints = _keypoints_of(compiled, source, step.spec.inputs[input_port].type)
        if keypoints is None:
            return None
        image = image_input(compiled, keypoints[0])
        found[side] = {"keypoints": list(keypoints), "image": list(image) if image else None}
    return found


def _inliers_reading(compiled: CompiledGraph, matches: Ref) -> Ref | None:
    for name, step in compiled.steps.items():
        if matches in step.inputs.values() and _is(step.outputs.get("inliers"), MatchesPort):
            return name, "inliers"
    return None


def epipolar_pair(compiled: CompiledGraph, node: str) -> dict[str, Any] | None:
    """For a fundamental matrix output of ``node``: its points in each view (the node's
    ``inliers_a``/``inliers_b`` outputs, else the points it read) and their images."""
    step = compiled.steps.get(node)
    if step is None:
        return None
    found: dict[str, Any] = {}
    for side in ("a", "b"):
        points: Ref | None = None
        if f"inliers_{side}" in step.outputs:
            points = (node, f"inliers_{side}")
        elif side in step.inputs and step.inputs[side][0] in compiled.steps:
            points = step.inputs[side]
        image = image_behind(compiled, node, side)
        if points is None or image is None:
            return None
        found[side] = {"points": list(points), "image": list(image)}
    return found


def cloud_colours(compiled: CompiledGraph, node: str) -> Ref | None:
    """The colour of each point of a point cloud ``node`` produced: its output of the
    ``PointColours`` type (N×3 in [0, 1], row for row), or None."""
    step = compiled.steps.get(node)
    if step is None:
        return None
    for port, kind in step.outputs.items():
        if kind.type_name() == "PointColours":
            return node, port
    return None


def prediction_samples(compiled: CompiledGraph, node: str) -> Ref | None:
    """The samples (a ``Samples`` input) a classifier's predictions of ``node`` were made on."""
    step = compiled.steps.get(node)
    if step is None:
        return None
    for port, (source, source_port) in step.inputs.items():
        kind = step.spec.inputs[port].type
        if isinstance(kind, type) and kind.type_name() == "Samples" and source in compiled.steps:
            return source, source_port
    return None


def confusion_counts(labels: np.ndarray, predicted: np.ndarray) -> tuple[list[Any], np.ndarray]:
    """The classes (sorted) and ``counts[i, j]``: samples of true class i predicted as j."""
    classes = np.unique(np.concatenate([labels, predicted]))
    index = {value: i for i, value in enumerate(classes.tolist())}
    counts = np.zeros((len(classes), len(classes)), np.int64)
    for truth, guess in zip(labels.tolist(), predicted.tolist(), strict=True):
        counts[index[truth], index[guess]] += 1
    return classes.tolist(), counts


def outputs_by_ref(
    compiled: CompiledGraph,
    outputs: Mapping[str, Any],
    intermediates: Mapping[str, tuple[type[PortType], Any]] | None = None,
) -> dict[Ref, Any]:
    """Every value a report holds, by ``(node, port)``: the graph outputs and the kept
    intermediates (named ``node`` for a node's only output, else ``node.port``)."""
    found: dict[Ref, Any] = {}
    for name, value in outputs.items():
        if name in compiled.outputs:
            found[tuple(compiled.outputs[name])] = value  # type: ignore[index]
    for where, (_, value) in (intermediates or {}).items():
        node, _, port = where.partition(".")
        step = compiled.steps.get(node)
        if step is not None and not port and len(step.outputs) == 1:
            port = next(iter(step.outputs))
        found[(node, port)] = value
    return found
