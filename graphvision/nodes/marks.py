"""What the decorators leave on a function (its marks), the id pattern, and the way to
reach the raw function behind a checked wrapper."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["NODE_ID", "SINGLE_OUTPUT", "NodeMark", "SourceMark", "unchecked"]

NODE_ID = re.compile(r"^[a-z][a-z0-9_]*\.[a-z][a-z0-9_]*$")
SINGLE_OUTPUT = "out"


@dataclass(frozen=True)
class NodeMark:
    id: str
    version: int
    cache: bool
    overrides: bool
    check: Callable[..., None] | None = None


@dataclass(frozen=True)
class SourceMark:
    scheme: str
    key: Callable[[str], str] | None = None


def unchecked(func: Callable) -> Callable:
    """The function a node decorator wrapped (``func`` itself when it is not a node)."""
    while hasattr(func, "__graphvision_node__") and hasattr(func, "__wrapped__"):
        func = func.__wrapped__
    return func
