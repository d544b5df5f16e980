"""Graph inputs as values: literals, paths, ``sample:NAME`` and the files an earlier run
wrote, validated by their port type and frozen."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from graphvision.errors import (
    InputError,
    PortValueError,
)
from graphvision.nodes.registry import Registry
from graphvision.values.ports import PortType, freeze_all
from graphvision.values.scalars import TextPort, _ScalarPort

__all__ = ["freeze_value", "resolve_input", "value_bytes"]


def resolve_input(name: str, port_type: type[PortType], value: Any, registry: Registry) -> Any:
    """Turn a given value into a validated port value.

    A string for a non-``Text`` port is a reference: ``scheme:rest`` goes to the
    plugin source of that scheme (e.g. ``sample:camera``), a scalar port parses
    it as YAML (``--input sigma=2``), a ``.npz`` path is read by the port type
    as it writes its values (with the ``.json`` beside it, if any: a trained
    network, keypoints or boxes from an earlier run's output folder), anything
    else is a path for the ``file`` source. The loaded value, or an array the
    caller passed, then goes through the port's dtype policy
    (:meth:`PortType.coerce`), so a ``uint8`` array from OpenCV is the same
    image as the PNG it was read from.

    Raises
    ------
    InputError
        Naming the input, the value and what is wrong.
    """
    origin = f"'{value}'" if isinstance(value, str) else f"the {type(value).__name__} given"
    empty = isinstance(value, str) and not value  # Path('') would be this folder
    if empty and not issubclass(port_type, (TextPort, _ScalarPort)):
        raise InputError(f"input '{name}' is empty: give a file, or a source such as sample:NAME")
    if isinstance(value, str) and not issubclass(port_type, TextPort):
        scheme, sep, rest = value.partition(":")
        try:
            if sep and scheme in registry.sources:
                value = registry.sources[scheme].func(rest)
            elif issubclass(port_type, _ScalarPort):
                value = yaml.safe_load(value)
            elif value.lower().endswith(".npz"):
                value = _read_written(port_type, Path(value))
            else:
                value = registry.source("file").func(value)
        except Exception as error:
            told = str(error)
            what = told if str(value) in told else f"cannot load '{value}': {told}"
            raise InputError(f"input '{name}': {what}") from error
    try:
        return freeze_value(port_type, port_type.admit(value, origin))
    except PortValueError as error:
        raise InputError(f"input '{name}': {error}") from None
    except (Exception, RecursionError) as error:  # a port type's check undone by hostile data
        raise InputError(
            f"input '{name}': not a valid {port_type.type_name()} ({type(error).__name__}: "
            f"{str(error)[:200]})"
        ) from None


def _read_written(port_type: type[PortType], archive: Path) -> Any:
    """The value in an ``.npz`` ``port_type`` wrote (with the ``.json`` of its header
    beside it, if any), or an error naming the file and what it lacks."""
    if not archive.is_file():
        raise FileNotFoundError(f"no such file: {archive}")
    header = archive.with_suffix(".json")
    try:
        return port_type.read([archive, header] if header.is_file() else [archive])
    except (KeyError, TypeError, ValueError, OSError) as error:
        raise ValueError(
            f"{archive} is not a {port_type.type_name()} as graphvision writes it "
            f"({type(error).__name__}: {error})"
        ) from None


def value_bytes(port_type: type[PortType], value: Any) -> int:
    """Bytes of a value's arrays (what a run record counts per node; a scalar has none)."""
    if issubclass(port_type, _ScalarPort):
        return 0
    return sum(a.nbytes for a in port_type.encode(value)[0].values())


def freeze_value(port_type: type[PortType], value: Any) -> Any:
    """The value over immutable copies of its arrays (see :func:`~graphvision.values.ports.freeze`).

    A node's inputs then cannot be changed by the node, whatever flags it
    sets: a mutating node fails, naming itself, and nothing else changes.
    The caller's own arrays (graph inputs given in Python) stay as they were.
    """
    if issubclass(port_type, _ScalarPort):
        return value
    arrays, meta = port_type.encode(value)
    return port_type.decode(freeze_all(arrays), meta)
