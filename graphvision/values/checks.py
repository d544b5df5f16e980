"""A port type's check of a node's fresh array, made once per type: the same conditions as
its :meth:`~graphvision.PortType.validate`, read in one function without its calls.

A run validates every array a node returns. The built-in array ports validate in a
chain of class methods (``GrayImagePort.validate`` calls ``ImagePort``'s, which calls
``FloatImagePort``'s, which calls ``ArrayPort``'s), each reading its class attributes
again; after a node that swept megabytes through the caches, each of those calls costs
the engine several times what it does in a loop. :func:`array_check` makes, once per
port type, one function that decides the common case, a valid array, from constants it
holds: the dtypes and dimensions the type takes, whether it may be empty, and the one
pass over the data its ``validate`` makes (values in [0, 1] for an image, as
:func:`~graphvision.values.dtype_policy.in_unit_range`; finite values for a filter
response; labels >= 0). It answers True only where the type's own ``validate`` returns
the array as it is; False sends the caller to that ``validate``, which raises the
type's own message (or accepts what the check does not decide, such as an image holding
-0.0). Nothing is checked less: each condition of each ``validate`` is in its check. A
port type with a ``validate`` of its own (a plugin's, :class:`RecordPort` types) has no
check: its ``validate`` is called.
"""

from __future__ import annotations

from collections.abc import Callable
from operator import attrgetter
from typing import Any

import numpy as np

from graphvision.values.dtype_policy import in_unit_range
from graphvision.values.images import FloatImagePort, ImagePort, LabelImagePort
from graphvision.values.memory import frozen_copies
from graphvision.values.ports import ArrayPort, PortType
from graphvision.values.scalars import TablePort, is_plain_table_port

__all__ = ["ArrayCheck", "array_check", "frozen_fresh_table", "is_fresh_table_port"]

ArrayCheck = Callable[[np.ndarray], bool]
"""Whether an ``ndarray`` is valid for a port type as it is (False: ask its ``validate``)."""


def _finite(array: np.ndarray) -> bool:
    """``FloatImagePort``'s pass: no NaN nor infinity (each end apart, as it checks)."""
    return bool(np.isfinite(array.min()) and np.isfinite(array.max()))


def _labels(array: np.ndarray) -> bool:
    """``LabelImagePort``'s pass: no label below 0."""
    return bool(array.min() >= 0)


_PASSES: dict[Any, Callable[[np.ndarray], bool] | None] = {
    ArrayPort.validate.__func__: None,  # type: ignore[attr-defined]
    FloatImagePort.validate.__func__: _finite,  # type: ignore[attr-defined]
    ImagePort.validate.__func__: in_unit_range,  # type: ignore[attr-defined]
    LabelImagePort.validate.__func__: _labels,  # type: ignore[attr-defined]
}
"""The ``validate`` functions a check stands for, with the pass over the data each makes
(``FloatImagePort``'s finite pass applies to that type alone: its subclasses' is the range)."""

_CHECKS: dict[type[PortType], ArrayCheck | None] = {}


def array_check(kind: type[PortType]) -> ArrayCheck | None:
    """The check of a fresh array by ``kind`` (see the module docstring), made once per
    type; None when ``kind`` validates in a way of its own, or takes any dtype."""
    try:
        return _CHECKS[kind]
    except KeyError:
        pass
    made = _CHECKS[kind] = _made(kind)
    return made


def _made(kind: type[PortType]) -> ArrayCheck | None:
    validate = getattr(kind.validate, "__func__", None)
    if not issubclass(kind, ArrayPort) or validate not in _PASSES or not kind.dtypes:
        return None
    data = _PASSES[validate]
    if validate is FloatImagePort.validate.__func__ and kind is not FloatImagePort:  # type: ignore[attr-defined]
        data = None  # (FloatImagePort.validate checks finite values of that type only)
    dtypes, ndims = frozenset(kind.dtypes), frozenset(kind.ndims)
    empty = kind is ArrayPort or kind.allow_empty  # (ArrayPort.validate's rule)
    colour = issubclass(kind, FloatImagePort)  # an H×W×C image has 3 channels

    def check(array: np.ndarray) -> bool:
        if array.dtype.type not in dtypes or (ndims and array.ndim not in ndims):
            return False
        if not (empty or array.size) or (colour and array.ndim == 3 and array.shape[2] != 3):
            return False
        return data is None or data(array)

    return check


def is_fresh_table_port(kind: type[PortType]) -> bool:
    """Whether ``kind`` validates and encodes its tables as :class:`TablePort` does (a node's
    new table of it may then be taken by :func:`frozen_fresh_table`)."""
    validate = getattr(kind.validate, "__func__", None)
    return validate is TablePort.validate.__func__ and is_plain_table_port(kind)  # type: ignore[attr-defined]


def frozen_fresh_table(value: Any) -> dict[str, np.ndarray] | None:
    """A node's new table checked as :meth:`TablePort.validate` checks it and frozen as
    :func:`~graphvision.values.ports.freeze_all` freezes it (its columns copied into one
    immutable buffer), in one pass of C calls over its columns, no Python step per column;
    None when it is not a non-empty ``dict`` of text to writable 1-D numeric arrays of one
    length (the caller then validates it, which raises the type's message, and freezes it
    as any value)."""
    if type(value) is not dict or not value:
        return None
    columns = list(value.values())
    if (
        set(map(type, value)) != {str}
        or set(map(type, columns)) != {np.ndarray}
        or set(map(_NDIM, columns)) != {1}
        or len(set(map(len, columns))) != 1
        or any(map(_HASOBJECT, columns))
        or not all(map(_WRITEABLE, columns))
    ):
        return None
    return dict(zip(value, frozen_copies(columns), strict=True))


_NDIM, _HASOBJECT, _WRITEABLE = map(attrgetter, ("ndim", "dtype.hasobject", "flags.writeable"))
