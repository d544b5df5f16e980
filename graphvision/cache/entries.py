"""What a store holds: a value as its port type's named arrays plus a JSON header, the
one-method store protocol, and the errors and warnings of caching."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from graphvision.errors import GraphvisionError

__all__ = [
    "CacheWarning",
    "Encoded",
    "NotACacheError",
    "Store",
]


class CacheWarning(UserWarning):
    """A cache problem that costs time but loses nothing (entry dropped, store disabled)."""


class NotACacheError(GraphvisionError):
    """A cache directory was asked for in a folder that holds other files."""


# -- stores ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Encoded:
    """A value as its port type's named arrays plus JSON header."""

    type_name: str
    arrays: dict[str, np.ndarray]
    meta: dict[str, Any]

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in self.arrays.values()) + 256


class Store(Protocol):
    """Where encoded results live. One method each; swap in a fake for tests."""

    def get(self, key: str) -> Encoded | None: ...

    def put(self, key: str, entry: Encoded) -> None: ...
