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
    """How far two implementations of an op may differ on the conformance suite's inputs.

    ``metric`` names the comparison (``max_abs``: largest pixel difference;
    ``mismatch``: fraction of differing pixels; ``corner_error``: mean corner
    distance of two homographies, in pixels; ``recall``: share of the reference's
    detections the other finds within ``radius`` pixels, at least ``tolerance``);
    ``note`` states the differences of convention that remain (an integer Otsu level,
    an accumulator tie, a border mode a library lacks), shown by ``describe``.
    """

    metric: str
    tolerance: float
    note: str = ""
    radius: float = 0.0

    def describe(self) -> dict[str, object]:
        shown: dict[str, object] = {"metric": self.metric, "tolerance": self.tolerance}
        if self.radius:
            shown["radius"] = self.radius
        if self.note:
            shown["note"] = self.note
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
