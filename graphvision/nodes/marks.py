"""What the decorators leave on a function (its marks), the id pattern, and the way to
reach the raw function behind a checked wrapper."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["NODE_ID", "SINGLE_OUTPUT", "Conformance", "NodeMark", "SourceMark", "unchecked"]

NODE_ID = re.compile(r"^[a-z][a-z0-9_]*\.[a-z][a-z0-9_]*$")
SINGLE_OUTPUT = "out"


@dataclass(frozen=True)
class NodeMark:
    id: str
    version: int
    cache: bool
    overrides: bool
    check: Callable[..., None] | None = None
    conformance: Conformance | None = None


@dataclass(frozen=True)
class Conformance:
    """How far another backend's implementation of an op may be from the reference's,
    on the conformance suite's inputs (:func:`graphvision.testing.check_conformance`).

    ``metric``:

    * ``max_abs``: every float output (arrays, scalars, pyramid levels) within
      ``tolerance`` of the reference's, ``margin`` border pixels left out; boolean and
      integer arrays differ in at most a ``mismatch`` fraction of pixels;
    * ``corner_error``: the mean distance, in pixels, between the corners of a
      ``radius × radius`` square mapped by the two homographies, at most ``tolerance``;
    * ``sampson``: the RMS Sampson distance of the reference's inlier pairs (its 4th and
      5th outputs) to the other's fundamental matrix (its first), at most ``tolerance``;
    * ``rotation_error``: the rotations of the cameras among the outputs, and the
      directions of their centres, within ``tolerance`` degrees;
    * ``recall``: at least a ``tolerance`` share of the reference's detections (mask
      pixels, keypoint positions, match pairs) have one of the other's within
      ``radius`` pixels, and the other way round;
    * ``up_to_scale``: the first outputs (a matrix defined up to scale and sign, as E),
      scaled to unit Frobenius norm, within ``tolerance`` of each other;
    * ``disparity``: disparity maps (NaN invalid) of which at most a ``tolerance``
      share of the pixels valid in both differ by more than ``radius`` pixels, and at
      most a ``mismatch`` share of the pixels valid in either are valid in one alone.

    ``note`` states the differences of convention that remain (an integer Otsu level,
    a border mode a library lacks), shown by ``graphvision describe``.
    """

    metric: str
    tolerance: float
    mismatch: float = 0.0
    radius: float = 0.0
    margin: int = 0
    note: str = ""

    def describe(self) -> dict[str, object]:
        shown: dict[str, object] = {"metric": self.metric, "tolerance": self.tolerance}
        for name in ("mismatch", "radius", "margin", "note"):
            if getattr(self, name):
                shown[name] = getattr(self, name)
        return shown


@dataclass(frozen=True)
class SourceMark:
    scheme: str
    key: Callable[[str], str] | None = None


def unchecked(func: Callable) -> Callable:
    """The function a node decorator wrapped (``func`` itself when it is not a node)."""
    while hasattr(func, "__graphvision_node__") and hasattr(func, "__wrapped__"):
        func = func.__wrapped__
    return func
