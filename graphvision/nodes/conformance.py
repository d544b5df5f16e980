"""Comparing two implementations of an op by the tolerance the op declares.

:func:`conformance_problems` runs the reference and another backend's implementation
of one op on the same inputs and parameters (both validated by the op's port types
and parameter model, as a run does) and compares what they return by the op's
:class:`~graphvision.nodes.marks.Conformance`. Values are compared field by field:
named tuples and dataclasses (keypoint and match sets, pyramids) by their fields,
arrays and numbers by the metric.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from graphvision.nodes.marks import Conformance
from graphvision.nodes.registry import Registry

__all__ = ["conformance_problems", "flatten"]


def flatten(value: Any, where: str = "out") -> dict[str, Any]:
    """Leaves (arrays and numbers) of a node's result, by dotted path."""
    if isinstance(value, tuple) and hasattr(value, "_fields"):
        items = {f"{where}.{k}": getattr(value, k) for k in value._fields}
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        items = {f"{where}.{f.name}": getattr(value, f.name) for f in dataclasses.fields(value)}
    elif isinstance(value, tuple | list) and not isinstance(value, str):
        items = {f"{where}[{i}]": v for i, v in enumerate(value)}
    else:
        return {where: value}
    leaves: dict[str, Any] = {}
    for path, item in items.items():
        leaves.update(flatten(item, path))
    return leaves


def conformance_problems(
    registry: Registry, op: str, backend: str, inputs: dict[str, Any], params: dict[str, Any]
) -> list[str]:
    """What differs beyond the op's tolerance between the reference and ``backend`` on
    ``inputs`` and ``params`` (empty: they conform). An op without a declared
    tolerance is a problem itself."""
    spec = registry.node(op)
    other = registry.implementation(op, backend)
    if other is None:
        return [f"{op} has no '{backend}' implementation"]
    if spec.conformance is None:
        return [f"{op} declares no conformance tolerance (@node(..., conformance=...))"]
    values, checked = spec.check_call((), {**inputs, **params})
    arguments = dict(zip(spec.inputs, values, strict=True))
    reference = spec.func(**arguments, **checked)
    candidate = other.func(**arguments, **checked)
    return _compare(spec.conformance, reference, candidate, f"{op} ({backend} vs numpy)")


def _compare(rule: Conformance, reference: Any, candidate: Any, label: str) -> list[str]:
    if rule.metric == "sampson":
        error = _sampson_rms(candidate[0], reference[3], reference[4])
        ok = error <= rule.tolerance
        return [] if ok else [f"{label}: Sampson RMS {error:.3g} px > {rule.tolerance}"]
    if rule.metric == "rotation_error":
        worst = max(_pose_angles(reference, candidate), default=0.0)
        ok = worst <= rule.tolerance
        return [] if ok else [f"{label}: pose differs by {worst:.3g}° > {rule.tolerance}°"]
    if rule.metric == "up_to_scale":
        error = _scale_free_distance(_homography(reference), _homography(candidate))
        ok = error <= rule.tolerance
        return [] if ok else [f"{label}: unit-norm distance {error:.3g} > {rule.tolerance}"]
    if rule.metric == "corner_error":
        error = _corner_error(_homography(reference), _homography(candidate), rule.radius)
        ok = error <= rule.tolerance
        return [] if ok else [f"{label}: corner error {error:.3g} px > {rule.tolerance}"]
    ours, theirs = flatten(reference), flatten(candidate)
    if ours.keys() != theirs.keys():
        return [f"{label}: outputs {sorted(theirs)} are not the reference's {sorted(ours)}"]
    problems = []
    for path, expected in ours.items():
        problem = _leaf(rule, np.asarray(expected), np.asarray(theirs[path]))
        if problem:
            problems.append(f"{label}: {path}: {problem}")
    return problems


def _leaf(rule: Conformance, expected: np.ndarray, got: np.ndarray) -> str:
    if expected.dtype.kind in "OUS":  # text (a pyramid's kind): equal
        return "" if np.array_equal(expected, got) else f"{got!r} != {expected!r}"
    if rule.metric == "recall":
        return _recall_problem(rule, expected, got)
    if rule.metric == "disparity":
        return _disparity_problem(rule, expected, got)
    if expected.shape != got.shape:
        return f"shape {got.shape} != {expected.shape}"
    if rule.margin and expected.ndim >= 2 and min(expected.shape[:2]) > 2 * rule.margin:
        m = rule.margin
        expected, got = expected[m:-m, m:-m], got[m:-m, m:-m]
    if expected.dtype.kind in "biu" and expected.ndim:
        share = float(np.mean(expected != got)) if expected.size else 0.0
        return "" if share <= rule.mismatch else f"{share:.3%} differ > {rule.mismatch:.3%}"
    if expected.size == 0:
        return ""
    difference = float(np.max(np.abs(expected.astype(np.float64) - got.astype(np.float64))))
    return "" if difference <= rule.tolerance else f"max |diff| {difference:.3g} > {rule.tolerance}"


def _recall_problem(rule: Conformance, expected: np.ndarray, got: np.ndarray) -> str:
    """Detections as points: a boolean mask's pixels, an ``N×2`` array's rows (positions
    or index pairs), lines ``(ρ, θ, strength)`` as ``(ρ px, θ degrees)`` (θ wrapping at
    180° with ρ → −ρ), circles ``(x, y, r, score)`` as ``(x, y, r)``; other leaves
    (scales, descriptors, magnitudes) are not compared."""
    if expected.dtype == np.bool_ and expected.ndim == 2:
        a, b = np.argwhere(expected).astype(float), np.argwhere(got).astype(float)
    elif expected.ndim == 2 and expected.shape[1] == 2:
        a, b = expected.astype(float), got.astype(float)
    elif expected.ndim == 2 and expected.shape[1] == 3 and got.ndim == 2:
        a, b = _line_points(expected), _line_points(got)
        worst = min(_share_near(a[: len(expected)], b, rule.radius),
                    _share_near(b[: len(got)], a, rule.radius))  # fmt: skip
        return "" if worst >= rule.tolerance else f"recall {worst:.3f} < {rule.tolerance}"
    elif expected.ndim == 2 and expected.shape[1] == 4 and got.ndim == 2:
        a, b = expected[:, :3].astype(float), got[:, :3].astype(float)
    else:
        return ""
    worst = min(_share_near(a, b, rule.radius), _share_near(b, a, rule.radius))
    return "" if worst >= rule.tolerance else f"recall {worst:.3f} < {rule.tolerance}"


def _disparity_problem(rule: Conformance, expected: np.ndarray, got: np.ndarray) -> str:
    """Disparity maps (NaN invalid): of the pixels valid in both, at most a ``tolerance``
    share differ by more than ``radius`` pixels; at most a ``mismatch`` share of the
    pixels valid in either are valid in one alone."""
    if expected.shape != got.shape:
        return f"shape {got.shape} != {expected.shape}"
    ours, theirs = np.isfinite(expected), np.isfinite(got)
    both, either = ours & theirs, ours | theirs
    alone = float(np.mean(both[either] == 0)) if either.any() else 0.0
    if alone > rule.mismatch:
        return f"{alone:.3%} of the valid pixels valid in one map alone > {rule.mismatch:.3%}"
    difference = np.abs(expected[both].astype(np.float64) - got[both].astype(np.float64))
    bad = float(np.mean(difference > rule.radius)) if both.any() else 0.0
    if bad > rule.tolerance:
        return f"{bad:.3%} of the pixels valid in both differ by > {rule.radius} px"
    return ""


def _line_points(lines: np.ndarray) -> np.ndarray:
    """Lines ``(ρ, θ, …)`` as points ``(ρ, θ°)``, then the same lines written with
    ``θ ∓ 180°`` and ``−ρ`` (the first ``N`` rows are the lines themselves)."""
    rho, degrees = lines[:, 0].astype(float), np.degrees(lines[:, 1].astype(float))
    return np.vstack([np.c_[rho, degrees], np.c_[-rho, degrees - 180], np.c_[-rho, degrees + 180]])


def _share_near(a: np.ndarray, b: np.ndarray, radius: float) -> float:
    """The share of the points of ``a`` with a point of ``b`` within ``radius``."""
    if len(a) == 0:
        return 1.0
    if len(b) == 0:
        return 0.0
    from scipy.spatial import cKDTree

    distance, _ = cKDTree(b).query(a, k=1)
    return float(np.mean(distance <= radius + 1e-9))


def _sampson_rms(F: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """RMS Sampson distance, pixels, of the reference's inlier pairs to the other's F."""
    ha, hb = np.c_[a, np.ones(len(a))], np.c_[b, np.ones(len(b))]
    fa, fb = ha @ np.asarray(F).T, hb @ np.asarray(F)
    algebraic = np.einsum("ni,ni->n", hb, fa)
    denominator = fa[:, 0] ** 2 + fa[:, 1] ** 2 + fb[:, 0] ** 2 + fb[:, 1] ** 2
    return float(np.sqrt(np.mean(algebraic**2 / np.maximum(denominator, 1e-300))))


def _pose_angles(reference: Any, candidate: Any) -> list[float]:
    """Degrees between the rotations, and between the centres' directions, of each pair of
    cameras (values with ``R`` and ``C``) among the outputs."""
    angles = []
    for ours, theirs in zip(reference, candidate, strict=True):
        if not (hasattr(ours, "R") and hasattr(ours, "C")):
            continue
        relative = np.asarray(ours.R).T @ np.asarray(theirs.R)
        cosine = np.clip((np.trace(relative) - 1) / 2, -1.0, 1.0)
        angles.append(float(np.degrees(np.arccos(cosine))))
        c1, c2 = np.asarray(ours.C, float), np.asarray(theirs.C, float)
        if np.linalg.norm(c1) > 0 and np.linalg.norm(c2) > 0:
            dot = np.clip(c1 @ c2 / np.linalg.norm(c1) / np.linalg.norm(c2), -1.0, 1.0)
            angles.append(float(np.degrees(np.arccos(dot))))
    return angles


def _homography(value: Any) -> np.ndarray:
    matrix = value[0] if isinstance(value, tuple) else value
    return np.asarray(matrix, dtype=np.float64)


def _scale_free_distance(m1: np.ndarray, m2: np.ndarray) -> float:
    """Frobenius distance between two matrices scaled to unit norm, the sign that
    brings them closest (a matrix defined up to scale and sign: F, E)."""
    u1, u2 = m1 / np.linalg.norm(m1), m2 / np.linalg.norm(m2)
    return float(min(np.linalg.norm(u1 - u2), np.linalg.norm(u1 + u2)))


def _corner_error(h1: np.ndarray, h2: np.ndarray, side: float) -> float:
    corners = np.array([[0, 0, 1], [side, 0, 1], [side, side, 1], [0, side, 1]], dtype=float)
    p1, p2 = corners @ h1.T, corners @ h2.T
    return float(np.mean(np.linalg.norm(p1[:, :2] / p1[:, 2:] - p2[:, :2] / p2[:, 2:], axis=1)))
